// Whole-file reads and atomic writes. Permissive: standard library only.
#pragma once

#include <string>
#include <string_view>
#include <vector>

namespace tetraprobe {

// Writes `bytes` to `path` atomically: to a temporary file in the same directory, flushed, then renamed over
// `path`. On failure returns false, sets `error` to one line naming the problem, and leaves no temporary
// file and no change at `path`.
bool writeFileAtomic(const std::string& path, std::string_view bytes, std::string* error);

// Reads the whole file. On failure returns false and sets `error`.
bool readFile(const std::string& path, std::vector<char>& bytes, std::string* error);

}  // namespace tetraprobe
