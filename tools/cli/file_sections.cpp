// A level file's section table as stored: contract in file_sections.h.
#include "file_sections.h"

#include <algorithm>

#include "tetraprobe/common/error.h"
#include "tetraprobe/runtime/file_io.h"

namespace tetraprobe::cli {

std::vector<FileSection> fileSections(const std::string& path) {
  std::vector<char> b;
  std::string error;
  if (!readFile(path, b, &error)) throw InputError(error);
  const auto u = [&b](size_t at, int n) {
    uint64_t v = 0;
    for (int i = 0; i < n; ++i) v |= uint64_t(uint8_t(b[at + size_t(i)])) << (8 * i);
    return v;
  };
  std::vector<FileSection> out;
  if (b.size() < 80) return out;
  const uint64_t count = u(72, 4);
  for (uint64_t i = 0; i < count && 80 + 24 * (i + 1) <= b.size(); ++i) {
    const size_t e = 80 + 24 * size_t(i);
    out.push_back({std::string(b.data() + e, 4), u(e + 16, 8)});
  }
  return out;
}

uint64_t sectionBytes(const std::vector<FileSection>& sections, const std::vector<std::string>& tags) {
  for (const FileSection& s : sections)
    if (std::find(tags.begin(), tags.end(), s.tag) != tags.end()) return s.bytes;
  return 0;
}

}  // namespace tetraprobe::cli
