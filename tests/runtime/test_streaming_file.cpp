// A streamed level file (section STRM) read by StreamingLevel and by loadLevel through the one header and
// table parser (level_file.h): they refuse the same framing with the same message, an older version naming
// both versions; opening reads the framing and the index, not the file; a sector's bytes are checked by
// their own CRC when the sector is loaded.
#include <gtest/gtest.h>

#include <unistd.h>

#include <cstring>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "../cli/level_bytes.h"  // little-endian fields of a level file
#include "test_levels.h"
#include "tetraprobe/runtime/cell_grid.h"
#include "tetraprobe/runtime/crc32.h"
#include "tetraprobe/runtime/file_io.h"
#include "tetraprobe/runtime/level.h"
#include "tetraprobe/runtime/level_file.h"
#include "tetraprobe/runtime/streaming.h"
#include "tetraprobe/tetra/stream_index.h"

namespace tetraprobe {
namespace {

namespace fs = std::filesystem;
using test::Bytes;
using test::getU32;
using test::getU64;
using test::putU32;

class StreamingFile : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("tetraprobe_streaming_file_" + std::to_string(::getpid()));
    fs::create_directories(dir_);
    // 300 probes in a 12 m box, 4 m cells: a few dozen sectors; tet 0 carries one occlusion plane.
    level_ = test::makeLevel(test::randomBoxPoints(300, 5, {-6, -4, -6}, {6, 4, 6}), {10.0, 0.0, -3.0}, 2);
    level_.cellGrid = buildCellGrid(level_.probes, level_.tets, 4.0f, 1);
    level_.occlusion.tets.assign(level_.tets.size(), TetOcclusion{});
    level_.occlusion.tets[0] = makeTetOcclusion(kOcclusionPlanes, 1, 0, 1);
    level_.occlusion.planes.push_back(OcclusionPlane{{12000, -3000, 500, 7}});
    StreamIndexOptions options;
    options.coarseSpacing = 6.0;
    level_.stream = buildStreamIndex(level_, options);
    ASSERT_TRUE(saveLevel(path("streamed.tpb"), level_));
    bytes_ = read(path("streamed.tpb"));
  }
  void TearDown() override { fs::remove_all(dir_); }

  std::string path(const std::string& name) const { return (dir_ / name).string(); }
  static Bytes read(const std::string& p) {
    std::vector<char> b;
    std::string error;
    EXPECT_TRUE(readFile(p, b, &error)) << error;
    return Bytes(b.begin(), b.end());
  }
  std::string write(const std::string& name, const Bytes& b) const {
    std::ofstream(path(name), std::ios::binary)
        .write(reinterpret_cast<const char*>(b.data()), std::streamsize(b.size()));
    return path(name);
  }
  // The table entry (its byte offset) of the section tagged `tag`.
  static size_t entry(const Bytes& b, const char (&tag)[5]) {
    for (uint32_t i = 0; i < getU32(b, 72); ++i)
      if (getU32(b, 80 + 24 * size_t(i)) == levelTag(tag)) return 80 + 24 * size_t(i);
    ADD_FAILURE() << "no section " << tag;
    return 0;
  }

  fs::path dir_;
  Level level_;
  Bytes bytes_;
};

// Both loaders give `bytes` the same status; for the framing (which they parse with the same code) the
// same message too.
void expectBothRefuse(const std::string& file, LevelStatus status, const char* needle) {
  Level whole;
  const LevelResult a = loadLevel(file, whole);
  StreamingLevel st;
  const LevelResult b = st.open(file);
  EXPECT_EQ(a.status, status) << a.message;
  EXPECT_EQ(b.status, status) << b.message;
  EXPECT_EQ(a.message, b.message);
  EXPECT_NE(a.message.find(needle), std::string::npos) << a.message;
  EXPECT_TRUE(st.sectors().empty());
}

