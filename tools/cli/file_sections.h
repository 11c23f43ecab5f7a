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

// The sections of the level file at `path`, in file order (docs/level_format.md: a u32 count at byte 72,
// 24-byte entries from byte 80: tag, flags, offset, size, little-endian). Call only on a file loadLevel
// accepted or saveLevel wrote, so the table is whole and its checksum holds. Throws InputError when the
// file cannot be read.
std::vector<FileSection> fileSections(const std::string& path);

// The bytes of the first section whose tag is one of `tags`, or 0.
uint64_t sectionBytes(const std::vector<FileSection>& sections, const std::vector<std::string>& tags);

}  // namespace tetraprobe::cli
