// The level file's framing (level_file.h): header, section table and checksums, parsed once for every
// reader. The field tables and the order of the checks are docs/level_format.md's; the constants below and
// in level_file.h are their single source of truth.
#include "tetraprobe/runtime/level_file.h"

#include <algorithm>
#include <bit>
#include <climits>
#include <cstring>
#include <fstream>

#include "tetraprobe/runtime/crc32.h"
#include "tetraprobe/runtime/sh.h"
#include "tetraprobe/runtime/sh_half.h"

#include "byte_order.h"
#include "stream_format.h"

namespace tetraprobe {
namespace {

constexpr uint64_t kHeaderCrcOffset = kLevelHeaderCrcAt;
constexpr uint64_t kMaxSectionBytes = uint64_t(1) << 40;  // bounds every size sum below 2^47
constexpr uint64_t kMaxCount = uint64_t(INT32_MAX);       // probe and tet indices are int32
constexpr uint64_t kMaxGeneratorBytes = 1u << 20;
constexpr uint64_t kTrailerBytes = 4;      // CRC-32 of bytes [kLevelHeaderBytes, size - 4)
constexpr uint64_t kProbeBytes = 3 * 4;    // PRBS: 3 x f32
constexpr uint64_t kShBytes = 27 * 4;      // SHRG (read only): 9 coefficients x RGB f32
constexpr uint64_t kShHalfBytes = 28 * 2;  // SHRH: 27 binary16 coefficients + binary16 scale
constexpr uint64_t kTetBytes = 8 * 4;      // TETS (read only): v[4] i32, n[4] i32
constexpr uint64_t kMinTetBytes = 2;       // TETM: two control bytes a tet at least
constexpr uint64_t kOuterCellBytes = 80;   // OUTC (read only)
static_assert(kShBytes == sizeof(ShRgb) && kShHalfBytes == sizeof(ShHalf) && kTetBytes == sizeof(Tet));

using runtime_detail::putU32;
using runtime_detail::u32At;
using runtime_detail::u64At;

LevelResult fail(LevelStatus status, std::string message) {
  return {status, std::move(message)};
}

}  // namespace

std::string levelTagName(uint32_t tag) {
  std::string s(4, ' ');
  for (int i = 0; i < 4; ++i) s[size_t(i)] = char(uint8_t(tag >> (8 * i)));
  return s;
}

LevelResult parseLevelHeader(const uint8_t* data, uint64_t fileSize, const std::string& name,
                             LevelFileLayout& out) {
  const std::string where = name + ": ";
  const uint64_t size = fileSize;
  // Magic (a prefix of it in a short file means truncated, anything else is not a level), then version.
  if (size > 0 && std::memcmp(data, kLevelMagic, size_t(std::min<uint64_t>(size, sizeof kLevelMagic))) != 0)
    return fail(LevelStatus::kNotALevel, where + "not a tetraprobe level (bad magic)");
  if (size < sizeof kLevelMagic + 4)
    return fail(LevelStatus::kTruncated, where + "truncated: " + std::to_string(size) + " bytes");
  out = LevelFileLayout{};
  out.version = u32At(data + 8);
  if (out.version != kLevelFormatVersion)
    return fail(LevelStatus::kUnsupportedVersion,
                where + "format version " + std::to_string(out.version) +
                    " (this reader understands version " + std::to_string(kLevelFormatVersion) +
                    (out.version < kLevelFormatVersion ? "; re-bake the level)" : ")"));
  if (size < kLevelHeaderBytes)
    return fail(LevelStatus::kTruncated, where + "truncated header: " + std::to_string(size) + " bytes");
  if (crc32(data, kHeaderCrcOffset) != u32At(data + kHeaderCrcOffset))
    return fail(LevelStatus::kCorrupt, where + "header checksum mismatch");
  const uint32_t headerBytes = u32At(data + 12);
  out.content = u32At(data + 16);
  out.shOrder = u32At(data + 20);
  for (int a = 0; a < 3; ++a) out.origin[a] = std::bit_cast<double>(u64At(data + 24 + 8 * a));
  out.probeCount = u64At(data + 48);
  out.tetCount = u64At(data + 56);
  out.generatorBytes = u64At(data + 64);
  out.sectionCount = u32At(data + 72);
  if (headerBytes != kLevelHeaderBytes || out.sectionCount > kLevelMaxSections)
    return fail(LevelStatus::kCorrupt, where + "unexpected header size or " +
                                           std::to_string(out.sectionCount) + " sections (at most " +
                                           std::to_string(kLevelMaxSections) + ")");
  // Counts are checked against the limits first, so the size arithmetic below cannot overflow (< 2^48).
  if (out.probeCount > kMaxCount || out.tetCount > kMaxCount || out.generatorBytes > kMaxGeneratorBytes)
    return fail(LevelStatus::kCorrupt, where + "implausible counts: " + std::to_string(out.probeCount) +
                                           " probes, " + std::to_string(out.tetCount) + " tets, " +
                                           std::to_string(out.generatorBytes) + " generator bytes");
  out.tableEnd = kLevelHeaderBytes + kLevelSectionEntryBytes * out.sectionCount + 4;
  const uint64_t minimum = out.tableEnd + out.probeCount * (kProbeBytes + kShHalfBytes) +
                           out.tetCount * kMinTetBytes + out.generatorBytes + kTrailerBytes;
  if (size < minimum)
    return fail(LevelStatus::kTruncated, where + "truncated: " + std::to_string(size) +
                                             " bytes, the header needs at least " + std::to_string(minimum));
  return {};
}

LevelResult parseLevelTable(const uint8_t* table, uint64_t fileSize, const std::string& name,
                            LevelFileLayout& out) {
  const std::string where = name + ": ";
  const uint64_t tableBytes = out.tableEnd - 4 - kLevelHeaderBytes;
  if (crc32(table, size_t(tableBytes)) != u32At(table + tableBytes))
    return fail(LevelStatus::kCorrupt, where + "section table checksum mismatch");
  // Packed in table order after it, each size bounded so the sum cannot overflow.
  uint64_t expected = out.tableEnd;
  out.sections.clear();
  for (uint32_t i = 0; i < out.sectionCount; ++i) {
    const uint8_t* e = table + kLevelSectionEntryBytes * i;
    const LevelSectionEntry entry{u32At(e), u32At(e + 4), u64At(e + 8), u64At(e + 16)};
    const std::string at = where + "section " + std::to_string(i) + ": ";
    if ((entry.flags & ~kLevelSectionRequired) != 0 || entry.offset != expected ||
        entry.size > kMaxSectionBytes)
      return fail(LevelStatus::kCorrupt, at + "bad flags, offset or size");
    expected += entry.size;
    const uint32_t t = entry.tag;
    LevelSectionRef* known = t == levelTag("PRBS")   ? &out.probes
                             : t == levelTag("SHRG") ? &out.sh
                             : t == levelTag("SHRH") ? &out.shHalf
                             : t == levelTag("TETS") ? &out.tets
                             : t == levelTag("TETC") ? &out.tetsCompact
                             : t == levelTag("TETM") ? &out.tetsPacked
                             : t == levelTag("GENR") ? &out.generator
                             : t == levelTag("OUTC") ? &out.outerCells
                             : t == levelTag("CGR2") ? &out.cellGrid
                             : t == levelTag("CGR4") ? &out.cellGridPacked
                             : t == levelTag("OCCL") ? &out.occlusion
                             : t == levelTag("OCC2") ? &out.occlusionPacked
                             : t == levelTag("KIND") ? &out.probeKinds
                             : t == levelTag("STRM") ? &out.stream
                                                     : nullptr;
    out.sections.push_back(entry);
    if (!known) {
      if (entry.flags & kLevelSectionRequired)
        return fail(LevelStatus::kUnsupportedVersion,
                    at + "unknown required section tag " + std::to_string(t));
      continue;  // optional data this reader does not know: skipped (still covered by the payload CRC)
    }
    if (known->present) return fail(LevelStatus::kCorrupt, at + "repeated section tag");
    *known = {entry.offset, entry.size, true};
  }
  expected += kTrailerBytes;
  if (fileSize < expected)
    return fail(LevelStatus::kTruncated, where + "truncated: " + std::to_string(fileSize) +
                                             " bytes, the section table needs " + std::to_string(expected));
  if (fileSize > expected)
    return fail(LevelStatus::kCorrupt,
                where + std::to_string(fileSize - expected) + " unexpected trailing bytes");
  out.fileBytes = expected;
  return {};
}

LevelResult checkLevelSections(const LevelFileLayout& l, const std::string& name) {
  const std::string where = name + ": ";
  const auto sized = [&](const LevelSectionRef& sec, uint64_t want, const char* what) -> LevelResult {
    if (!sec.present) return fail(LevelStatus::kCorrupt, where + "missing " + what + " section");
    if (sec.size != want)
      return fail(LevelStatus::kCorrupt, where + what + " section of " + std::to_string(sec.size) +
                                             " bytes, the header's counts need " + std::to_string(want));
    return {};
  };
  if (LevelResult e = sized(l.probes, l.probeCount * kProbeBytes, "probe"); !e) return e;
  // SH: half precision (SHRH, what saveLevel writes) or float (SHRG, levels written before it), not both.
  if (l.sh.present && l.shHalf.present)
    return fail(LevelStatus::kCorrupt, where + "both SHRG and SHRH SH sections");
  if (LevelResult e = l.shHalf.present ? sized(l.shHalf, l.probeCount * kShHalfBytes, "SH")
                                       : sized(l.sh, l.probeCount * kShBytes, "SH");
      !e)
    return e;
  // Tets: packed (TETM), fixed records (TETC, streamed levels) or with neighbours (TETS); one of the three.
  if (int(l.tets.present) + int(l.tetsCompact.present) + int(l.tetsPacked.present) > 1)
    return fail(LevelStatus::kCorrupt, where + "more than one of the TETS, TETC and TETM tet sections");
  if (l.tetsPacked.present) {
    if (l.tetsPacked.size < kMinTetBytes * l.tetCount)  // the decoder checks the rest
      return fail(LevelStatus::kCorrupt, where + "tet section of " + std::to_string(l.tetsPacked.size) +
                                             " bytes, the header's counts need at least " +
                                             std::to_string(kMinTetBytes * l.tetCount));
  } else if (LevelResult e =
                 l.tetsCompact.present
                     ? sized(l.tetsCompact, l.tetCount * 4 * levelProbeIndexBytes(l.probeCount), "tet")
                     : sized(l.tets, l.tetCount * kTetBytes, "tet");
             !e) {
    return e;
  }
  if (LevelResult e = sized(l.generator, l.generatorBytes, "generator"); !e) return e;
  if (l.outerCells.present &&
      (l.outerCells.size % kOuterCellBytes != 0 || l.outerCells.size / kOuterCellBytes > kMaxCount))
    return fail(LevelStatus::kCorrupt, where + "outer cell section of " + std::to_string(l.outerCells.size) +
                                           " bytes is not whole records");
  if (l.probeKinds.present && l.probeKinds.size != l.probeCount)
    return fail(LevelStatus::kCorrupt, where + "probe kind section of " + std::to_string(l.probeKinds.size) +
                                           " bytes for " + std::to_string(l.probeCount) + " probes");
  if (l.cellGrid.present && l.cellGridPacked.present)
    return fail(LevelStatus::kCorrupt, where + "both CGR2 and CGR4 cell grid sections");
  if (l.cellGridPacked.present && l.tets.present)  // CGR4 refers to the neighbours the loader derives
    return fail(LevelStatus::kCorrupt, where + "a CGR4 cell grid with TETS tets");
  if (l.occlusion.present && l.occlusionPacked.present)
    return fail(LevelStatus::kCorrupt, where + "both OCCL and OCC2 occlusion sections");
  return {};
}

LevelResult readLevelLayout(const std::string& path, LevelFileLayout& out, uint64_t* bytesRead) {
  if (bytesRead) *bytesRead = 0;
  std::ifstream in(path, std::ios::binary | std::ios::ate);
  if (!in) return fail(LevelStatus::kCannotOpen, path + ": cannot open");
  const auto end = in.tellg();
  if (end < 0) return fail(LevelStatus::kCannotOpen, path + ": cannot read");
  const auto size = uint64_t(end);
  const auto readAt = [&](uint64_t at, uint8_t* p, uint64_t n) {
    in.seekg(std::streamoff(at));
    in.read(reinterpret_cast<char*>(p), std::streamsize(n));
    if (bytesRead) *bytesRead += n;
    return bool(in);
  };
  uint8_t header[kLevelHeaderBytes];
  const uint64_t headerRead = std::min<uint64_t>(size, kLevelHeaderBytes);
  if (!readAt(0, header, headerRead)) return fail(LevelStatus::kCannotOpen, path + ": read failed");
  if (LevelResult r = parseLevelHeader(header, size, path, out); !r) return r;
  std::vector<uint8_t> table(size_t(out.tableEnd - kLevelHeaderBytes));
  if (!readAt(kLevelHeaderBytes, table.data(), table.size()))
    return fail(LevelStatus::kCannotOpen, path + ": read failed");
  return parseLevelTable(table.data(), size, path, out);
}

void recomputeLevelChecksums(uint8_t* data, size_t size) {
  if (size < kLevelHeaderBytes) return;
  putU32(data + kHeaderCrcOffset, crc32(data, kHeaderCrcOffset));
  const uint32_t sections = u32At(data + 72);
  if (sections <= kLevelMaxSections) {
    const uint64_t tableEnd = kLevelHeaderBytes + kLevelSectionEntryBytes * sections + 4;
    if (size >= tableEnd)
      putU32(data + tableEnd - 4, crc32(data + kLevelHeaderBytes, size_t(tableEnd - 4 - kLevelHeaderBytes)));
    LevelFileLayout layout;
    if (parseLevelHeader(data, size, "", layout) &&
        parseLevelTable(data + kLevelHeaderBytes, size, "", layout) && checkLevelSections(layout, "") &&
        layout.stream.present)
      runtime_detail::sealStreamIndex(data, size, layout, runtime_detail::StreamSeal::kWhatParses);
  }
  if (size >= kLevelHeaderBytes + kTrailerBytes)
    putU32(data + size - kTrailerBytes,
           crc32(data + kLevelHeaderBytes, size - kTrailerBytes - kLevelHeaderBytes));
}

}  // namespace tetraprobe
