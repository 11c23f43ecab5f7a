// The `.tpb` level file: exact round trips, and a loader that survives hostile bytes (docs/level_format.md).
#include <gtest/gtest.h>

#include <unistd.h>

#include <algorithm>
#include <array>
#include <climits>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <random>

#include "test_levels.h"
#include "tetraprobe/runtime/crc32.h"
#include "tetraprobe/runtime/file_io.h"
#include "tetraprobe/runtime/level.h"
#include "tetraprobe/runtime/occlusion.h"
#include "tetraprobe/runtime/outer_cells.h"
#include "tetraprobe/runtime/query.h"
#include "tetraprobe/runtime/sh_half.h"

namespace tetraprobe {
namespace {

namespace fs = std::filesystem;

// A fresh directory per test, removed afterwards; in memory where possible (the corruption tests write
// thousands of small files).
class TempDir {
 public:
  TempDir() {
    const fs::path base = fs::is_directory("/dev/shm") ? fs::path("/dev/shm") : fs::temp_directory_path();
    path_ = base / ("tetraprobe_level_" + std::to_string(::getpid()) + "_" + std::to_string(counter_++));
    fs::create_directories(path_);
  }
  ~TempDir() { fs::remove_all(path_); }
  std::string file(const std::string& name) const { return (path_ / name).string(); }
  const fs::path& path() const { return path_; }

