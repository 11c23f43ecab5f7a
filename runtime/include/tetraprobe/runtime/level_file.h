// The level file's framing (docs/level_format.md): the fixed header, the section table and their
// checksums, parsed and validated in one place for every reader: loadLevel (level.h), StreamingLevel
// (streaming.h) and `tetraprobe inspect`. Safe on untrusted bytes: nothing is read past what the caller
// hands in, and every count is checked before it is used. Permissive: standard library and GLM only.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include <glm/vec3.hpp>

#include "tetraprobe/runtime/level.h"

namespace tetraprobe {

// `\x89TPB\r\n\x1a\n`: catches text-mode and 7-bit transfers.
inline constexpr uint8_t kLevelMagic[8] = {0x89, 'T', 'P', 'B', '\r', '\n', 0x1A, '\n'};
inline constexpr uint64_t kLevelHeaderBytes = 80;        // the fixed header
inline constexpr uint64_t kLevelHeaderCrcAt = 76;        // its CRC-32 of bytes [0, 76)
inline constexpr uint64_t kLevelSectionEntryBytes = 24;  // tag u32, flags u32, offset u64, size u64
inline constexpr uint32_t kLevelMaxSections = 64;
inline constexpr uint32_t kLevelSectionRequired = 1u;  // flags bit 0: a reader not knowing the tag refuses

// A section tag: four ASCII characters read as a little-endian u32 (`PRBS` = 0x53425250).
constexpr uint32_t levelTag(const char (&s)[5]) {
  return uint32_t(uint8_t(s[0])) | uint32_t(uint8_t(s[1])) << 8 | uint32_t(uint8_t(s[2])) << 16 |
         uint32_t(uint8_t(s[3])) << 24;
}
// The four characters of a tag.
std::string levelTagName(uint32_t tag);

// One entry of the section table, as stored.
struct LevelSectionEntry {
  uint32_t tag = 0;
  uint32_t flags = 0;
  uint64_t offset = 0;  // bytes from the file's start
  uint64_t size = 0;    // bytes
};

// Where one known section lies; present = false when the file has none.
struct LevelSectionRef {
  uint64_t offset = 0, size = 0;
  bool present = false;
};

// The header and the table of a file, checked as far as the framing goes (steps 1-8 of
// docs/level_format.md, "Loading untrusted files"), and each known section found.
struct LevelFileLayout {
  uint32_t version = 0;
  uint32_t content = 0;  // ProbeContent flags, as stored (validateLevel checks them)
  uint32_t shOrder = 0;  // as stored
  glm::dvec3 origin{0.0};
  uint64_t probeCount = 0, tetCount = 0, generatorBytes = 0;
  uint32_t sectionCount = 0;
  uint64_t tableEnd = 0;   // the first byte after the table and its CRC: 84 + 24 S
  uint64_t fileBytes = 0;  // the size the table implies (the payload CRC is its last 4 bytes)
  std::vector<LevelSectionEntry> sections;  // table order (after parseLevelTable)
  // The known sections (tags in docs/level_format.md); unknown optional ones are only in `sections`.
  LevelSectionRef probes;                         // PRBS
  LevelSectionRef sh, shHalf;                     // SHRG, SHRH
  LevelSectionRef tets, tetsCompact, tetsPacked;  // TETS, TETC, TETM
  LevelSectionRef generator;                      // GENR
  LevelSectionRef outerCells;                     // OUTC
  LevelSectionRef cellGrid, cellGridPacked;       // CGR2, CGR4
  LevelSectionRef occlusion, occlusionPacked;     // OCCL, OCC2
  LevelSectionRef probeKinds;                     // KIND
  LevelSectionRef stream;                         // STRM
};

// Steps 1-5: magic (kNotALevel; a prefix of it in a file under 12 bytes is kTruncated), version (anything but
// kLevelFormatVersion is kUnsupportedVersion, the message naming the file's version and this reader's), the
// header's size, CRC and counts (kCorrupt), and the least size they need against `fileSize` (kTruncated).
// `data` holds the file's first min(fileSize, kLevelHeaderBytes) bytes. Sets every header field of `out`
// and tableEnd; messages start with `name`: "name: ...", one line.
LevelResult parseLevelHeader(const uint8_t* data, uint64_t fileSize, const std::string& name,
                             LevelFileLayout& out);

// Steps 6-8, after parseLevelHeader: the table's CRC, its entries (flags, offsets packed in order with no gap,
// sizes at most 2^40, no known tag twice: kCorrupt; an unknown tag flagged required: kUnsupportedVersion),
// and `fileSize` against the table's end (shorter: kTruncated, longer: kCorrupt). `table` holds the file's
// bytes [kLevelHeaderBytes, out.tableEnd). Sets `sections`, the known sections and fileBytes.
LevelResult parseLevelTable(const uint8_t* table, uint64_t fileSize, const std::string& name,
                            LevelFileLayout& out);

// Step 10: each known section present when required and sized as the header's counts say, and at most one
// of each alternative form (SHRG/SHRH; TETS/TETC/TETM; CGR2/CGR4; OCCL/OCC2); kCorrupt otherwise. The checks
// that need a section's own bytes (its inner header) are its reader's.
LevelResult checkLevelSections(const LevelFileLayout& layout, const std::string& name);

// Header and table of the file at `path`, reading only those bytes (80 + 24 S + 4): parseLevelHeader and
// parseLevelTable. kCannotOpen when the file cannot be read. `bytesRead` (optional) is set to the bytes read.
LevelResult readLevelLayout(const std::string& path, LevelFileLayout& out, uint64_t* bytesRead = nullptr);

// For tests and fuzzers that forge files in memory: recomputes the header's, the table's and the payload's
// CRC-32 where the bytes are long enough to hold them, and, when the framing then parses and the file holds
// a streaming index (STRM) whose structure parses, the index's and each readable sector's CRC (the bytes they
// cover: docs/level_format.md, STRM). Never reads or writes outside [data, data + size); bytes it cannot
// parse are left as they are.
void recomputeLevelChecksums(uint8_t* data, size_t size);

}  // namespace tetraprobe
