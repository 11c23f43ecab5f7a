// A level file's section table as stored (tags and byte sizes), for the bake summary and `inspect`.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace tetraprobe::cli {

struct FileSection {
  std::string tag;  // four ASCII characters
  uint64_t bytes;
};

// The sections of the level file at `path`, in file order, read by the runtime's header and table parser
// (readLevelLayout, level_file.h: only those bytes are read). Throws InputError with its one-line message
// when the file cannot be read or its header or table is refused.
std::vector<FileSection> fileSections(const std::string& path);

// The bytes of the first section whose tag is one of `tags`, or 0.
uint64_t sectionBytes(const std::vector<FileSection>& sections, const std::vector<std::string>& tags);

}  // namespace tetraprobe::cli