// Loads each sector alone (unloading it again): the number refused, each as kCorrupt with a message
// holding `needle` and leaving nothing loaded.
size_t expectSectorsRefused(StreamingLevel& st, const char* needle) {
  size_t refused = 0;
  for (const SectorKey& key : st.sectors()) {
    const LevelResult r = st.load(key);
    if (r) {
      st.unload(key);
      continue;
    }
    ++refused;
    EXPECT_EQ(r.status, LevelStatus::kCorrupt);
    EXPECT_NE(r.message.find(needle), std::string::npos) << r.message;
    EXPECT_TRUE(st.loadedLevel().tets.empty());
  }
  return refused;
}

// The saved index is sealed: loadLevel accepts it, a re-save gives the same bytes, and every sector loads.
TEST_F(StreamingFile, SealedIndexLoadsThroughBothLoadersAndResavesIdentically) {
  Level back;
  const LevelResult r = loadLevel(path("streamed.tpb"), back);
  ASSERT_TRUE(r) << r.message;
  ASSERT_TRUE(saveLevel(path("again.tpb"), back));
  EXPECT_EQ(read(path("again.tpb")), bytes_);
  StreamingLevel st;
  const LevelResult o = st.open(path("streamed.tpb"));
  ASSERT_TRUE(o) << o.message;
  ASSERT_GE(st.sectors().size(), 8u);
  for (const SectorKey& key : st.sectors()) {
    const LevelResult l = st.load(key);
    EXPECT_TRUE(l) << l.message;
  }
  // An index saveLevel cannot read is refused, not written with checksums that mean nothing.
  Level bad = level_;
  bad.stream = {'S', 'T', 'R', 'M'};
  const LevelResult w = saveLevel(path("bad.tpb"), bad);
  EXPECT_EQ(w.status, LevelStatus::kWriteFailed);
  EXPECT_NE(w.message.find("streaming index"), std::string::npos) << w.message;
  EXPECT_FALSE(fs::exists(path("bad.tpb")));
}

// open() reads the header, the table, the occlusion section's 24-byte header and the index's header, sector
// records and coarse set: exactly those bytes, not the sectors' references and nodes nor the level's records.
TEST_F(StreamingFile, OpenReadsOnlyTheFramingAndTheIndex) {
  StreamingLevel st;
  ASSERT_TRUE(st.open(path("streamed.tpb")));
  const size_t strm = size_t(getU64(bytes_, entry(bytes_, "STRM") + 8));
  const uint64_t sectors = getU32(bytes_, strm + 4), coarseProbes = getU32(bytes_, strm + 48),
                 coarseTets = getU32(bytes_, strm + 52);
  const uint64_t expected = 80 + 24 * uint64_t(getU32(bytes_, 72)) + 4 + 24 + 64 + 44 * sectors +
                            120 * coarseProbes + 32 * coarseTets;
  EXPECT_EQ(st.bytesReadAtOpen(), expected);
  EXPECT_EQ(sectors, st.sectors().size());
  EXPECT_LT(st.bytesReadAtOpen(), bytes_.size() / 4) << "file " << bytes_.size() << " bytes";
}

// A byte of one probe's position changed, the payload CRC made good again: open still succeeds (it reads no
// record), every sector holding that probe is refused by its own CRC when loaded and leaves nothing
// loaded, the others load; loadLevel refuses the file naming a sector's checksum.
TEST_F(StreamingFile, DamagedSectorIsRefusedByItsChecksumWhenLoaded) {
  Bytes b = bytes_;
  const size_t prbs = size_t(getU64(b, entry(b, "PRBS") + 8));
  b[prbs + 12 * 7 + 2] ^= 0x10;  // probe 7's x
  putU32(b, b.size() - 4, crc32(b.data() + 80, b.size() - 84));
  const std::string file = write("damaged.tpb", b);
  Level whole;
  const LevelResult a = loadLevel(file, whole);
  EXPECT_EQ(a.status, LevelStatus::kCorrupt);
  EXPECT_NE(a.message.find("checksum mismatch"), std::string::npos) << a.message;
  StreamingLevel st;
  const LevelResult o = st.open(file);
  ASSERT_TRUE(o) << o.message;
  const size_t idle = st.bytesInUse();
  const size_t refused = expectSectorsRefused(st, "checksum mismatch");
  EXPECT_GE(refused, 1u);
  EXPECT_LT(refused, st.sectors().size());
  EXPECT_EQ(st.bytesInUse(), idle);
}

