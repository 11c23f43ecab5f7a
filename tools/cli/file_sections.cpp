// A level file's section table as stored: contract in file_sections.h.
#include "file_sections.h"

#include <algorithm>
#include <fstream>

#include "tetraprobe/common/error.h"

namespace tetraprobe::cli {

std::vector<FileSection> fileSections(const std::string& path) {
  // Only the header and the table are read (80 + 24 bytes a section), not the level.
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(path + ": cannot open");
  const auto u = [](const char* b, int n) {
    uint64_t v = 0;
    for (int i = 0; i < n; ++i) v |= uint64_t(uint8_t(b[i])) << (8 * i);
    return v;
  };
  char header[80];
  std::vector<FileSection> out;
  if (!in.read(header, sizeof header)) return out;
  const uint64_t count = u(header + 72, 4);
  char entry[24];
  for (uint64_t i = 0; i < count && in.read(entry, sizeof entry); ++i)
    out.push_back({std::string(entry, 4), u(entry + 16, 8)});
  return out;
}

uint64_t sectionBytes(const std::vector<FileSection>& sections, const std::vector<std::string>& tags) {
  for (const FileSection& s : sections)
    if (std::find(tags.begin(), tags.end(), s.tag) != tags.end()) return s.bytes;
  return 0;
}

}  // namespace tetraprobe::cli