 private:
  static inline int counter_ = 0;
  fs::path path_;
};

Level smallLevel() {
  Level level =
      test::makeLevel(test::randomBoxPoints(10, 3, {-2, -1, -3}, {2, 1, 3}), {5000.25, -20.5, 1e4}, 9);
  level.content = kContentAll;
  level.outerCells = buildOuterCells(level.probes, level.tets);
  level.cellGrid = buildCellGrid(level.probes, level.tets, 2.0f, 1);
  return level;
}

std::vector<char> bytesOf(const std::string& path) {
  std::vector<char> b;
  std::string err;
  EXPECT_TRUE(readFile(path, b, &err)) << err;
  return b;
}

void writeBytes(const std::string& path, const std::vector<char>& b, size_t n) {
  std::ofstream(path, std::ios::binary).write(b.data(), std::streamsize(n));
}

void putU32(std::vector<char>& b, size_t at, uint32_t v) {
  for (int i = 0; i < 4; ++i) b[at + size_t(i)] = char(uint8_t(v >> (8 * i)));
}
void putU64(std::vector<char>& b, size_t at, uint64_t v) {
  for (int i = 0; i < 8; ++i) b[at + size_t(i)] = char(uint8_t(v >> (8 * i)));
}
void fixHeaderCrc(std::vector<char>& b) {
  putU32(b, 76, crc32(b.data(), 76));
}
void fixPayloadCrc(std::vector<char>& b) {
  putU32(b, b.size() - 4, crc32(b.data() + 80, b.size() - 84));
}

bool emptyLevel(const Level& l) {
  return l.probes.empty() && l.sh.empty() && l.tets.empty() && l.generator.empty() && l.outerCells.empty() &&
         l.cellGrid.slots.empty() && l.cellGrid.nodes.empty();
}

uint32_t getU32(const std::vector<char>& b, size_t at) {
  uint32_t v = 0;
  for (int i = 0; i < 4; ++i) v |= uint32_t(uint8_t(b[at + size_t(i)])) << (8 * i);
  return v;
}
uint64_t getU64(const std::vector<char>& b, size_t at) {
  return uint64_t(getU32(b, at)) | uint64_t(getU32(b, at + 4)) << 32;
}
uint32_t tagOf(const char* s) {
  return uint32_t(uint8_t(s[0])) | uint32_t(uint8_t(s[1])) << 8 | uint32_t(uint8_t(s[2])) << 16 |
         uint32_t(uint8_t(s[3])) << 24;
}

// Field `at` (8: offset, 16: size) of the table entry of the section tagged `tag` (docs/level_format.md: the
// table of 24-byte entries follows the 80-byte header).
size_t sectionField(const std::vector<char>& b, const char* tag, size_t at) {
  const uint32_t n = getU32(b, 72);
  for (uint32_t i = 0; i < n; ++i)
    if (getU32(b, 80 + 24 * i) == tagOf(tag)) return size_t(getU64(b, 80 + 24 * i + at));
  ADD_FAILURE() << "no section " << tag;
  return 0;
}
size_t sectionOffset(const std::vector<char>& b, const char* tag) {
  return sectionField(b, tag, 8);
}
size_t sectionSize(const std::vector<char>& b, const char* tag) {
  return sectionField(b, tag, 16);
}

// `bytes`, written and loaded, is refused as kCorrupt with a message holding `needle`, and nothing is loaded.
void expectRefusedAsCorrupt(TempDir& dir, const std::vector<char>& bytes, const char* needle) {
  writeBytes(dir.file("refused.tpb"), bytes, bytes.size());
  Level out;
  const LevelResult r = loadLevel(dir.file("refused.tpb"), out);
  EXPECT_EQ(r.status, LevelStatus::kCorrupt) << r.message;
  EXPECT_NE(r.message.find(needle), std::string::npos) << r.message;
  EXPECT_TRUE(emptyLevel(out));
}

// checksum made consistent again: how files written before a section changed look.
std::vector<char> withSectionReplaced(const std::vector<char>& full, const char* from, const char* to,
                                      const std::string& data) {
  const uint32_t n = getU32(full, 72);
  const size_t tableEnd = 80 + 24 * size_t(n) + 4;
  std::vector<char> b(full.begin(), full.begin() + long(tableEnd));
  int64_t shift = 0;
  for (uint32_t i = 0; i < n; ++i) {
    const size_t e = 80 + 24 * size_t(i);
    const uint64_t offset = getU64(full, e + 8), size = getU64(full, e + 16);
    putU64(b, e + 8, uint64_t(int64_t(offset) + shift));
    if (getU32(full, e) == tagOf(from)) {
      putU32(b, e, tagOf(to));
      putU64(b, e + 16, data.size());
      b.insert(b.end(), data.begin(), data.end());
      shift += int64_t(data.size()) - int64_t(size);
    } else {
      b.insert(b.end(), full.begin() + long(offset), full.begin() + long(offset + size));
    }
  }
  putU32(b, tableEnd - 4, crc32(b.data() + 80, tableEnd - 4 - 80));
  b.resize(b.size() + 4);
  fixPayloadCrc(b);
  return b;
}

// The file with its packed tets (TETM) written as fixed records instead (TETC: each probe index in
// levelProbeIndexBytes(P) bytes, what a streamed level stores), for `tets` (the level's, or forged ones).
std::vector<char> withFixedTetRecords(const std::vector<char>& full, const std::vector<Tet>& tets,
                                      size_t probeCount) {
  const uint32_t w = levelProbeIndexBytes(probeCount);
  std::string records;
  for (const Tet& t : tets)
    for (int32_t v : t.v)
      for (uint32_t k = 0; k < w; ++k) records.push_back(char(uint8_t(uint32_t(v) >> (8 * k))));
  return withSectionReplaced(full, "TETM", "TETC", records);
}

// The file with one more section appended (table entry, data), every checksum made consistent again.
std::vector<char> withExtraSection(const std::vector<char>& full, const char* tag, uint32_t flags,
                                   const std::string& data) {
  const uint32_t n = getU32(full, 72);
  const size_t oldTableEnd = 80 + 24 * size_t(n) + 4, newTableEnd = oldTableEnd + 24;
  std::vector<char> b(full.begin(), full.begin() + 80);
  putU32(b, 72, n + 1);
  fixHeaderCrc(b);
  b.resize(newTableEnd);
  for (uint32_t i = 0; i < n; ++i) {
    const size_t e = 80 + 24 * size_t(i);
    std::copy(full.begin() + long(e), full.begin() + long(e + 24), b.begin() + long(e));
    putU64(b, e + 8, getU64(full, e + 8) + 24);
  }
  const size_t e = 80 + 24 * size_t(n);
  putU32(b, e, tagOf(tag));
  putU32(b, e + 4, flags);
  putU64(b, e + 8, full.size() - 4 + 24);
  putU64(b, e + 16, data.size());
  putU32(b, newTableEnd - 4, crc32(b.data() + 80, newTableEnd - 4 - 80));
  b.insert(b.end(), full.begin() + long(oldTableEnd), full.end() - 4);
  b.insert(b.end(), data.begin(), data.end());
  b.resize(b.size() + 4);
  fixPayloadCrc(b);
  return b;
}

// A bake must reload exactly (no float re-rounding, nothing dropped), and equal input must give equal bytes.
TEST(LevelFile, RoundTripIsBitExact) {
  TempDir dir;
  const Level level = smallLevel();
  ASSERT_TRUE(saveLevel(dir.file("a.tpb"), level));
  Level back;
  const LevelResult r = loadLevel(dir.file("a.tpb"), back);
  ASSERT_TRUE(r) << r.message;
  EXPECT_EQ(back.content, level.content);
  EXPECT_EQ(back.shOrder, level.shOrder);
  EXPECT_EQ(std::memcmp(&back.origin, &level.origin, sizeof(level.origin)), 0);
  ASSERT_EQ(back.probes.size(), level.probes.size());
  ASSERT_EQ(back.sh.size(), level.sh.size());
  ASSERT_EQ(back.tets.size(), level.tets.size());
  EXPECT_EQ(std::memcmp(back.probes.data(), level.probes.data(), level.probes.size() * sizeof(glm::vec3)), 0);
  EXPECT_EQ(std::memcmp(back.sh.data(), level.sh.data(), level.sh.size() * sizeof(ShRgb)), 0);
  EXPECT_EQ(std::memcmp(back.tets.data(), level.tets.data(), level.tets.size() * sizeof(Tet)), 0);
  EXPECT_EQ(back.generator, level.generator);
  // Neighbours (compared with the tets above) and outer cells are not stored but derived: the query builds
  // the same outer cells, bit for bit.
  EXPECT_TRUE(back.outerCells.empty());
  ASSERT_FALSE(level.outerCells.empty());
  const ProbeQuery query(back);
  ASSERT_EQ(query.outerCells().size(), level.outerCells.size());
  EXPECT_EQ(std::memcmp(query.outerCells().data(), level.outerCells.data(),
                        level.outerCells.size() * sizeof(OuterCell)),
            0);
  const CellGrid &g = level.cellGrid, &gb = back.cellGrid;
  ASSERT_FALSE(g.slots.empty());
  EXPECT_EQ(gb.min, g.min);
  EXPECT_EQ(gb.cellSize, g.cellSize);
  EXPECT_EQ(gb.maxProbe, g.maxProbe);
  EXPECT_EQ(gb.maxDepth, g.maxDepth);
  EXPECT_EQ(gb.meanDepth, g.meanDepth);
  EXPECT_EQ(gb.leaves, g.leaves);
  EXPECT_EQ(gb.unprovenLeaves, g.unprovenLeaves);
  ASSERT_EQ(gb.slots.size(), g.slots.size());
  ASSERT_EQ(gb.nodes.size(), g.nodes.size());
  EXPECT_EQ(std::memcmp(gb.slots.data(), g.slots.data(), g.slots.size() * sizeof(CellSlot)), 0);
  EXPECT_EQ(std::memcmp(gb.nodes.data(), g.nodes.data(), g.nodes.size() * sizeof(BspNode)), 0);
  ASSERT_TRUE(saveLevel(dir.file("b.tpb"), level));
  ASSERT_TRUE(saveLevel(dir.file("c.tpb"), back));
  EXPECT_EQ(bytesOf(dir.file("a.tpb")), bytesOf(dir.file("b.tpb")));
  EXPECT_EQ(bytesOf(dir.file("a.tpb")), bytesOf(dir.file("c.tpb")));
  // The documented size: 80-byte header, five 24-byte table entries and the table's CRC, 68 bytes per
  // probe (12 position + 56 half-precision SH), the tets' packed probes (TETM: two control bytes a tet and a
  // one-byte varint for each probe not among the last 15 named, all of them below 64 apart here), the
  // generator, the cell grid (64-byte header, 16 per slot, then the node stream of CGR4: 1 to 4 bytes a node
  // on a level this small, its face varint plus leaves given explicitly), a 4-byte CRC.
  const std::vector<char> a = bytesOf(dir.file("a.tpb"));
  ASSERT_NE(sectionOffset(a, "TETM"), 0u);
  ASSERT_NE(sectionOffset(a, "CGR4"), 0u);
  ASSERT_LT(level.probes.size(), 64u);
  const size_t tets = sectionSize(a, "TETM");
  EXPECT_GE(tets, 2 * level.tets.size() + level.probes.size());  // each probe given once at least
  EXPECT_LE(tets, 6 * level.tets.size());
  const size_t stream = sectionSize(a, "CGR4") - 64 - 16 * g.slots.size();
  EXPECT_GE(stream, g.nodes.size());
  EXPECT_LE(stream, 4 * g.nodes.size());
  EXPECT_EQ(a.size(), 80 + 5 * 24 + 4 + 68 * level.probes.size() + tets + level.generator.size() + 64 +
                          16 * g.slots.size() + stream + 4);
}

// An interrupted copy or download leaves a prefix: every prefix must be reported, never read past its end.
TEST(LevelFile, RejectsTruncatedFilesAtEveryLength) {
  TempDir dir;
  ASSERT_TRUE(saveLevel(dir.file("full.tpb"), smallLevel()));
  const std::vector<char> full = bytesOf(dir.file("full.tpb"));
  for (size_t n = 0; n < full.size(); ++n) {
    writeBytes(dir.file("cut.tpb"), full, n);
    Level out;
    const LevelResult r = loadLevel(dir.file("cut.tpb"), out);
    ASSERT_EQ(r.status, LevelStatus::kTruncated) << n << " of " << full.size() << " bytes: " << r.message;
    EXPECT_FALSE(r.message.empty());
    EXPECT_TRUE(emptyLevel(out));
  }
}

// Bit rot and hostile edits must end in a status (bad magic, bad version, or corrupt), never a crash or a
// silently different level.
TEST(LevelFile, RejectsCorruptedByte) {
  TempDir dir;
  ASSERT_TRUE(saveLevel(dir.file("full.tpb"), smallLevel()));
  const std::vector<char> full = bytesOf(dir.file("full.tpb"));
  for (size_t at = 0; at < full.size(); ++at)
    for (uint8_t flip : {uint8_t(0x01), uint8_t(0x80), uint8_t(0xFF)}) {
      std::vector<char> b = full;
      b[at] = char(uint8_t(b[at]) ^ flip);
      writeBytes(dir.file("bad.tpb"), b, b.size());
      Level out;
      const LevelResult r = loadLevel(dir.file("bad.tpb"), out);
      const LevelStatus want = at < 8    ? LevelStatus::kNotALevel
                               : at < 12 ? LevelStatus::kUnsupportedVersion
                                         : LevelStatus::kCorrupt;
      ASSERT_EQ(r.status, want) << "byte " << at << " ^ " << int(flip) << ": " << r.message;
      EXPECT_TRUE(emptyLevel(out));
    }
}

// A file with valid checksums but broken indices (a buggy writer, or a forger) must fail validation.
TEST(LevelFile, RejectsOutOfRangeIndicesWithValidChecksums) {
  TempDir dir;
  const Level level = smallLevel();
  ASSERT_TRUE(saveLevel(dir.file("full.tpb"), level));
  // Fixed tet records (TETC, as a streamed level stores them) to forge indices in place; the packed form's
  // forgeries are in RejectsForgedTetStreams.
  const std::vector<char> full =
      withFixedTetRecords(bytesOf(dir.file("full.tpb")), level.tets, level.probes.size());
  const size_t tets = sectionOffset(full, "TETC");
  const size_t grid = sectionOffset(full, "CGR4"), slots = grid + 64;
  size_t usedSlot = 0;
  while (level.cellGrid.slots[usedSlot].key[0] == INT32_MIN) ++usedSlot;
  const struct {
    size_t offset;
    uint32_t value;
    const char* needle;
  } cases[] = {{tets + 0, uint32_t(level.probes.size()) | uint32_t(level.tets[0].v[1]) << 16,
                "out of range"},  // tet 0 vertex 0 (2-byte indices: vertex 1 kept)
               {tets + 8, uint32_t(level.probes.size()) | uint32_t(level.tets[1].v[1]) << 16,
                "out of range"},  // tet 1 vertex 0
               {tets + 0, uint32_t(level.tets[0].v[0]) | uint32_t(level.tets[0].v[0]) << 16,
                "repeated"},  // tet 0 vertex 1 = vertex 0
               {slots + 16 * usedSlot + 12, uint32_t(level.cellGrid.nodes.size() + 5), "root out of range"},
               {slots + 16 * usedSlot + 12, uint32_t(~int32_t(level.tets.size())), "root out of range"},
               {grid + 12, 0x7FC00000u, "cell size"}};
  for (const auto& c : cases) {
    std::vector<char> b = full;
    putU32(b, c.offset, c.value);
    fixPayloadCrc(b);
    writeBytes(dir.file("forged.tpb"), b, b.size());
    Level out;
    const LevelResult r = loadLevel(dir.file("forged.tpb"), out);
    EXPECT_EQ(r.status, LevelStatus::kCorrupt) << r.message;
    EXPECT_NE(r.message.find(c.needle), std::string::npos) << r.message;
    EXPECT_TRUE(emptyLevel(out));
  }
}

// Tet records hold each probe index in the fewest bytes that reach every probe: 2 up to 65,536 probes, 3
// above (and 4 above 2^24, the same code with n = 4). A level of 65,600 probes whose tets name probes beyond
// 2^16 round-trips exactly, at 12 bytes a tet.
TEST(LevelFile, ProbeIndicesTakeThreeBytesAbove65536Probes) {
  EXPECT_EQ(levelProbeIndexBytes(0), 2u);
  EXPECT_EQ(levelProbeIndexBytes(65536), 2u);
  EXPECT_EQ(levelProbeIndexBytes(65537), 3u);
  EXPECT_EQ(levelProbeIndexBytes(uint64_t(1) << 24), 3u);
  EXPECT_EQ(levelProbeIndexBytes((uint64_t(1) << 24) + 1), 4u);
  TempDir dir;
  const Level small = smallLevel();
  Level level = small;
  const size_t extra = 65600 - small.probes.size();  // probes no tet names, far from the small level
  level.probes.clear();
  level.sh.clear();
  for (size_t i = 0; i < extra; ++i) {
    level.probes.emplace_back(100.0f + float(i % 256), 100.0f + float(i / 256), 0.0f);
    level.sh.push_back(ShRgb{});
  }
  level.probes.insert(level.probes.end(), small.probes.begin(), small.probes.end());
  level.sh.insert(level.sh.end(), small.sh.begin(), small.sh.end());
  for (Tet& t : level.tets)
    for (int32_t& v : t.v) v += int32_t(extra);
  level.outerCells.clear();
  level.cellGrid = CellGrid{};
  // A level with a streaming index keeps fixed records (TETC: the streaming loader seeks them). Here the
  // smallest index (docs/level_format.md, STRM: version 2, no sector, no coarse set, 1 m cells), whose
  // checksum saveLevel computes.
  level.stream.assign(64, 0);
  level.stream[0] = 2;
  level.stream[23] = 0x3F;  // f32 1.0 at byte 20
  level.stream[22] = 0x80;
  ASSERT_TRUE(saveLevel(dir.file("wide.tpb"), level));
  const std::vector<char> b = bytesOf(dir.file("wide.tpb"));
  const size_t tets = sectionOffset(b, "TETC"), generator = sectionOffset(b, "GENR");
  EXPECT_EQ(generator - tets, 12 * level.tets.size());
  // Packed (TETM, no streaming index) the probes' indices above 2^16 are given as 3-byte varints.
  Level packed = level;
  packed.stream.clear();
  ASSERT_TRUE(saveLevel(dir.file("packed.tpb"), packed));
  const std::vector<char> p = bytesOf(dir.file("packed.tpb"));
  EXPECT_LT(sectionSize(p, "TETM"), 12 * level.tets.size());
  for (const char* file : {"wide.tpb", "packed.tpb"}) {
    Level back;
    const LevelResult r = loadLevel(dir.file(file), back);
    ASSERT_TRUE(r) << file << ": " << r.message;
    ASSERT_EQ(back.tets.size(), level.tets.size());
    EXPECT_EQ(std::memcmp(back.tets.data(), level.tets.data(), level.tets.size() * sizeof(Tet)), 0) << file;
  }
}

// Neighbours are derived from the stored probes of each tet (linkTetNeighbours): a file whose tets do not
// form a tetrahedralization, here one tet copied over another (each of its interior faces then has three
// tets), is refused with a message naming the face, not walked.
TEST(LevelFile, RefusesTetsThatShareAFaceThreeWays) {
  TempDir dir;
  const Level level = smallLevel();
  ASSERT_TRUE(saveLevel(dir.file("full.tpb"), level));
  const std::vector<char> full = bytesOf(dir.file("full.tpb"));
  size_t interior = 0;
  while (interior < level.tets.size() &&
         *std::min_element(level.tets[interior].n, level.tets[interior].n + 4) < 0)
    ++interior;
  ASSERT_LT(interior, level.tets.size());
  const size_t victim = interior == 0 ? 1 : 0;
  std::vector<Tet> forged = level.tets;
  forged[victim] = level.tets[interior];
  std::vector<char> b = withFixedTetRecords(full, forged, level.probes.size());
  writeBytes(dir.file("forged.tpb"), b, b.size());
  Level out;
  const LevelResult r = loadLevel(dir.file("forged.tpb"), out);
  EXPECT_EQ(r.status, LevelStatus::kCorrupt) << r.message;
  EXPECT_NE(r.message.find("shared by 3 tets"), std::string::npos) << r.message;
  EXPECT_TRUE(emptyLevel(out));
}

// Fuzzing past the checksums: whatever the validator lets through must be safe to query (no crash, no NaN,
// no out-of-range tet), and whatever it rejects must be reported as corrupt.
TEST(LevelFile, MutationsBehindValidChecksumsAreRejectedOrSafe) {
  TempDir dir;
  ASSERT_TRUE(saveLevel(dir.file("full.tpb"), smallLevel()));
  const std::vector<char> full = bytesOf(dir.file("full.tpb"));
  std::mt19937_64 rng(77);
  std::uniform_int_distribution<size_t> at(80, full.size() - 5);
  std::uniform_int_distribution<int> byte(0, 255), flips(1, 8);
  std::uniform_real_distribution<double> coord(-1e4, 1e4);
  int accepted = 0;
  for (int iter = 0; iter < 3000; ++iter) {
    std::vector<char> b = full;
    for (int k = flips(rng); k > 0; --k) b[at(rng)] = char(byte(rng));
    fixPayloadCrc(b);
    writeBytes(dir.file("fuzz.tpb"), b, b.size());
    Level level;
    const LevelResult r = loadLevel(dir.file("fuzz.tpb"), level);
    if (!r) {
      ASSERT_EQ(r.status, LevelStatus::kCorrupt) << "iteration " << iter << ": " << r.message;
      continue;
    }
    ++accepted;
    ASSERT_TRUE(validateLevel(level));
    const ProbeQuery q(level);
    for (int k = 0; k < 20; ++k) {
      const glm::dvec3 x =
          level.origin + glm::dvec3(coord(rng), coord(rng), coord(rng)) * (k < 10 ? 1e-3 : 1.0);
      const Location loc = q.locate(x);
      ASSERT_GE(loc.tet, 0);
      ASSERT_LT(size_t(loc.tet), level.tets.size());
      float sum = 0.0f;
      for (int i = 0; i < 4; ++i) {
        ASSERT_TRUE(std::isfinite(loc.weights[i]) && loc.weights[i] >= 0.0f) << "iteration " << iter;
        sum += loc.weights[i];
      }
      ASSERT_NEAR(sum, 1.0f, 1e-5f) << "iteration " << iter;
    }
  }
  EXPECT_GT(accepted,
            100);  // float fields (positions, SH) take most mutations: both paths are exercised
}

// A header claiming 1e12 tets must fail on the size check, before any allocation.
TEST(LevelFile, RejectsHugeCounts) {
  TempDir dir;
  ASSERT_TRUE(saveLevel(dir.file("full.tpb"), smallLevel()));
  const std::vector<char> full = bytesOf(dir.file("full.tpb"));
  const struct {
    size_t offset;
    uint64_t count;
    LevelStatus want;
  } cases[] = {{56, 1'000'000'000'000ull, LevelStatus::kCorrupt},  // tets beyond the int32 index range
               {48, ~0ull, LevelStatus::kCorrupt},               // probes: would overflow a size computation
               {56, 2'000'000'000ull, LevelStatus::kTruncated},  // in range, but the file is far too short
               {64, 1ull << 40, LevelStatus::kCorrupt}};         // generator string
  for (const auto& c : cases) {
    std::vector<char> b = full;
    putU64(b, c.offset, c.count);
    fixHeaderCrc(b);
    writeBytes(dir.file("huge.tpb"), b, b.size());
    Level out;
    const LevelResult r = loadLevel(dir.file("huge.tpb"), out);
    EXPECT_EQ(r.status, c.want) << "count " << c.count << " at " << c.offset << ": " << r.message;
    EXPECT_TRUE(emptyLevel(out));
  }
}

// Not every file handed to the loader is a level; the status must say which problem it is.
TEST(LevelFile, RejectsOtherFilesAndVersions) {
  TempDir dir;
  Level out;
  EXPECT_EQ(loadLevel(dir.file("missing.tpb"), out).status, LevelStatus::kCannotOpen);
  std::ofstream(dir.file("text.tpb")) << "# this is a text file, not a level\n";
  EXPECT_EQ(loadLevel(dir.file("text.tpb"), out).status, LevelStatus::kNotALevel);
  ASSERT_TRUE(saveLevel(dir.file("full.tpb"), smallLevel()));
  std::vector<char> b = bytesOf(dir.file("full.tpb"));
  // 1 had no section table, 2 stored rows, 3 float planes, 4 a streaming index without checksums: re-bake
  // (or re-stream) such levels; 6 is newer than this reader.
  for (uint32_t version : {1u, 2u, 3u, 4u, 6u}) {
    putU32(b, 8, version);
    fixHeaderCrc(b);
    writeBytes(dir.file("other.tpb"), b, b.size());
    EXPECT_EQ(loadLevel(dir.file("other.tpb"), out).status, LevelStatus::kUnsupportedVersion) << version;
  }
  b = bytesOf(dir.file("full.tpb"));
  b.push_back(0);
  writeBytes(dir.file("long.tpb"), b, b.size());
  EXPECT_EQ(loadLevel(dir.file("long.tpb"), out).status, LevelStatus::kCorrupt);
}

// A failed save must never leave a partial file (or a stray temporary) where the engine will look.
TEST(LevelFile, WriteIsAtomic) {
  TempDir dir;
  const Level level = smallLevel();
  const LevelResult r = saveLevel(dir.file("no_such_dir/level.tpb"), level);
  EXPECT_EQ(r.status, LevelStatus::kWriteFailed);
  EXPECT_FALSE(r.message.empty());
  EXPECT_TRUE(fs::is_empty(dir.path()));
  // An invalid level is refused and the previous good file stays as it was.
  ASSERT_TRUE(saveLevel(dir.file("level.tpb"), level));
  const std::vector<char> before = bytesOf(dir.file("level.tpb"));
  Level broken = level;
  broken.tets[0].v[0] = 1'000'000;
  EXPECT_EQ(saveLevel(dir.file("level.tpb"), broken).status, LevelStatus::kWriteFailed);
  EXPECT_EQ(bytesOf(dir.file("level.tpb")), before);
  EXPECT_EQ(std::distance(fs::directory_iterator(dir.path()), fs::directory_iterator()), 1);
}

// The empty level (no probes) is a legal file: tools write it for levels with no probe volume.
TEST(LevelFile, EmptyLevelRoundTrips) {
  TempDir dir;
  Level empty;
  ASSERT_TRUE(saveLevel(dir.file("empty.tpb"), empty));
  Level back;
  ASSERT_TRUE(loadLevel(dir.file("empty.tpb"), back));
  EXPECT_TRUE(emptyLevel(back));
  EXPECT_EQ(bytesOf(dir.file("empty.tpb")).size(), 80u + 4 * 24 + 4 + 4);  // four empty sections
}

// Optional data a reader does not know (a later tool's section) is skipped; the rest loads unchanged.
TEST(LevelFile, SkipsUnknownOptionalSection) {
  TempDir dir;
  const Level level = smallLevel();
  ASSERT_TRUE(saveLevel(dir.file("full.tpb"), level));
  const std::vector<char> b = withExtraSection(bytesOf(dir.file("full.tpb")), "ZZZZ", 0, "future data");
  writeBytes(dir.file("extra.tpb"), b, b.size());
  Level back;
  const LevelResult r = loadLevel(dir.file("extra.tpb"), back);
  ASSERT_TRUE(r) << r.message;
  EXPECT_EQ(back.tets.size(), level.tets.size());
  EXPECT_EQ(back.cellGrid.nodes.size(), level.cellGrid.nodes.size());
  // Its bytes are still covered by the checksum.
  std::vector<char> bad = b;
  bad[b.size() - 6] ^= 1;
  writeBytes(dir.file("bad.tpb"), bad, bad.size());
  EXPECT_EQ(loadLevel(dir.file("bad.tpb"), back).status, LevelStatus::kCorrupt);
}

// The file with section `from` replaced by section `to` holding `data` (same place in the table), every

// The file as written before SHRH: float SH (SHRG, 108-byte records).
std::vector<char> withFloatShSection(const std::vector<char>& full, const std::vector<ShRgb>& sh) {
  std::string floats(sh.size() * sizeof(ShRgb), '\0');
  std::memcpy(floats.data(), sh.data(), floats.size());  // little-endian f32, as the format stores them
  return withSectionReplaced(full, "SHRH", "SHRG", floats);
}

// The cell grid as written before CGR4 (CGR2: the same 64-byte header and 16-byte slots, 24-byte nodes with
// their float planes).
std::string cellGridWithPlanes(const CellGrid& g) {
  std::string out;
  const auto put = [&out](const auto& v) { out.append(reinterpret_cast<const char*>(&v), sizeof(v)); };
  for (int a = 0; a < 3; ++a) put(g.min[a]);
  put(g.cellSize);
  put(g.maxProbe);
  put(g.maxDepth);
  put(g.meanDepth);
  put(uint64_t(g.leaves));
  put(uint64_t(g.unprovenLeaves));
  put(uint64_t(g.slots.size()));
  put(uint64_t(g.nodes.size()));
  for (const CellSlot& slot : g.slots) {
    for (int32_t k : slot.key) put(k);
    put(slot.root);
  }
  for (const BspNode& node : g.nodes) {
    for (float x : node.plane) put(x);
    for (int32_t c : node.child) put(c);
  }
  return out;
}

// The file as written before TETC: 32-byte tets with their neighbours (TETS), the outer cells (OUTC, 80-byte
// records, appended as the last section) and the grid's nodes with their planes (CGR2).
std::vector<char> withOldTetsAndOuterCells(const std::vector<char>& full, const Level& level) {
  std::string tets(level.tets.size() * sizeof(Tet), '\0');
  std::memcpy(tets.data(), level.tets.data(), tets.size());  // v[4], n[4] little-endian i32, the old record
  std::string cells;  // v[3], tet, n[3], face (i32), normals (3 x 3 f32), 12 bytes of zero padding
  const auto put = [&cells](const void* p, size_t n) { cells.append(static_cast<const char*>(p), n); };
  for (const OuterCell& c : level.outerCells) {
    put(c.v, 12);
    put(&c.tet, 4);
    put(c.n, 12);
    put(&c.face, 4);
    for (const auto& nrm : c.normal) put(nrm, 12);
    cells.append(12, '\0');
  }
  return withExtraSection(withSectionReplaced(withSectionReplaced(full, "TETM", "TETS", tets), "CGR4", "CGR2",
                                              cellGridWithPlanes(level.cellGrid)),
                          "OUTC", 0, cells);
}

// Levels written before TETC (tets with neighbours, and outer cells) still load, as written; their
// neighbours and outer cells are checked as before (walks trust them), and a file with both tet sections is
// refused.
TEST(LevelFile, ReadsOldTetsWithNeighboursAndOuterCells) {
  TempDir dir;
  const Level level = smallLevel();
  ASSERT_TRUE(saveLevel(dir.file("new.tpb"), level));
  const std::vector<char> old = withOldTetsAndOuterCells(bytesOf(dir.file("new.tpb")), level);
  writeBytes(dir.file("old.tpb"), old, old.size());
  Level back;
  const LevelResult r = loadLevel(dir.file("old.tpb"), back);
  ASSERT_TRUE(r) << r.message;
  ASSERT_EQ(back.tets.size(), level.tets.size());
  EXPECT_EQ(std::memcmp(back.tets.data(), level.tets.data(), level.tets.size() * sizeof(Tet)), 0);
  ASSERT_EQ(back.outerCells.size(), level.outerCells.size());
  EXPECT_EQ(std::memcmp(back.outerCells.data(), level.outerCells.data(),
                        level.outerCells.size() * sizeof(OuterCell)),
            0);
  ASSERT_EQ(back.cellGrid.nodes.size(), level.cellGrid.nodes.size());
  EXPECT_EQ(std::memcmp(back.cellGrid.nodes.data(), level.cellGrid.nodes.data(),
                        level.cellGrid.nodes.size() * sizeof(BspNode)),
            0);
  // Saved again: the compact form, the same bytes as the level's own save.
  ASSERT_TRUE(saveLevel(dir.file("again.tpb"), Level(back)));
  Level again;
  ASSERT_TRUE(loadLevel(dir.file("again.tpb"), again));
  EXPECT_EQ(std::memcmp(again.tets.data(), level.tets.data(), level.tets.size() * sizeof(Tet)), 0);

  const size_t tets = sectionOffset(old, "TETS"), outer = sectionOffset(old, "OUTC");
  const struct {
    size_t offset;
    uint32_t value;
    const char* needle;
  } cases[] = {{tets + 16, uint32_t(level.tets.size()), "out of range"},         // tet 0 neighbour 0
               {tets + 16, 0u, "out of range"},                                  // tet 0 its own neighbour
               {outer + 12, uint32_t(level.tets.size()), "out of range"},        // outer cell 0's tet
               {outer + 16, uint32_t(level.outerCells.size()), "out of range"},  // outer cell 0's link 0
               {outer + 0, uint32_t(level.probes.size() + 3), "not a vertex"},   // outer cell 0's probe 0
               {outer + 32, 0x7FC00000u, "not a unit vector"},                   // outer cell 0's normal: NaN
               {outer + 76, 1u, "padding"}};
  for (const auto& c : cases) {
    std::vector<char> b = old;
    putU32(b, c.offset, c.value);
    fixPayloadCrc(b);
    writeBytes(dir.file("forged.tpb"), b, b.size());
    Level out;
    const LevelResult f = loadLevel(dir.file("forged.tpb"), out);
    EXPECT_EQ(f.status, LevelStatus::kCorrupt) << f.message;
    EXPECT_NE(f.message.find(c.needle), std::string::npos) << f.message;
    EXPECT_TRUE(emptyLevel(out));
  }
  std::string tetData(level.tets.size() * sizeof(Tet), '\0');
  std::memcpy(tetData.data(), level.tets.data(), tetData.size());
  const std::vector<char> both = withExtraSection(bytesOf(dir.file("new.tpb")), "TETS", 1, tetData);
  writeBytes(dir.file("both.tpb"), both, both.size());
  const LevelResult b = loadLevel(dir.file("both.tpb"), back);
  EXPECT_EQ(b.status, LevelStatus::kCorrupt);
  EXPECT_NE(b.message.find("more than one of the TETS, TETC and TETM"), std::string::npos) << b.message;
}

// saveLevel writes SH in half precision (SHRH, 56 bytes a probe); levels written before, with float SH
// (SHRG), still load, bit for bit as written; a file holding both is refused.
TEST(LevelFile, ReadsOldFloatShAndRefusesBothShSections) {
  TempDir dir;
  Level level = smallLevel();
  ASSERT_TRUE(saveLevel(dir.file("half.tpb"), level));
  std::vector<ShRgb> floats = level.sh;
  for (ShRgb& s : floats) s.c[2].y += 1e-5f * s.c[0].x + 3e-7f;  // values no half record holds
  const std::vector<char> old = withFloatShSection(bytesOf(dir.file("half.tpb")), floats);
  writeBytes(dir.file("old.tpb"), old, old.size());
  Level back;
  const LevelResult r = loadLevel(dir.file("old.tpb"), back);
  ASSERT_TRUE(r) << r.message;
  ASSERT_EQ(back.sh.size(), floats.size());
  EXPECT_EQ(std::memcmp(back.sh.data(), floats.data(), floats.size() * sizeof(ShRgb)), 0);
  EXPECT_EQ(back.tets.size(), level.tets.size());
  // Saved again, the level is written in half precision: the quantized floats.
  ASSERT_TRUE(saveLevel(dir.file("again.tpb"), back));
  Level again;
  ASSERT_TRUE(loadLevel(dir.file("again.tpb"), again));
  for (size_t p = 0; p < floats.size(); ++p) {
    const ShRgb want = quantizeSh(floats[p]);
    EXPECT_EQ(std::memcmp(&again.sh[p], &want, sizeof(ShRgb)), 0) << p;
  }
  std::string shData(level.sh.size() * sizeof(ShRgb), '\0');
  std::memcpy(shData.data(), level.sh.data(), shData.size());
  const std::vector<char> both = withExtraSection(bytesOf(dir.file("half.tpb")), "SHRG", 1, shData);
  writeBytes(dir.file("both.tpb"), both, both.size());
  const LevelResult b = loadLevel(dir.file("both.tpb"), back);
  EXPECT_EQ(b.status, LevelStatus::kCorrupt);
  EXPECT_NE(b.message.find("SHRG and SHRH"), std::string::npos) << b.message;
}

// An SH coefficient beyond what a half-precision record holds (2.1e9 W/(m^2 sr)) is refused at save with a
// message naming the probe, and nothing is written.
TEST(LevelFile, RefusesShBeyondHalfPrecisionRange) {
  TempDir dir;
  Level level = smallLevel();
  level.sh[3].c[0].x = 3e9f;
  const LevelResult r = saveLevel(dir.file("huge.tpb"), level);
  EXPECT_FALSE(r);
  EXPECT_NE(r.message.find("probe 3"), std::string::npos) << r.message;
  EXPECT_FALSE(fs::exists(dir.file("huge.tpb")));
  level.sh[3].c[0].x = 2e9f;  // within range
  EXPECT_TRUE(saveLevel(dir.file("big.tpb"), level));
}

// Levels written before leaves named one tet carry the retired CGRD section (leaves listing up to 8 tets),
// and levels of session 14 the retired CGR3 (12-byte nodes): each is skipped like any unknown optional
// section, and the query builds the grid itself, answering as a level that stores one.
TEST(LevelFile, RetiredCellGridSectionIsSkippedAndRebuilt) {
  for (const char* retired : {"CGRD", "CGR3"}) {
    TempDir dir;
    Level level = smallLevel();
    const Level stored = level;
    level.cellGrid = CellGrid{};
    ASSERT_TRUE(saveLevel(dir.file("bare.tpb"), level));
    const std::vector<char> b =
        withExtraSection(bytesOf(dir.file("bare.tpb")), retired, 0, std::string(64 + 16 * 16, '\x01'));
    writeBytes(dir.file("old.tpb"), b, b.size());
    Level back;
    const LevelResult r = loadLevel(dir.file("old.tpb"), back);
    ASSERT_TRUE(r) << r.message;
    EXPECT_TRUE(back.cellGrid.slots.empty());
    const ProbeQuery rebuilt(back, 2.0f, 1), fromFile(stored, 2.0f, 1);
    EXPECT_EQ(rebuilt.cellGrid().nodes.size(), stored.cellGrid.nodes.size());
    for (int k = 0; k < 200; ++k) {
      const glm::dvec3 x = back.origin + glm::dvec3(-2.5 + 0.025 * k, 0.3 - 0.004 * k, -3.2 + 0.032 * k);
      const Location a = rebuilt.locate(x), c = fromFile.locate(x);
      EXPECT_EQ(a.tet, c.tet);
      EXPECT_EQ(a.weights, c.weights);
    }
  }
}

// saveLevel packs the grid's nodes (CGR4) only when every node's plane is a tet face's bit for bit; a grid
// built some other way (here: one plane nudged by an ulp) is written with its planes (CGR2, the format of
// earlier levels), which still loads bit for bit. A file with both is refused.
TEST(LevelFile, GridNotCutFromTetFacesIsWrittenWithItsPlanes) {
  TempDir dir;
  Level level = smallLevel();
  ASSERT_FALSE(level.cellGrid.nodes.empty());
  float& w = level.cellGrid.nodes.back().plane[3];
  w = std::nextafter(w, 1e30f);
  ASSERT_TRUE(saveLevel(dir.file("planes.tpb"), level));
  const std::vector<char> full = bytesOf(dir.file("planes.tpb"));
  EXPECT_NE(sectionOffset(full, "CGR2"), 0u);
  Level back;
  const LevelResult r = loadLevel(dir.file("planes.tpb"), back);
  ASSERT_TRUE(r) << r.message;
  ASSERT_EQ(back.cellGrid.nodes.size(), level.cellGrid.nodes.size());
  EXPECT_EQ(std::memcmp(back.cellGrid.nodes.data(), level.cellGrid.nodes.data(),
                        level.cellGrid.nodes.size() * sizeof(BspNode)),
            0);

  expectRefusedAsCorrupt(dir, withExtraSection(full, "CGR4", 0, std::string(64, '\0')), "both CGR2 and CGR4");
}

// LEB128, as the CGR4 node stream stores its numbers (runtime/src/bsp_codec.h), to forge streams.
std::string varint(uint64_t v) {
  std::string out;
  for (; v >= 0x80; v >>= 7) out.push_back(char(uint8_t(v) | 0x80));
  out.push_back(char(uint8_t(v)));
  return out;
}
uint64_t zigzag(int64_t v) {
  return v < 0 ? (uint64_t(-(v + 1)) << 1) | 1u : uint64_t(v) << 1;
}

// The grid's node renumbered breadth first in each tree: the same trees (children still after their
// parents, the same answer everywhere), but not the preorder buildCellGrid lays out.
CellGrid breadthFirst(const CellGrid& g) {
  CellGrid out = g;
  std::vector<int32_t> order, newIndex(g.nodes.size(), -1);
  std::vector<int32_t> roots;
  for (size_t n = 0; n < g.nodes.size(); ++n) {
    bool isChild = false;  // a root: no node names it (trees are laid out one after another)
    for (size_t m = 0; m < n && !isChild; ++m)
      isChild = g.nodes[m].child[0] == int32_t(n) || g.nodes[m].child[1] == int32_t(n);
    if (!isChild) roots.push_back(int32_t(n));
  }
  for (int32_t root : roots) {
    const size_t begin = order.size();
    order.push_back(root);
    for (size_t i = begin; i < order.size(); ++i)
      for (int32_t c : g.nodes[size_t(order[i])].child)
        if (c >= 0) order.push_back(c);
  }
  for (size_t i = 0; i < order.size(); ++i) newIndex[size_t(order[i])] = int32_t(i);
  for (size_t i = 0; i < order.size(); ++i) {
    out.nodes[i] = g.nodes[size_t(order[i])];
    for (int32_t& c : out.nodes[i].child)
      if (c >= 0) c = newIndex[size_t(c)];
  }
  for (CellSlot& slot : out.slots)
    if (slot.key[0] != INT32_MIN && slot.root >= 0) slot.root = newIndex[size_t(slot.root)];
  return out;
}

// The packed node stream (CGR4) codes each leaf as its node's face tet, the tet across that face, an explicit
// tet or the empty leaf, and each node child by position in preorder. Over levels of several shapes and
// grids (cell sizes, one-tet and default leaves) every kind occurs, and every grid comes back bit for bit.
TEST(LevelFile, PackedGridNodesRoundTripEveryLeafKind) {
  TempDir dir;
  size_t kinds[4] = {0, 0, 0, 0};  // face tet, across the face, other tet, empty
  int grids = 0;
  for (bool corners : {true, false})
    for (float cellSize : {1.0f, 4.0f})
      for (int leafTets : {1, kDefaultLeafTets}) {
        Level level = test::makeLevel(test::randomBoxPoints(150, 11, {-3, -2, -3}, {3, 2, 3}, corners),
                                      {-7.5, 3.25, 120.0}, 4);
        level.cellGrid = buildCellGrid(level.probes, level.tets, cellSize, 2, leafTets);
        const CellGrid& g = level.cellGrid;
        ASSERT_TRUE(saveLevel(dir.file("g.tpb"), level));
        Level back;
        const LevelResult r = loadLevel(dir.file("g.tpb"), back);
        ASSERT_TRUE(r) << r.message;
        EXPECT_NE(sectionOffset(bytesOf(dir.file("g.tpb")), "CGR4"), 0u);
        ASSERT_EQ(back.cellGrid.nodes.size(), g.nodes.size());
        EXPECT_EQ(std::memcmp(back.cellGrid.nodes.data(), g.nodes.data(), g.nodes.size() * sizeof(BspNode)),
                  0);
        ASSERT_EQ(back.cellGrid.slots.size(), g.slots.size());
        EXPECT_EQ(std::memcmp(back.cellGrid.slots.data(), g.slots.data(), g.slots.size() * sizeof(CellSlot)),
                  0);
        ++grids;
        // Each leaf's kind: the node's face is the first tet face whose float plane is the node's bit for
        // bit (back.tets carry the neighbours the loader derived).
        std::map<std::array<uint32_t, 4>, std::pair<int32_t, int>> faceOf;
        for (size_t t = 0; t < back.tets.size(); ++t) {
          glm::vec3 c[4];
          for (int i = 0; i < 4; ++i) c[i] = back.probes[size_t(back.tets[t].v[i])];
          for (int f = 0; f < 4; ++f) {
            std::array<uint32_t, 4> key;
            if (cellGridFacePlane(c, f, reinterpret_cast<float*>(key.data())))
              faceOf.emplace(key, std::make_pair(int32_t(t), f));
          }
        }
        for (const BspNode& node : g.nodes) {
          std::array<uint32_t, 4> key;
          std::memcpy(key.data(), node.plane, sizeof node.plane);
          const auto it = faceOf.find(key);
          ASSERT_NE(it, faceOf.end());
          const auto [faceTet, face] = it->second;
          for (int32_t child : node.child) {
            if (child >= 0) continue;
            const int32_t leaf = bspLeafTet(child);
            ++kinds[leaf < 0 ? 3 : leaf == faceTet ? 0 : leaf == back.tets[size_t(faceTet)].n[face] ? 1 : 2];
          }
        }
      }
  EXPECT_EQ(grids, 8);
  for (int k = 0; k < 4; ++k) EXPECT_GT(kinds[k], 0u) << "leaf kind " << k;
}

// The stream holds no node indices: it can only describe preorder trees. A grid laid out otherwise (here the
// same trees breadth first) is written with its planes and indices (CGR2) and loads bit for bit.
TEST(LevelFile, GridNotInPreorderIsWrittenWithItsPlanes) {
  TempDir dir;
  Level level = test::makeLevel(test::randomBoxPoints(150, 11, {-3, -2, -3}, {3, 2, 3}), {0, 0, 0}, 4);
  level.cellGrid = breadthFirst(buildCellGrid(level.probes, level.tets, 4.0f, 1));
  const CellGrid& g = level.cellGrid;
  ASSERT_TRUE(saveLevel(dir.file("bfs.tpb"), level));
  EXPECT_NE(sectionOffset(bytesOf(dir.file("bfs.tpb")), "CGR2"), 0u);
  Level back;
  const LevelResult r = loadLevel(dir.file("bfs.tpb"), back);
  ASSERT_TRUE(r) << r.message;
  ASSERT_EQ(back.cellGrid.nodes.size(), g.nodes.size());
  EXPECT_EQ(std::memcmp(back.cellGrid.nodes.data(), g.nodes.data(), g.nodes.size() * sizeof(BspNode)), 0);
  // The same point answers from the renumbered grid as from the built one.
  const CellGrid built = buildCellGrid(level.probes, level.tets, 4.0f, 1);
  EXPECT_NE(std::memcmp(built.nodes.data(), g.nodes.data(), g.nodes.size() * sizeof(BspNode)), 0);
  for (const glm::dvec3& x : test::randomBoxPoints(500, 5, {-3.5, -2.5, -3.5}, {3.5, 2.5, 3.5}, false))
    EXPECT_EQ(cellGridLeaf(back.cellGrid, x), cellGridLeaf(built, x));
}

// A forged node stream with valid checksums is refused with a message naming what is wrong, whatever part of
// a varint it breaks: a face of a missing tet, a leaf across a hull face, an explicit leaf past the last tet,
// an overlong varint, a stream cut short or with bytes left over, more nodes than bytes, a tree left open.
TEST(LevelFile, RejectsForgedGridNodeStreams) {
  TempDir dir;
  ASSERT_TRUE(saveLevel(dir.file("full.tpb"), smallLevel()));
  const std::vector<char> full = bytesOf(dir.file("full.tpb"));
  Level level;
  ASSERT_TRUE(loadLevel(dir.file("full.tpb"), level));  // with the neighbours the loader derives
  ASSERT_FALSE(level.cellGrid.nodes.empty());
  const size_t grid = sectionOffset(full, "CGR4"), size = sectionSize(full, "CGR4");
  const size_t fixed = 64 + 16 * level.cellGrid.slots.size();
  const std::string head(full.begin() + long(grid), full.begin() + long(grid + fixed)),
      stream(full.begin() + long(grid + fixed), full.begin() + long(grid + size));
  const uint64_t tetCount = level.tets.size();
  int32_t hullTet = -1, hullFace = -1;
  for (size_t t = 0; t < level.tets.size() && hullTet < 0; ++t)
    for (int f = 0; f < 4 && hullTet < 0; ++f)
      if (level.tets[t].n[f] < 0) {
        hullTet = int32_t(t);
        hullFace = f;
      }
  ASSERT_GE(hullTet, 0);
  // The section with `nodes` nodes and stream `s`.
  const auto section = [&](uint64_t nodes, const std::string& s) {
    std::string b = head;
    for (int i = 0; i < 8; ++i) b[56 + size_t(i)] = char(uint8_t(nodes >> (8 * i)));
    return withSectionReplaced(full, "CGR4", "CGR4", b + s);
  };
  const uint64_t n = level.cellGrid.nodes.size();
  const auto leafLeaf = [](int64_t delta, int face, uint32_t c0, uint32_t c1) {
    return varint(zigzag(delta) << 6 | uint64_t(face) << 4 | c0 << 2 | c1);
  };
  expectRefusedAsCorrupt(dir, section(1, leafLeaf(int64_t(tetCount), 0, 1, 1)), "names a tet past the last");
  expectRefusedAsCorrupt(dir, section(1, leafLeaf(-1, 0, 1, 1)), "names a tet past the last");
  expectRefusedAsCorrupt(dir, section(1, leafLeaf(hullTet, hullFace, 1, 2)), "a hull face");
  expectRefusedAsCorrupt(dir, section(1, leafLeaf(0, 0, 3, 1) + varint(zigzag(int64_t(tetCount)) + 1)),
                         "a leaf naming a tet past the last");
  expectRefusedAsCorrupt(dir, section(1, std::string(11, char(0xFF)) + '\0'), "overlong");
  expectRefusedAsCorrupt(dir, section(1, leafLeaf(0, 0, 3, 1)), "truncated");
  expectRefusedAsCorrupt(dir, section(1, leafLeaf(0, 0, 0, 1)), "stream ends inside a tree");
  expectRefusedAsCorrupt(dir, section(n, stream + '\0'), "after the last node");
  expectRefusedAsCorrupt(dir, section(n, stream.substr(0, stream.size() - 1)), "truncated");
  expectRefusedAsCorrupt(dir, section(stream.size() + 1, stream), "size does not match");  // > a byte a node
  // The untouched stream through the same path still loads: the forgeries, not the helper, are refused.
  writeBytes(dir.file("same.tpb"), section(n, stream), full.size());
  Level same;
  EXPECT_TRUE(loadLevel(dir.file("same.tpb"), same));
}

// A forged packed tet stream (TETM) with valid checksums is refused, naming the tet and what is wrong: a
// list position not yet filled, a probe out of range or twice in one tet, an overlong varint, a stream cut
// short or with bytes left over, fewer bytes than two a tet; and a file with two tet sections.
TEST(LevelFile, RejectsForgedTetStreams) {
  TempDir dir;
  const Level level = smallLevel();
  ASSERT_TRUE(saveLevel(dir.file("full.tpb"), level));
  const std::vector<char> full = bytesOf(dir.file("full.tpb"));
  const size_t at = sectionOffset(full, "TETM"), size = sectionSize(full, "TETM");
  const std::string stream(full.begin() + long(at), full.begin() + long(at + size));
  // Tet 0 as `head`, the rest of the section zeros (never read: the error comes first).
  const auto first = [&](const std::string& head) {
    std::string b = head;
    b.resize(std::max(size, head.size()), '\0');
    return withSectionReplaced(full, "TETM", "TETM", b);
  };
  const std::string given4 = "\xFF\xFF";  // four vertices given by varints
  const uint64_t P = level.probes.size();
  expectRefusedAsCorrupt(dir, first(std::string(2, '\0')), "tet 0: names recent probe 0 of 0");
  expectRefusedAsCorrupt(dir, first(given4 + varint(zigzag(int64_t(P)))), "tet 0: vertex out of range");
  expectRefusedAsCorrupt(dir, first(given4 + varint(zigzag(-1))), "tet 0: vertex out of range");
  expectRefusedAsCorrupt(dir, first(std::string("\x0F\xFF", 2) + varint(0)), "tet 0: vertex 0 repeated");
  expectRefusedAsCorrupt(dir, first(given4 + std::string(11, char(0xFF))), "tet 0: truncated or overlong");
  expectRefusedAsCorrupt(dir, withSectionReplaced(full, "TETM", "TETM", stream + '\0'), "after the last tet");
  expectRefusedAsCorrupt(dir, withSectionReplaced(full, "TETM", "TETM", stream.substr(0, stream.size() - 1)),
                         "truncated");
  expectRefusedAsCorrupt(
      dir, withSectionReplaced(full, "TETM", "TETM", std::string(2 * level.tets.size() - 1, '\0')),
      "need at least");
  std::string records(8 * level.tets.size(), '\0');
  expectRefusedAsCorrupt(dir, withExtraSection(full, "TETC", 1, records),
                         "more than one of the TETS, TETC and TETM");
  // The untouched stream through the same path still loads.
  const std::vector<char> same = withSectionReplaced(full, "TETM", "TETM", stream);
  writeBytes(dir.file("same.tpb"), same, same.size());
  Level back;
  EXPECT_TRUE(loadLevel(dir.file("same.tpb"), back));
}

// A section flagged as required that this reader does not know must not be ignored.
TEST(LevelFile, RefusesUnknownRequiredSection) {
  TempDir dir;
  ASSERT_TRUE(saveLevel(dir.file("full.tpb"), smallLevel()));
  const std::vector<char> b = withExtraSection(bytesOf(dir.file("full.tpb")), "ZZZZ", 1, "must understand");
  writeBytes(dir.file("req.tpb"), b, b.size());
  Level out;
  EXPECT_EQ(loadLevel(dir.file("req.tpb"), out).status, LevelStatus::kUnsupportedVersion);
  EXPECT_TRUE(emptyLevel(out));
  // A second copy of a known section is corrupt, not silently preferred.
  const std::vector<char> twice = withExtraSection(bytesOf(dir.file("full.tpb")), "GENR", 1, "");
  writeBytes(dir.file("twice.tpb"), twice, twice.size());
  EXPECT_EQ(loadLevel(dir.file("twice.tpb"), out).status, LevelStatus::kCorrupt);
}

// Outer cells are never stored (a function of the tets): a level saved with or without them loads without
// them and answers outside the hull from outer cells the query builds itself, the ones the bake built.
TEST(LevelFile, OuterCellsOptional) {
  TempDir dir;
  Level level = smallLevel();
  const std::vector<OuterCell> cells = level.outerCells;
  level.outerCells.clear();
  ASSERT_TRUE(saveLevel(dir.file("bare.tpb"), level));
  Level back;
  ASSERT_TRUE(loadLevel(dir.file("bare.tpb"), back));
  EXPECT_TRUE(back.outerCells.empty());
  const ProbeQuery q(back);
  ASSERT_EQ(q.outerCells().size(), cells.size());
  EXPECT_EQ(std::memcmp(q.outerCells().data(), cells.data(), cells.size() * sizeof(OuterCell)), 0);
}

// A synthetic occlusion for `level`: kinds cycle none, planes (1..3), shadow maps; packed as the builder
// packs.
LevelOcclusion syntheticOcclusion(const Level& level) {
  LevelOcclusion occ;
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> u(-1.0f, 1.0f);
  for (size_t t = 0; t < level.tets.size(); ++t) {
    const size_t kind = t % 5;
    if (kind == 0) {
      occ.tets.push_back({});
    } else if (kind <= 3) {
      const uint32_t count = uint32_t(kind);
      uint32_t cells = 0;
      for (uint32_t c = 0; c < (1u << count); ++c) cells |= (uint32_t(rng()) & 15u) << (4 * c);
      occ.tets.push_back(makeTetOcclusion(kOcclusionPlanes, count, uint32_t(occ.planes.size()), cells));
      for (uint32_t k = 0; k < count; ++k) {
        const double a = u(rng), b = u(rng), c = u(rng);
        occ.planes.push_back(makeOcclusionPlane(a, b, c, 1.0));
      }
    } else {
      occ.tets.push_back(makeTetOcclusion(kOcclusionShadowMaps, 0,
                                          uint32_t(occ.shadowMaps.size() / kShadowMapBlockBytes), 0));
      for (int b = 0; b < kShadowMapBlockBytes; ++b) occ.shadowMaps.push_back(uint8_t(rng()));
    }
  }
  return occ;
}

// The same occlusion with tets 1 and 6 (one plane each) swapping where their planes are stored: valid, but
// not in the order the packed section (OCC2) implies, so saveLevel keeps the records as they are (OCCL).
LevelOcclusion unorderedOcclusion(const Level& level) {
  LevelOcclusion occ = syntheticOcclusion(level);
  TetOcclusion &a = occ.tets[1], &b = occ.tets[6];
  EXPECT_EQ(a.planeCount(), 1u);
  EXPECT_EQ(b.planeCount(), 1u);
  std::swap(occ.planes[a.offset()], occ.planes[b.offset()]);
  const uint32_t offsetA = a.offset();
  a = makeTetOcclusion(kOcclusionPlanes, 1, b.offset(), a.cells);
  b = makeTetOcclusion(kOcclusionPlanes, 1, offsetA, b.cells);
  return occ;
}

// Cell-mask bytes of the packed section: 2^count x 4 bits per plane tet.
uint64_t packedCellBytes(const LevelOcclusion& occ) {
  uint64_t n = 0;
  for (const TetOcclusion& rec : occ.tets)
    if (rec.kind() == kOcclusionPlanes) n += uint64_t(1) << (rec.planeCount() - 1);
  return n;
}

TEST(LevelFile, OcclusionRoundTripsAndEmptyWritesNoSection) {
  TempDir dir;
  Level level = smallLevel();
  ASSERT_TRUE(saveLevel(dir.file("none.tpb"), level));
  level.occlusion = syntheticOcclusion(level);
  ASSERT_FALSE(level.occlusion.planes.empty());
  ASSERT_FALSE(level.occlusion.shadowMaps.empty());
  ASSERT_TRUE(saveLevel(dir.file("occ.tpb"), level));
  Level back;
  const LevelResult r = loadLevel(dir.file("occ.tpb"), back);
  ASSERT_TRUE(r) << r.message;
  const LevelOcclusion &a = level.occlusion, &b = back.occlusion;
  ASSERT_EQ(b.tets.size(), a.tets.size());
  ASSERT_EQ(b.planes.size(), a.planes.size());
  EXPECT_EQ(std::memcmp(b.tets.data(), a.tets.data(), a.tets.size() * sizeof(TetOcclusion)), 0);
  EXPECT_EQ(std::memcmp(b.planes.data(), a.planes.data(), a.planes.size() * sizeof(OcclusionPlane)), 0);
  EXPECT_EQ(b.shadowMaps, a.shadowMaps);
  ASSERT_TRUE(saveLevel(dir.file("again.tpb"), back));
  const std::vector<char> occBytes = bytesOf(dir.file("occ.tpb"));
  EXPECT_EQ(occBytes, bytesOf(dir.file("again.tpb")));
  // One more section (OCC2): 24-byte table entry, 32-byte counts, a code byte per tet, the plane tets' cell
  // masks (1, 2 or 4 bytes), 8 per plane, 64 per shadow-map block.
  EXPECT_NE(sectionOffset(occBytes, "OCC2"), 0u);
  EXPECT_EQ(occBytes.size(), bytesOf(dir.file("none.tpb")).size() + 24 + 32 + a.tets.size() +
                                 packedCellBytes(a) + 8 * a.planes.size() + a.shadowMaps.size());
  // Records whose offsets are not in tet order keep them: the fixed 8-byte records (OCCL), read back as they
  // were.
  level.occlusion = unorderedOcclusion(level);
  ASSERT_TRUE(saveLevel(dir.file("fixed.tpb"), level));
  const std::vector<char> fixedBytes = bytesOf(dir.file("fixed.tpb"));
  EXPECT_NE(sectionOffset(fixedBytes, "OCCL"), 0u);
  EXPECT_EQ(fixedBytes.size(), bytesOf(dir.file("none.tpb")).size() + 24 + 24 + 8 * a.tets.size() +
                                   8 * a.planes.size() + a.shadowMaps.size());
  Level fixedBack;
  ASSERT_TRUE(loadLevel(dir.file("fixed.tpb"), fixedBack));
  EXPECT_EQ(std::memcmp(fixedBack.occlusion.tets.data(), level.occlusion.tets.data(),
                        a.tets.size() * sizeof(TetOcclusion)),
            0);
  EXPECT_EQ(std::memcmp(fixedBack.occlusion.planes.data(), level.occlusion.planes.data(),
                        a.planes.size() * sizeof(OcclusionPlane)),
            0);
  // Dropping it again gives the bytes of a level that never had any.
  back.occlusion = {};
  ASSERT_TRUE(saveLevel(dir.file("dropped.tpb"), back));
  EXPECT_EQ(bytesOf(dir.file("dropped.tpb")), bytesOf(dir.file("none.tpb")));
}

TEST(LevelFile, RejectsInconsistentOcclusion) {
  TempDir dir;
  Level level = smallLevel();
  level.occlusion = syntheticOcclusion(level);
  {  // in memory: the writer refuses
    Level bad = level;
    bad.occlusion.tets.pop_back();
    EXPECT_FALSE(validateLevel(bad));
    EXPECT_FALSE(saveLevel(dir.file("bad.tpb"), bad));
    bad = level;
    bad.occlusion.shadowMaps.pop_back();
    EXPECT_FALSE(validateLevel(bad));
    bad = level;
    bad.occlusion.planes.push_back({});
    EXPECT_FALSE(validateLevel(bad));
    bad = level;
    bad.occlusion.planes[0] = OcclusionPlane{};  // the zero plane: no plane at all
    EXPECT_FALSE(validateLevel(bad));
  }
  // The fixed records (OCCL): a level whose offsets are not in tet order is written with them.
  level.occlusion = unorderedOcclusion(level);
  ASSERT_TRUE(saveLevel(dir.file("full.tpb"), level));
  const std::vector<char> full = bytesOf(dir.file("full.tpb"));
  const size_t occ = sectionOffset(full, "OCCL"), recs = occ + 24;
  const TetOcclusion& planes1 = level.occlusion.tets[1];  // planes, count 1
  const TetOcclusion& shadow = level.occlusion.tets[4];   // shadow maps
  const struct {
    size_t offset;
    uint32_t value;
    const char* needle;
  } cases[] = {
      {occ + 0, uint32_t(level.tets.size() - 1), "does not match its counts"},  // tet count
      {occ + 16, 0u, "does not match its counts"},                              // shadow-map block count
      {recs + 0, 3u, "unknown kind"},                                           // tet 0: kind 3
      {recs + 4, 1u, "non-zero"},                                               // tet 0: none with cells
      {recs + 8, makeTetOcclusion(kOcclusionPlanes, 1, uint32_t(level.occlusion.planes.size()), 0).header,
       "out of range"},                                        // plane offset
      {recs + 8 + 4, planes1.cells | 0x100u, "out of range"},  // cell 2 of 1 plane
      {recs + 8, makeTetOcclusion(kOcclusionPlanes, 2, planes1.offset(), 0).header, "the records use"},
      {recs + 32, makeTetOcclusion(kOcclusionShadowMaps, 0, 1u << 20, 0).header, "out of range"},
      {recs + 32 + 4, 1u, "out of range"},  // shadow maps with cells
  };
  ASSERT_EQ(shadow.kind(), kOcclusionShadowMaps);
  for (const auto& c : cases) {
    std::vector<char> b = full;
    putU32(b, c.offset, c.value);
    fixPayloadCrc(b);
    writeBytes(dir.file("forged.tpb"), b, b.size());
    Level out;
    const LevelResult r = loadLevel(dir.file("forged.tpb"), out);
    EXPECT_EQ(r.status, LevelStatus::kCorrupt) << r.message;
    EXPECT_NE(r.message.find(c.needle), std::string::npos) << r.message;
    EXPECT_TRUE(emptyLevel(out));
    EXPECT_TRUE(out.occlusion.empty());
  }
  // Every truncation of the occlusion section is reported, never read past.
  for (size_t n = occ; n < full.size(); n += 7) {
    writeBytes(dir.file("short.tpb"), full, n);
    Level out;
    EXPECT_FALSE(loadLevel(dir.file("short.tpb"), out));
  }

  // The packed section (OCC2): counts, then a code byte per tet (kind | plane count << 2), then cell masks.
  level.occlusion = syntheticOcclusion(level);
  ASSERT_TRUE(saveLevel(dir.file("packed.tpb"), level));
  const std::vector<char> packed = bytesOf(dir.file("packed.tpb"));
  const size_t occ2 = sectionOffset(packed, "OCC2"), codes = occ2 + 32;
  const uint64_t cellBytes = packedCellBytes(level.occlusion);
  const char* const counts = "does not match its counts";
  const char* const overrun = "past the section's counts";
  const struct {
    size_t offset;
    uint8_t value;
    const char* needle;
  } packedCases[] = {
      {occ2 + 0, uint8_t(level.tets.size() - 1), counts},  // tet count (below 256: the low byte)
      {occ2 + 16, 0, counts},                              // shadow-map block count
      {occ2 + 24, uint8_t(cellBytes + 1), counts},         // cell-mask bytes (below 255)
      {codes + 0, 3, "unknown code"},                      // tet 0: kind 3
      {codes + 0, 0x10, "unknown code"},                   // tet 0: bits above the plane count
      {codes + 1, 1, "unknown code"},                      // tet 1: planes, count 0
      {codes + 4, 2 | 1 << 2, "unknown code"},             // tet 4: shadow maps with a plane count
      {codes + 4, 0, "the records use"},                   // tet 4: its block left unused
      {codes + 0, 1 | 3 << 2, "the records use"},          // tet 0: three more planes than counted
  };
  ASSERT_LT(level.tets.size(), 256u);
  ASSERT_LT(cellBytes, 255u);
  for (const auto& c : packedCases) {
    std::vector<char> b = packed;
    b[c.offset] = char(c.value);
    fixPayloadCrc(b);
    writeBytes(dir.file("forged.tpb"), b, b.size());
    Level out;
    const LevelResult r = loadLevel(dir.file("forged.tpb"), out);
    EXPECT_EQ(r.status, LevelStatus::kCorrupt) << r.message;
    const bool named = r.message.find(c.needle) != std::string::npos ||
                       (c.needle != counts && r.message.find(overrun) != std::string::npos);
    EXPECT_TRUE(named) << c.needle << ": " << r.message;
    EXPECT_TRUE(emptyLevel(out));
    EXPECT_TRUE(out.occlusion.empty());
  }
  expectRefusedAsCorrupt(dir, withExtraSection(full, "OCC2", 0, std::string(32, '\0')), "both OCCL and OCC2");
}

}  // namespace
}  // namespace tetraprobe

namespace tetraprobe {
namespace {

// Probe kinds ride in their own optional section: they round-trip, a level without them writes no section
// (its bytes are those of a level from before the section existed), the section costs one byte a probe,
// and a count or value out of range is refused.
TEST(LevelFile, ProbeKindsRoundTripAndAbsentWritesNoSection) {
  TempDir dir;
  Level level = smallLevel();
  ASSERT_TRUE(saveLevel(dir.file("none.tpb"), level));
  for (size_t i = 0; i < level.probes.size(); ++i)
    level.probeKinds.push_back(LevelProbeKind(uint8_t(i % kLevelProbeKindCount)));
  ASSERT_TRUE(saveLevel(dir.file("kinds.tpb"), level));
  Level back;
  const LevelResult r = loadLevel(dir.file("kinds.tpb"), back);
  ASSERT_TRUE(r) << r.message;
  EXPECT_EQ(back.probeKinds, level.probeKinds);
  EXPECT_EQ(bytesOf(dir.file("kinds.tpb")).size(),
            bytesOf(dir.file("none.tpb")).size() + 24 + level.probes.size());
  back.probeKinds.clear();
  ASSERT_TRUE(saveLevel(dir.file("dropped.tpb"), back));
  EXPECT_EQ(bytesOf(dir.file("dropped.tpb")), bytesOf(dir.file("none.tpb")));
  Level old;
  ASSERT_TRUE(loadLevel(dir.file("none.tpb"), old));
  EXPECT_TRUE(old.probeKinds.empty());

  Level bad = level;
  bad.probeKinds.pop_back();
  EXPECT_FALSE(validateLevel(bad));
  bad = level;
  bad.probeKinds[0] = LevelProbeKind(uint8_t(kLevelProbeKindCount));
  EXPECT_FALSE(validateLevel(bad));
  EXPECT_FALSE(saveLevel(dir.file("bad.tpb"), bad));
}

}  // namespace
}  // namespace tetraprobe
