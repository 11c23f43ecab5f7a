// A level file's section table as stored: contract in file_sections.h.
#include "file_sections.h"

#include <algorithm>

#include "tetraprobe/common/error.h"
#include "tetraprobe/runtime/level_file.h"

namespace tetraprobe::cli {

std::vector<FileSection> fileSections(const std::string& path) {
  // Only the header and the table are read (80 + 24 bytes a section), by the runtime's one parser.
  LevelFileLayout layout;
  if (const LevelResult r = readLevelLayout(path, layout); !r) throw InputError(r.message);
  std::vector<FileSection> out;
  for (const LevelSectionEntry& s : layout.sections) out.push_back({levelTagName(s.tag), s.size});
  return out;
}

uint64_t sectionBytes(const std::vector<FileSection>& sections, const std::vector<std::string>& tags) {
  for (const FileSection& s : sections)
    if (std::find(tags.begin(), tags.end(), s.tag) != tags.end()) return s.bytes;
  return 0;
}

}  // namespace tetraprobe::cli
