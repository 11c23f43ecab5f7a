// Whole-file reads and atomic writes. Permissive: standard library only.
#pragma once

#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

namespace tetraprobe {

// Writes `bytes` to `path` atomically: to a temporary file in the same directory, flushed, then renamed over
// `path`. On failure returns false, sets `error` to one line naming the problem, and leaves no temporary
// file and no change at `path`.
bool writeFileAtomic(const std::string& path, std::string_view bytes, std::string* error);

// The default cap on readFile: 4 GiB (a level of a million probes is about 0.4 GiB).
inline constexpr uint64_t kDefaultMaxReadBytes = uint64_t(4) << 30;

// Reads the whole file into `bytes`. Never throws. On failure returns false and sets `error` to one line
// naming the file and the problem: it cannot be opened, is not a regular file, is larger than `maxBytes`
// (checked before anything is allocated: "N bytes, more than the limit of M"), memory for it cannot be
// allocated, or the read fails; `tooLarge` (optional) is set to whether the failure was one of size (over
// `maxBytes` or out of memory). Allocates the file's size once.
bool readFile(const std::string& path, std::vector<char>& bytes, std::string* error,
              uint64_t maxBytes = kDefaultMaxReadBytes, bool* tooLarge = nullptr);

}  // namespace tetraprobe
