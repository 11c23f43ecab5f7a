// ProbeQuery: the walk against a brute-force scan, degenerate query points, and SH interpolation.
#include "tetraprobe/runtime/query.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <map>
#include <random>

#include <glm/geometric.hpp>

#include "test_levels.h"

namespace tetraprobe {
namespace {

using test::maxDifference;
using test::probeWeights;

const glm::dvec3 kOrigin(12000.0, 35.0, -8000.0);  // levels live far from the world origin
const glm::dvec3 kLo(-20.0, -5.0, -30.0), kHi(25.0, 10.0, 15.0);

const Level& randomLevel() {  // 400 random probes plus the box corners (so the hull is the box)
  static const Level level = test::makeLevel(
      [] {
        auto pts = test::randomBoxPoints(400, 21, kLo, kHi);
        for (auto& p : pts) p += kOrigin;
        return pts;
      }(),
      kOrigin, 4);
  return level;
}

const Level& gridLevel() {  // a 6x5x4 regular grid: cospherical everywhere, points on shared faces galore
  static const Level level = test::makeLevel(
      [] {
        std::vector<glm::dvec3> pts;
        for (int z = 0; z < 4; ++z)
          for (int y = 0; y < 5; ++y)
            for (int x = 0; x < 6; ++x) pts.push_back(kOrigin + glm::dvec3(x, y, z) * 2.0);
        return pts;
      }(),
      kOrigin + glm::dvec3(5.0, 4.0, 3.0), 5);
  return level;
}

void expectValid(const Level& level, const Location& loc, const glm::dvec3& x) {
  ASSERT_GE(loc.tet, 0) << x.x << " " << x.y << " " << x.z;
  ASSERT_LT(size_t(loc.tet), level.tets.size());
  float sum = 0.0f;
  for (int i = 0; i < 4; ++i) {
    ASSERT_TRUE(std::isfinite(loc.weights[i]));
    EXPECT_GE(loc.weights[i], 0.0f);
    sum += loc.weights[i];
  }
  EXPECT_NEAR(sum, 1.0f, 1e-6f);
}

glm::dvec3 interpolatedPosition(const Level& level, const Location& loc) {
  glm::dvec3 p(0.0);
  for (int i = 0; i < 4; ++i)
    p += double(loc.weights[i]) * glm::dvec3(level.probes[size_t(level.tets[size_t(loc.tet)].v[i])]);
  return level.origin + p;
}

// The GPU and the CPU both start walks from the grid: every cell must name a real tet.
TEST(Locate, StartGridNamesValidTets) {
  for (const Level* level : {&randomLevel(), &gridLevel()}) {
    const ProbeQuery q(*level);
    const StartGrid& g = q.startGrid();
    ASSERT_GT(g.dims.x * g.dims.y * g.dims.z, 0);
    ASSERT_EQ(g.startTet.size(), size_t(g.dims.x) * size_t(g.dims.y) * size_t(g.dims.z));
    for (int32_t t : g.startTet) {
      ASSERT_GE(t, 0);
      ASSERT_LT(size_t(t), level->tets.size());
    }
  }
}

// The walk is the fast path every pixel takes; the brute-force scan is the definition it must match.
TEST(Locate, AgreesWithBruteForce) {
  const Level& level = randomLevel();
  const ProbeQuery q(level);
  std::mt19937_64 rng(99);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  for (int k = 0; k < 100'000; ++k) {
    const glm::dvec3 x = kOrigin + kLo + (kHi - kLo) * glm::dvec3(u(rng), u(rng), u(rng));
    const Location walk = q.locate(x), brute = q.bruteForceLocate(x);
    expectValid(level, walk, x);
    ASSERT_TRUE(walk.inside) << k;
    ASSERT_TRUE(brute.inside) << k;
    ASSERT_LE(maxDifference(probeWeights(level, walk), probeWeights(level, brute)), 1e-6)
        << "point " << k << ": walk tet " << walk.tet << ", brute-force tet " << brute.tet;
  }
}

// Probes on a grid put query points exactly on shared faces, edges and vertices, where rounding decides the
// side: the walk must still stop (no ping-pong) with near-exact weights.
TEST(Locate, OnFacesEdgesVertices) {
  for (const Level* level : {&randomLevel(), &gridLevel()}) {
    const ProbeQuery q(*level);
    const double diagonal = glm::length(glm::dvec3(q.startGrid().cellSize * glm::vec3(q.startGrid().dims)));
    std::mt19937_64 rng(7);
    std::uniform_real_distribution<double> u(0.0, 1.0);
    for (size_t t = 0; t < level->tets.size(); ++t) {
      glm::dvec3 p[4];
      for (int i = 0; i < 4; ++i)
        p[i] = level->origin + glm::dvec3(level->probes[size_t(level->tets[t].v[i])]);
      const double a = u(rng), b = u(rng) * (1.0 - a);
      const glm::dvec3 points[] = {p[0],
                                   p[1],
                                   0.5 * (p[0] + p[2]),
                                   a * p[1] + (1.0 - a) * p[3],
                                   a * p[0] + b * p[1] + (1.0 - a - b) * p[2],
                                   (p[1] + p[2] + p[3]) / 3.0};
      for (const glm::dvec3& x : points) {
        const Location loc = q.locate(x);
        expectValid(*level, loc, x);
        for (int i = 0; i < 4; ++i) {
          EXPECT_GE(loc.weights[i], -1e-6f);
          EXPECT_LE(loc.weights[i], 1.0f + 1e-6f);
        }
        // The weights must rebuild the point: a wrong tet is off by metres; float rows on the large flat
        // hull tets of a box with probes only at its corners are off by up to ~1e-5 of the level's size.
        const glm::dvec3 back = interpolatedPosition(*level, loc);
        EXPECT_LT(glm::length(back - x), 2e-5 * diagonal) << "tet " << t;
      }
    }
  }
}

// Objects leave the probe volume and buggy callers pass NaN: the answer must stay usable.
TEST(Locate, OutsideHullIsFiniteAndNormalized) {
  const double nan = std::numeric_limits<double>::quiet_NaN(), inf = std::numeric_limits<double>::infinity();
  for (const Level* level : {&randomLevel(), &gridLevel()}) {
    const ProbeQuery q(*level);
    std::mt19937_64 rng(8);
    std::normal_distribution<double> n(0.0, 1.0);
    for (double dist : {1e3, 1e6}) {
      for (int k = 0; k < 200; ++k) {
        const glm::dvec3 dir = glm::normalize(glm::dvec3(n(rng), n(rng), n(rng)));
        const glm::dvec3 x = kOrigin + dist * dir;
        const Location loc = q.locate(x);
        expectValid(*level, loc, x);
        EXPECT_FALSE(loc.inside);
        const int32_t* n = level->tets[size_t(loc.tet)].n;  // the answer comes from a tet on the hull
        EXPECT_TRUE(n[0] < 0 || n[1] < 0 || n[2] < 0 || n[3] < 0) << "tet " << loc.tet;
        expectValid(*level, q.bruteForceLocate(x), x);
      }
    }
    for (const glm::dvec3& x :
         {glm::dvec3(nan, 0, 0), glm::dvec3(nan, nan, nan), glm::dvec3(kOrigin.x, inf, 0),
          glm::dvec3(-inf, inf, nan), glm::dvec3(1e300, -1e300, 1e300)}) {
      const Location loc = q.locate(x);
      expectValid(*level, loc, x);
      expectValid(*level, q.locate(x, 3), x);
      expectValid(*level, q.bruteForceLocate(x), x);
      const glm::vec3 e = q.irradiance(x, glm::vec3(0, 1, 0));
      EXPECT_TRUE(std::isfinite(e.x) && std::isfinite(e.y) && std::isfinite(e.z));
    }
  }
}

// A stale or wrong per-object hint may cost steps, never a different answer.
TEST(Locate, HintDoesNotChangeAnswer) {
  const Level& level = randomLevel();
  const ProbeQuery q(level);
  std::mt19937_64 rng(10);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::uniform_int_distribution<int32_t> anyTet(0, int32_t(level.tets.size()) - 1);
  for (int k = 0; k < 20'000; ++k) {
    const glm::dvec3 x = kOrigin + kLo + (kHi - kLo) * glm::dvec3(u(rng), u(rng), u(rng));
    const auto expected = probeWeights(level, q.locate(x));
    for (int32_t hint : {anyTet(rng), int32_t(-1), int32_t(-5), int32_t(1'000'000'000)}) {
      const Location loc = q.locate(x, hint);
      ASSERT_LE(maxDifference(probeWeights(level, loc), expected), 1e-6) << "point " << k << " hint " << hint;
    }
  }
}

// The per-object cache is written back so the next frame starts in the right tet.
TEST(Query, TetCacheIsUpdated) {
  const ProbeQuery q(randomLevel());
  const glm::dvec3 x = kOrigin + glm::dvec3(1.0, 2.0, 3.0);
  int32_t cache = -1;
  q.irradiance(x, glm::vec3(0, 0, 1), &cache);
  EXPECT_EQ(cache, q.locate(x).tet);
}

// Interpolating identical probes must give exactly that probe's irradiance, everywhere (inside or not).
TEST(Query, ConstantShGivesConstantIrradiance) {
  ShRgb sh;
  std::mt19937_64 rng(12);
  std::uniform_real_distribution<float> u(-1.0f, 1.0f);
  for (auto& c : sh.c) c = glm::vec3(u(rng), u(rng), u(rng));
  sh.c[0] += glm::vec3(3.0f);
  auto pts = test::randomBoxPoints(200, 13, kLo, kHi);
  for (auto& p : pts) p += kOrigin;
  const Level level = test::makeLevel(pts, kOrigin, 1, &sh);
  const ProbeQuery q(level);
  std::uniform_real_distribution<double> box(-40.0, 40.0);
  std::normal_distribution<float> n(0.0f, 1.0f);
  for (int k = 0; k < 5000; ++k) {
    const glm::dvec3 x = kOrigin + glm::dvec3(box(rng), box(rng), box(rng));
    const glm::vec3 normal = glm::normalize(glm::vec3(n(rng), n(rng), n(rng)));
    const glm::vec3 want = shIrradiance(level.sh[0], normal), got = q.irradiance(x, normal);  // as stored
    for (int c = 0; c < 3; ++c) EXPECT_NEAR(got[c], want[c], 1e-5f * (1.0f + std::abs(want[c])));
  }
}

// The batch interleaves queries and tries the previous item's tet first; threads only split the work: it is
// bit-identical to the single queries, on random points (inside and around the hull), points on tet
// vertices, edges and faces, far outside, and in raster (pixel) order, where the previous tet is the hint.
TEST(Query, BatchMatchesSingle) {
  for (const Level* level : {&randomLevel(), &gridLevel()}) {
    const ProbeQuery q(*level);
    std::mt19937_64 rng(14);
    std::uniform_real_distribution<double> box(-35.0, 35.0), u(0.0, 1.0);
    std::normal_distribution<float> n(0.0f, 1.0f);
    std::vector<glm::dvec3> world;
    for (int k = 0; k < 10'001; ++k) world.push_back(kOrigin + glm::dvec3(box(rng), box(rng), box(rng)));
    for (size_t t = 0; t < level->tets.size(); ++t) {
      glm::dvec3 p[4];
      for (int i = 0; i < 4; ++i)
        p[i] = level->origin + glm::dvec3(level->probes[size_t(level->tets[t].v[i])]);
      const double a = u(rng), b = u(rng) * (1.0 - a);
      world.push_back(p[t % 4]);
      world.push_back(a * p[1] + (1.0 - a) * p[3]);
      world.push_back(a * p[0] + b * p[1] + (1.0 - a - b) * p[2]);
    }
    for (int k = 0; k < 1000; ++k) world.push_back(kOrigin + 1e4 * glm::dvec3(box(rng), box(rng), box(rng)));
    for (int r = 0; r < 120; ++r)  // a raster over a slanted plane through the level
      for (int c = 0; c < 160; ++c) {
        const double s = (c + 0.5) / 160.0, t = (r + 0.5) / 120.0;
        world.push_back(kOrigin + kLo + (kHi - kLo) * glm::dvec3(s, 0.1 + 0.8 * t, 0.9 - 0.8 * t));
      }
    const size_t count = world.size();
    std::vector<glm::vec3> normal(count), single(count);
    for (size_t i = 0; i < count; ++i) {
      normal[i] = glm::normalize(glm::vec3(n(rng), n(rng), n(rng)));
      single[i] = q.irradiance(world[i], normal[i]);
    }
    for (int threads : {0, 1, 3, 8}) {
      std::vector<glm::vec3> batch(count, glm::vec3(-999.0f));
      q.irradianceBatch(world.data(), normal.data(), batch.data(), count, threads);
      for (size_t i = 0; i < count; ++i)
        ASSERT_EQ(batch[i], single[i]) << "item " << i << " at (" << world[i].x << ", " << world[i].y << ", "
                                       << world[i].z << "), " << threads << " threads";
    }
  }
}

// An empty level (no probes) is legal: queries answer "nothing here", not a crash.
TEST(Query, EmptyLevelAnswersNothing) {
  const Level empty;
  const ProbeQuery q(empty);
  EXPECT_EQ(q.locate(glm::dvec3(1.0)).tet, -1);
  EXPECT_EQ(q.irradiance(glm::dvec3(1.0), glm::vec3(0, 1, 0)), glm::vec3(0.0f));
}

}  // namespace
}  // namespace tetraprobe
