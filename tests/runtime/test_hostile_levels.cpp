// The gaps issue 14 closed in the loader, each with its typed error: a size cap on whole-file reads, forged
// neighbour tables, tets flat in float, coordinates beyond what the cell grid rebuild can key.
#include <gtest/gtest.h>

#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <limits>

#include "test_levels.h"
#include "tetraprobe/runtime/cell_grid.h"
#include "tetraprobe/runtime/file_io.h"
#include "tetraprobe/runtime/level.h"
#include "tetraprobe/runtime/outer_cells.h"
#include "tetraprobe/runtime/query.h"

namespace tetraprobe {
namespace {

namespace fs = std::filesystem;

class Scratch {
 public:
  Scratch() : dir_(fs::temp_directory_path() / ("tetraprobe_hostile_rt_" + std::to_string(::getpid()))) {
    fs::create_directories(dir_);
  }
  ~Scratch() { fs::remove_all(dir_); }
  std::string file(const std::string& name) const { return (dir_ / name).string(); }

 private:
  fs::path dir_;
};

Level boxLevel() {
  return test::makeLevel(test::randomBoxPoints(40, 7, {-3, -1, -2}, {3, 2, 2}), {100.0, 0.0, -50.0}, 4);
}

// readFile refuses a file over its byte limit before allocating, and non-regular files; loadLevel maps the
// limit to kTooLarge and keeps `out` empty. The limit is the caller's (loadLevel's maxBytes).
TEST(HostileLevels, FileOverTheByteLimitIsTooLargeNotBadAlloc) {
  Scratch dir;
  const Level level = boxLevel();
  ASSERT_TRUE(saveLevel(dir.file("l.tpb"), level));
  const auto size = fs::file_size(dir.file("l.tpb"));
  Level out;
  const LevelResult atLimit = loadLevel(dir.file("l.tpb"), out, size);  // exactly at the limit: fine
  EXPECT_TRUE(atLimit) << int(atLimit.status) << " " << atLimit.message;
  const LevelResult r = loadLevel(dir.file("l.tpb"), out, size - 1);
  EXPECT_EQ(r.status, LevelStatus::kTooLarge) << r.message;
  EXPECT_NE(r.message.find("more than the limit"), std::string::npos) << r.message;
  EXPECT_TRUE(out.probes.empty() && out.tets.empty());

  // A sparse 6 GiB file (nothing written) against the default 4 GiB limit: refused from its size alone.
  std::ofstream(dir.file("huge.tpb")).put('x');
  fs::resize_file(dir.file("huge.tpb"), uint64_t(6) << 30);
  EXPECT_EQ(loadLevel(dir.file("huge.tpb"), out).status, LevelStatus::kTooLarge);

  std::vector<char> bytes;
  std::string error;
  bool tooLarge = true;
  EXPECT_FALSE(readFile(dir.file(""), bytes, &error, kDefaultMaxReadBytes, &tooLarge));  // a directory
  EXPECT_FALSE(tooLarge);
  EXPECT_NE(error.find("not a regular file"), std::string::npos) << error;
  EXPECT_FALSE(readFile("/dev/zero", bytes, &error));
  EXPECT_NE(error.find("not a regular file"), std::string::npos) << error;
}

// loadLevelFromMemory is loadLevel without the file: the same level, the same errors.
TEST(HostileLevels, LoadFromMemoryMatchesLoadFromFile) {
  Scratch dir;
  const Level level = boxLevel();
  ASSERT_TRUE(saveLevel(dir.file("l.tpb"), level));
  std::vector<char> bytes;
  std::string error;
  ASSERT_TRUE(readFile(dir.file("l.tpb"), bytes, &error)) << error;
  Level a, b;
  ASSERT_TRUE(loadLevel(dir.file("l.tpb"), a));
  ASSERT_TRUE(loadLevelFromMemory(bytes.data(), bytes.size(), "mem", b));
  EXPECT_EQ(a.probes, b.probes);
  ASSERT_EQ(a.tets.size(), b.tets.size());
  bytes[100] ^= 1;
  const LevelResult r = loadLevelFromMemory(bytes.data(), bytes.size(), "mem", b);
  EXPECT_EQ(r.status, LevelStatus::kCorrupt);
  EXPECT_EQ(r.message.rfind("mem: ", 0), 0u) << r.message;
  EXPECT_TRUE(b.tets.empty());
  EXPECT_EQ(loadLevelFromMemory(nullptr, 0, "empty", b).status, LevelStatus::kTruncated);
}

// Two adjacent pairs rewired crosswise: every link is mutual (the old check passed) but no face is shared. A
// walk trusting that table wanders and falls back to scanning every tet; the loader refuses it.
TEST(HostileLevels, NeighbourThatDoesNotShareItsFaceIsCorrupt) {
  Level level = boxLevel();
  ASSERT_TRUE(validateLevel(level));
  const auto faceTo = [&](int32_t t, int32_t u) {
    for (int i = 0; i < 4; ++i)
      if (level.tets[size_t(t)].n[i] == u) return i;
    return -1;
  };
  int32_t a = -1, b = -1, c = -1, d = -1;
  for (int32_t t = 0; t < int32_t(level.tets.size()) && d < 0; ++t)
    for (int32_t u : level.tets[size_t(t)].n) {
      if (u <= t || d >= 0) continue;
      if (a < 0)
        a = t, b = u;
      else if (t != a && t != b && u != a && u != b)
        c = t, d = u;
    }
  ASSERT_GE(d, 0);
  const int ab = faceTo(a, b), ba = faceTo(b, a), cd = faceTo(c, d), dc = faceTo(d, c);
  level.tets[size_t(a)].n[ab] = c;
  level.tets[size_t(c)].n[cd] = a;
  level.tets[size_t(b)].n[ba] = d;
  level.tets[size_t(d)].n[dc] = b;
  const LevelResult r = validateLevel(level);
  EXPECT_EQ(r.status, LevelStatus::kCorrupt);
  EXPECT_NE(r.message.find("does not share that face"), std::string::npos) << r.message;

  // Reciprocal and sharing the face, but named back across another face: also refused.
  Level swapped = boxLevel();
  Tet& t0 = swapped.tets[0];
  int i = 0;
  while (t0.n[i] < 0) ++i;
  Tet& u = swapped.tets[size_t(t0.n[i])];
  const int back = [&] {
    for (int k = 0; k < 4; ++k)
      if (u.n[k] == 0) return k;
    return -1;
  }();
  ASSERT_GE(back, 0);
  std::swap(u.n[back], u.n[(back + 1) % 4]);
  EXPECT_EQ(validateLevel(swapped).status, LevelStatus::kCorrupt);
}

// A tet whose two probes sit at one float position is flat for good (no weights exist in it): the build
// refuses it (buildTetRecords) and so does the loader, naming the tet and the probes.
TEST(HostileLevels, TetFlatInFloatIsCorrupt) {
  Level level = boxLevel();
  const Tet t = level.tets[3];
  level.probes[size_t(t.v[2])] = level.probes[size_t(t.v[0])];
  const LevelResult r = validateLevel(level);
  EXPECT_EQ(r.status, LevelStatus::kCorrupt);
  EXPECT_NE(r.message.find("flat"), std::string::npos) << r.message;
}

// Local positions beyond 2^24 m are refused (float holds them to 2 m or worse, and the cell-grid keys the
// query would rebuild from them could leave int32 for small cells).
TEST(HostileLevels, PositionBeyondTheCoordinateLimitIsCorrupt) {
  Level level = boxLevel();
  level.probes[5].y = 3.0e7f;
  const LevelResult r = validateLevel(level);
  EXPECT_EQ(r.status, LevelStatus::kCorrupt);
  EXPECT_NE(r.message.find("beyond"), std::string::npos) << r.message;
}

// The cell grid a query rebuilds for a level that stores none: cell keys are range-checked in double before
// any float-to-int conversion (UB before, caught by the sanitizer build), tets beyond the int32 keys are left
// to the walk, and locate still agrees with the brute-force scan.
TEST(HostileLevels, CellGridRebuildWithKeysBeyondInt32StaysCorrect) {
  const Level level =
      test::makeLevel(test::randomBoxPoints(30, 11, {-1e6, -1e6, -1e6}, {1e6, 1e6, 1e6}), glm::dvec3(0.0), 2);
  ASSERT_TRUE(validateLevel(level));
  for (float cellSize : {1e-30f, 1e-3f, std::numeric_limits<float>::denorm_min()}) {
    const CellGrid g = buildCellGrid(level.probes, level.tets, cellSize, 1);
    ProbeQuery q(level, cellSize, 1);
    for (const glm::dvec3 x : {glm::dvec3(0.0), glm::dvec3(3e5, -2e5, 1e5), glm::dvec3(-9e5, 9e5, 0.0)}) {
      const Location a = q.locate(x), b = q.bruteForceLocate(x);
      EXPECT_LT(test::maxDifference(test::probeWeights(level, a), test::probeWeights(level, b)), 1e-5)
          << "cell size " << cellSize;
    }
    (void)g;
  }
}

}  // namespace
}  // namespace tetraprobe
