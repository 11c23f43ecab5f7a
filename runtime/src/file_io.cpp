// Atomic whole-file writes (temporary file + fsync + rename) and whole-file reads.
#include "tetraprobe/runtime/file_io.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <exception>
#include <string>

namespace tetraprobe {

bool writeFileAtomic(const std::string& path, std::string_view bytes, std::string* error) {
  static std::atomic<unsigned> counter{0};
  const std::string tmp = path + ".tmp." + std::to_string(::getpid()) + "." + std::to_string(counter++);
  auto fail = [&](const char* what) {
    if (error) *error = path + ": " + what + ": " + std::strerror(errno);
    ::unlink(tmp.c_str());
    return false;
  };
  const int fd = ::open(tmp.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (fd < 0) {
    if (error) *error = path + ": cannot create: " + std::strerror(errno);
    return false;
  }
  const char* p = bytes.data();
  size_t left = bytes.size();
  while (left > 0) {
    const ssize_t n = ::write(fd, p, left);
    if (n < 0) {
      if (errno == EINTR) continue;
      ::close(fd);
      return fail("write failed");
    }
    p += n;
    left -= size_t(n);
  }
  if (::fsync(fd) != 0) {
    ::close(fd);
    return fail("fsync failed");
  }
  if (::close(fd) != 0) return fail("close failed");
  if (::rename(tmp.c_str(), path.c_str()) != 0) return fail("rename failed");
  return true;
}

bool readFile(const std::string& path, std::vector<char>& bytes, std::string* error, uint64_t maxBytes,
              bool* tooLarge) {
  if (tooLarge) *tooLarge = false;
  const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0) {
    if (error) *error = path + ": cannot open: " + std::strerror(errno);
    return false;
  }
  auto fail = [&](const std::string& what) {
    if (error) *error = path + ": " + what;
    ::close(fd);
    return false;
  };
  struct stat st {};
  if (::fstat(fd, &st) != 0) return fail(std::string("cannot stat: ") + std::strerror(errno));
  // Directories, FIFOs and devices have no size to trust (/dev/zero would never end).
  if (!S_ISREG(st.st_mode)) return fail("cannot read (not a regular file)");
  const auto size = uint64_t(st.st_size);
  if (size > maxBytes) {
    if (tooLarge) *tooLarge = true;
    return fail(std::to_string(size) + " bytes, more than the limit of " + std::to_string(maxBytes));
  }
  try {
    bytes.assign(size_t(size), 0);
  } catch (const std::exception&) {  // bad_alloc or length_error: a size under the cap may still not fit
    if (tooLarge) *tooLarge = true;
    return fail("cannot allocate " + std::to_string(size) + " bytes to read it");
  }
  size_t done = 0;
  while (done < bytes.size()) {
    const ssize_t n = ::read(fd, bytes.data() + done, bytes.size() - done);
    if (n < 0 && errno == EINTR) continue;
    if (n < 0) return fail(std::string("read failed: ") + std::strerror(errno));
    if (n == 0) return fail("read failed: the file shrank while it was read");
    done += size_t(n);
  }
  ::close(fd);
  return true;
}

}  // namespace tetraprobe