// A level file one format version older (4: the index had no checksums) is refused by both loaders, the
// message naming the file's version and the reader's.
TEST_F(StreamingFile, OlderVersionIsRefusedNamingBothVersions) {
  ASSERT_EQ(kLevelFormatVersion, 5u);
  Bytes b = bytes_;
  putU32(b, 8, 4);
  recomputeLevelChecksums(b.data(), b.size());
  expectBothRefuse(write("v4.tpb", b), LevelStatus::kUnsupportedVersion,
                   "format version 4 (this reader understands version 5");
}

// The table checks StreamingLevel used to skip: a section flag other than bit 0, a repeated known tag (the
// last used to win), an unknown tag flagged required (an older StreamingLevel loaded it).
TEST_F(StreamingFile, TableIsCheckedAsLoadLevelChecksIt) {
  const size_t grid = entry(bytes_, "CGR4");
  Bytes flags = bytes_;
  putU32(flags, grid + 4, 2);
  recomputeLevelChecksums(flags.data(), flags.size());
  expectBothRefuse(write("flags.tpb", flags), LevelStatus::kCorrupt, "bad flags, offset or size");
  Bytes repeated = bytes_;
  putU32(repeated, grid, levelTag("PRBS"));
  recomputeLevelChecksums(repeated.data(), repeated.size());
  expectBothRefuse(write("repeated.tpb", repeated), LevelStatus::kCorrupt, "repeated section tag");
  Bytes unknown = bytes_;
  putU32(unknown, grid, levelTag("ZZZZ"));
  putU32(unknown, grid + 4, kLevelSectionRequired);
  recomputeLevelChecksums(unknown.data(), unknown.size());
  expectBothRefuse(write("unknown.tpb", unknown), LevelStatus::kUnsupportedVersion,
                   "unknown required section tag");
  // An unknown optional tag is skipped by both (the grid section renamed: the index does not need it).
  Bytes optional = bytes_;
  putU32(optional, grid, levelTag("ZZZZ"));
  recomputeLevelChecksums(optional.data(), optional.size());
  Level whole;
  EXPECT_TRUE(loadLevel(write("optional.tpb", optional), whole));
  StreamingLevel st;
  EXPECT_TRUE(st.open(path("optional.tpb")));
}

// The occlusion plane tet 0 uses made all zero (no plane: loadLevel's last occlusion check), every checksum
// made good again: StreamingLevel refuses each sector holding tet 0 naming the plane, as loadLevel refuses
// the file.
TEST_F(StreamingFile, ZeroOcclusionPlaneIsRefusedByBothLoaders) {
  Bytes b = bytes_;
  const size_t occl = size_t(getU64(b, entry(b, "OCCL") + 8));
  const size_t plane = occl + 24 + 8 * level_.tets.size();
  std::memset(&b[plane], 0, 8);
  recomputeLevelChecksums(b.data(), b.size());
  const std::string file = write("zero_plane.tpb", b);
  Level whole;
  const LevelResult a = loadLevel(file, whole);
  EXPECT_EQ(a.status, LevelStatus::kCorrupt);
  EXPECT_NE(a.message.find("is zero (no plane)"), std::string::npos) << a.message;
  StreamingLevel st;
  ASSERT_TRUE(st.open(file));
  EXPECT_GE(expectSectorsRefused(st, "is zero (no plane)"), 1u);
}

}  // namespace
}  // namespace tetraprobe
