// The sparse cell grid + BSP (runtime/cell_grid.h) as ProbeQuery::locate uses it: agreement with an exact
// scan on over ten million queries per level (random, on faces, edges and vertices, just outside and far
// outside the hull), leaves naming the tet that holds the point, the hash table's probe bound, and the
// tree's invariants.
#include "tetraprobe/runtime/cell_grid.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <cstring>
#include <map>
#include <random>
#include <set>

#include <glm/geometric.hpp>

#include "test_levels.h"
#include "tetraprobe/runtime/query.h"

namespace tetraprobe {
namespace {

const glm::dvec3 kOrigin(4000.0, -150.0, 2500.0);

Level ballLevel() {
  std::mt19937_64 rng(41);
  std::normal_distribution<double> n(0.0, 1.0);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::vector<glm::dvec3> pts;
  for (int k = 0; k < 600; ++k) {
    const glm::dvec3 d = glm::normalize(glm::dvec3(n(rng), n(rng), n(rng)));
    pts.push_back(kOrigin + 12.0 * std::cbrt(u(rng)) * d);
  }
  return test::makeLevel(pts, kOrigin, 6);
}

Level boxLevel() {
  auto pts = test::randomBoxPoints(500, 42, {-20, -4, -9}, {22, 5, 12});
  for (auto& p : pts) p += kOrigin;
  return test::makeLevel(pts, kOrigin, 7);
}

Level latticeLevel() {  // a regular lattice: cospherical everywhere, queries on shared faces galore
  std::vector<glm::dvec3> pts;
  for (int z = 0; z < 5; ++z)
    for (int y = 0; y < 4; ++y)
      for (int x = 0; x < 7; ++x) pts.push_back(kOrigin + glm::dvec3(x, y, z) * 3.0);
  return test::makeLevel(pts, kOrigin + glm::dvec3(9.0, 4.5, 6.0), 8);
}

// The exact reference: every tet whose bounding box holds x (from a uniform bucket grid built here, not the
// code under test) weighed in double from its probe positions (test::exactTetWeights; the float rows only
// skip tets far from x), the best (largest smallest weight, ties lowest index) taken; when none holds x within 1e-6, ProbeQuery::bruteForceLocate (every tet, then every outer cell).
class ExactScan {
 public:
  ExactScan(const Level& level, const ProbeQuery& query) : level_(level), query_(query) {
    lo_ = glm::dvec3(1e300);
    hi_ = glm::dvec3(-1e300);
    for (const glm::vec3& p : level.probes) {
      lo_ = glm::min(lo_, glm::dvec3(p));
      hi_ = glm::max(hi_, glm::dvec3(p));
    }
    step_ = (hi_ - lo_) / double(kDim) + 1e-9;
    buckets_.resize(size_t(kDim * kDim * kDim));
    for (size_t t = 0; t < level.tets.size(); ++t) {
      glm::dvec3 a(1e300), b(-1e300);
      for (int i = 0; i < 4; ++i) {
        a = glm::min(a, glm::dvec3(level.probes[size_t(level.tets[t].v[i])]));
        b = glm::max(b, glm::dvec3(level.probes[size_t(level.tets[t].v[i])]));
      }
      const glm::ivec3 c0 = cell(a - 1e-4), c1 = cell(b + 1e-4);
      for (int z = c0.z; z <= c1.z; ++z)
        for (int y = c0.y; y <= c1.y; ++y)
          for (int x = c0.x; x <= c1.x; ++x)
            buckets_[size_t(x + kDim * (y + kDim * z))].push_back(int32_t(t));
    }
  }

  Location locate(const glm::dvec3& world) const {
    const glm::dvec3 x = world - level_.origin;
    int32_t best = -1;
    double bestMin = -1e300, bestW[4] = {};
    if (x.x >= lo_.x && x.y >= lo_.y && x.z >= lo_.z && x.x <= hi_.x && x.y <= hi_.y && x.z <= hi_.z) {
      const glm::ivec3 c = cell(x);
      for (int32_t t : buckets_[size_t(c.x + kDim * (c.y + kDim * c.z))]) {
        const Tet& tet = level_.tets[size_t(t)];
        double w[4];
        test::exactTetWeights(level_, tet, x, w);
        const double m = *std::min_element(w, w + 4);
        if (m > bestMin || (m == bestMin && t < best)) {
          best = t;
          bestMin = m;
          std::copy(w, w + 4, bestW);
        }
      }
    }
    if (best < 0 || bestMin < -1e-6) {
      // Outside every tet: the full scan of tets and outer cells on every 64th such point, the walk from the
      // start grid (a path that does not use the cell grid) on the others.
      return ++outsideCount_ % 64 == 0 ? query_.bruteForceLocate(world) : query_.walkLocate(world);
    }
    Location loc;
    loc.tet = best;
    loc.inside = true;
    double sum = 0.0;
    for (double& w : bestW) sum += (w = std::max(w, 0.0));
    for (int i = 0; i < 4; ++i) loc.weights[i] = float(bestW[i] / sum);
    return loc;
  }

 private:
  static constexpr int kDim = 24;
  glm::ivec3 cell(const glm::dvec3& x) const {
    glm::ivec3 c;
    for (int a = 0; a < 3; ++a) c[a] = std::clamp(int(std::floor((x[a] - lo_[a]) / step_[a])), 0, kDim - 1);
    return c;
  }
  const Level& level_;
  const ProbeQuery& query_;
  glm::dvec3 lo_, hi_, step_;
  std::vector<std::vector<int32_t>> buckets_;
  mutable size_t outsideCount_ = 0;
};

// How far two correct answers may differ: 1e-6 when both are inside tets (float weights; plus the float rows'
// rounding when both name the same tet, as locate() takes the rows' weights where they clearly hold x, and
// the reference's are exact), unless the point
// lies on a face, edge or vertex two tets share: each tet's float rows then put it there only within their
// rounding, and which of them the walk stops in depends on where it came from; 1e-5 when both are
// outer cells (a cell accepts a point within 1e-6 of its edges, where its neighbour's weights differ by that
// much times the cells' slopes); otherwise (a point on a hull face, or in a float gap between sliver faces
// that no tet's rows claim) the tets' float rows decide, as in OuterCells.ContinuousAcrossHullBoundary: their
// slope times their rounding.
double tolerance(const Level& level, const Location& a, const Location& b, const glm::dvec3& world) {
  const auto minWeight = [](const Location& l) {
    return std::min({l.weights[0], l.weights[1], l.weights[2], l.weights[3]});
  };
  if (a.inside && b.inside && a.tet == b.tet)
    return 1e-6;  // the same tet: both weights exact (from the probe positions)
  if (a.inside && b.inside && minWeight(a) > 1e-5f && minWeight(b) > 1e-5f) return 1e-6;
  double slope = 0.0;
  for (const Location* loc : {&a, &b}) {
    if (loc->outerCell >= 0) continue;
    const BaryFrame frame = baryFrame(level.tets[size_t(loc->tet)], level.probes);
    glm::dvec3 sum(0.0);
    for (int r = 0; r < 3; ++r) {
      const glm::dvec3 g(frame.grad[r]);
      slope = std::max(slope, glm::length(g));
      sum += g;
    }
    slope = std::max(slope, glm::length(sum));
  }
  return 1e-5 + slope * 4.0 * 1.2e-7 * (glm::length(world - level.origin) + 1.0);
}

// Largest difference between two answers' probe weights (the same interpolation whichever of two tets sharing
// the point is named).
double weightDifference(const Level& level, const Location& a, const Location& b) {
  if (a.tet == b.tet) {
    double d = 0.0;
    for (int i = 0; i < 4; ++i) d = std::max(d, double(std::abs(a.weights[i] - b.weights[i])));
    return d;
  }
  std::map<int32_t, double> m;
  for (int i = 0; i < 4; ++i) {
    m[level.tets[size_t(a.tet)].v[i]] += a.weights[i];
    m[level.tets[size_t(b.tet)].v[i]] -= b.weights[i];
  }
  double d = 0.0;
  for (const auto& [p, w] : m) d = std::max(d, std::abs(w));
  return d;
}

struct Tally {
  size_t queries = 0, inside = 0;
};

// Runs `count` queries from `make` through locate() and the exact reference; every answer must agree.
template <typename Make>
void compare(const Level& level, const ProbeQuery& q, const ExactScan& ref, size_t count, Make make,
             const char* what, Tally& tally) {
  for (size_t k = 0; k < count; ++k) {
    const glm::dvec3 x = make(k);
    const Location got = q.locate(x), want = ref.locate(x);
    ++tally.queries;
    tally.inside += got.inside;
    ASSERT_GE(got.tet, 0);
    const double d = weightDifference(level, got, want);
    ASSERT_LE(d, tolerance(level, got, want, x))
        << what << " query " << k << " at local (" << (x - level.origin).x << ", " << (x - level.origin).y
        << ", " << (x - level.origin).z << "): grid tet " << got.tet << " (outer " << got.outerCell
        << "), reference tet " << want.tet << " (outer " << want.outerCell << ")";
  }
}

// Over ten million queries on each level, with the default 16 m cells and with 2 m cells (many cells, so the
// hash table and cell borders are exercised): the grid + BSP locate gives the exact scan's interpolation
// everywhere: to 1e-6 in every probe weight inside the hull (see tolerance() for the rest).
size_t agreeOnLevel(int which) {
  size_t total = 0;
  const Level level = which == 0 ? ballLevel() : which == 1 ? boxLevel() : latticeLevel();
  for (float cellSize : {16.0f, 2.0f}) {
    const ProbeQuery q(level, cellSize, 2);
    const ExactScan ref(level, q);
    glm::dvec3 lo(1e300), hi(-1e300);
    for (const glm::vec3& p : level.probes) {
      lo = glm::min(lo, glm::dvec3(p));
      hi = glm::max(hi, glm::dvec3(p));
    }
    const glm::dvec3 ext = hi - lo;
    std::mt19937_64 rng(uint64_t(100 + which * 10) + uint64_t(cellSize));
    std::uniform_real_distribution<double> u(0.0, 1.0);
    std::normal_distribution<double> n(0.0, 1.0);
    Tally tally;
    // Random in the bounds (grown by 5 %: inside and just around the hull).
    compare(
        level, q, ref, 3'600'000,
        [&](size_t) {
          return level.origin + lo - 0.05 * ext + 1.1 * ext * glm::dvec3(u(rng), u(rng), u(rng));
        },
        "random", tally);
    // On tet vertices, edges and faces (exactly representable or within rounding of them).
    std::uniform_int_distribution<size_t> anyTet(0, level.tets.size() - 1);
    compare(
        level, q, ref, 1'350'000,
        [&](size_t k) {
          const Tet& t = level.tets[anyTet(rng)];
          glm::dvec3 p[4];
          for (int i = 0; i < 4; ++i) p[i] = glm::dvec3(level.probes[size_t(t.v[i])]);
          const double a = u(rng), b = u(rng) * (1.0 - a);
          switch (k % 3) {
            case 0:
              return level.origin + p[k % 4];
            case 1:
              return level.origin + a * p[0] + (1.0 - a) * p[(k / 3) % 3 + 1];
            default:
              return level.origin + a * p[1] + b * p[2] + (1.0 - a - b) * p[3];
          }
        },
        "face/edge/vertex", tally);
    // Just outside (within 1 % of the size beyond the bounds) and far outside (100 m to 10 km).
    compare(
        level, q, ref, 60'000,
        [&](size_t k) {
          const glm::dvec3 d = glm::normalize(glm::dvec3(n(rng), n(rng), n(rng)));
          const double r =
              k % 2 ? 0.5 * glm::length(ext) * (1.0 + 0.01 * u(rng)) : 100.0 * std::pow(100.0, u(rng));
          return level.origin + 0.5 * (lo + hi) + r * d;
        },
        "outside", tally);
    total += tally.queries;
    std::printf(
        "level %d, %g m cells: %zu cells in %zu slots (probe bound %u), %zu nodes, depth max %d mean %.1f; "
        "%zu queries, %zu inside\n",
        which, double(cellSize), occupiedCells(q.cellGrid()), q.cellGrid().slots.size(),
        q.cellGrid().maxProbe, q.cellGrid().nodes.size(), q.cellGrid().maxDepth, q.cellGrid().meanDepth,
        tally.queries, tally.inside);
  }
  return total;
}

TEST(CellGrid, AgreesWithExactScanOnTenMillionQueriesInABall) {
  EXPECT_GE(agreeOnLevel(0), 10'000'000u);
}
TEST(CellGrid, AgreesWithExactScanOnTenMillionQueriesInABox) {
  EXPECT_GE(agreeOnLevel(1), 10'000'000u);
}
TEST(CellGrid, AgreesWithExactScanOnTenMillionQueriesOnALattice) {
  EXPECT_GE(agreeOnLevel(2), 10'000'000u);
}

// The answer does not depend on how the trees were split: three grids of different cell sizes (so different
// cells, trees and leaves) give every point on a vertex, edge or face the same interpolation, probe weight by
// probe weight, to 1e-6 (which of the tets sharing the point is named may differ; what they interpolate may
// not).
TEST(CellGrid, AnswerDoesNotDependOnTheSplits) {
  for (int which = 0; which < 3; ++which) {
    const Level level = which == 0 ? ballLevel() : which == 1 ? boxLevel() : latticeLevel();
    const ProbeQuery a(level, 16.0f, 2), b(level, 2.0f, 2), c(level, 0.7f, 2);
    ASSERT_NE(a.cellGrid().nodes.size(), b.cellGrid().nodes.size());
    std::mt19937_64 rng(77 + uint64_t(which));
    std::uniform_real_distribution<double> u(0.0, 1.0);
    std::uniform_int_distribution<size_t> anyTet(0, level.tets.size() - 1);
    double worst = 0.0;
    size_t differentTet = 0;
    for (size_t k = 0; k < 60'000; ++k) {
      const Tet& t = level.tets[anyTet(rng)];
      glm::dvec3 p[4];
      for (int i = 0; i < 4; ++i) p[i] = glm::dvec3(level.probes[size_t(t.v[i])]);
      const double s = u(rng), r = u(rng) * (1.0 - s);
      const glm::dvec3 x = k % 3 == 0   ? p[k % 4]
                           : k % 3 == 1 ? s * p[0] + (1.0 - s) * p[(k / 3) % 3 + 1]
                                        : s * p[1] + r * p[2] + (1.0 - s - r) * p[3];
      const Location la = a.locate(level.origin + x), lb = b.locate(level.origin + x),
                     lc = c.locate(level.origin + x);
      differentTet += la.tet != lb.tet || la.tet != lc.tet;
      worst = std::max({worst, weightDifference(level, la, lb), weightDifference(level, la, lc)});
    }
    EXPECT_LE(worst, 1e-6) << "level " << which;
    std::printf(
        "level %d: %zu of 60000 boundary points named a different tet by another grid; worst weight "
        "difference %.2e\n",
        which, differentTet, worst);
  }
}

// kStoredCellGridOnly (the bake's rounds): no grid is built for a level without one, and the walks from the
// coarse start grid give the grid's answers: the same tet and bit-identical weights for points inside a tet,
// weights within 1e-6 on shared faces, edges and vertices (where either tet holding the point may be named);
// a level that stores a grid keeps using it.
TEST(CellGrid, WalkWithoutAGridGivesTheGridsAnswers) {
  for (int which = 0; which < 3; ++which) {
    Level level = which == 0 ? ballLevel() : which == 1 ? boxLevel() : latticeLevel();
    level.cellGrid = CellGrid{};
    const ProbeQuery walked(level, kStoredCellGridOnly), gridded(level, 16.0f, 2);
    EXPECT_TRUE(walked.cellGrid().slots.empty()) << "no grid is built";
    ASSERT_FALSE(gridded.cellGrid().slots.empty());
    std::mt19937_64 rng(91 + uint64_t(which));
    std::uniform_real_distribution<double> u(0.0, 1.0);
    std::uniform_int_distribution<size_t> anyTet(0, level.tets.size() - 1);
    double worst = 0.0;
    size_t interiorMismatch = 0, interior = 0;
    for (size_t k = 0; k < 20'000; ++k) {
      const Tet& t = level.tets[anyTet(rng)];
      glm::dvec3 p[4];
      for (int i = 0; i < 4; ++i) p[i] = glm::dvec3(level.probes[size_t(t.v[i])]);
      double b[4] = {u(rng) + 0.05, u(rng) + 0.05, u(rng) + 0.05, u(rng) + 0.05};
      const double sum = b[0] + b[1] + b[2] + b[3];
      const bool onBoundary = k % 2 == 0;
      if (onBoundary) b[k % 4] = 0.0;  // on a face of t
      glm::dvec3 x(0.0);
      double bs = 0.0;
      for (int i = 0; i < 4; ++i) bs += b[i];
      for (int i = 0; i < 4; ++i) x += b[i] / (onBoundary ? bs : sum) * p[i];
      const Location lw = walked.locate(level.origin + x), lg = gridded.locate(level.origin + x);
      worst = std::max(worst, weightDifference(level, lw, lg));
      if (!onBoundary) {
        ++interior;
        interiorMismatch += lw.tet != lg.tet || lw.weights != lg.weights;
      }
    }
    EXPECT_LE(worst, 1e-6) << "level " << which;
    EXPECT_EQ(interiorMismatch, 0u) << "level " << which << ": of " << interior << " interior points";
  }
  Level stored = boxLevel();
  stored.cellGrid = buildCellGrid(stored.probes, stored.tets, 4.0f, 1);
  EXPECT_EQ(ProbeQuery(stored, kStoredCellGridOnly).cellGrid().nodes.size(), stored.cellGrid.nodes.size());
}

// The hash table keeps its stated bound, is at most half full, and every stored cell is found.
TEST(CellGrid, HashProbeBoundHolds) {
  const Level level = boxLevel();
  for (float cellSize : {16.0f, 1.0f, 0.5f}) {
    const CellGrid g = buildCellGrid(level.probes, level.tets, cellSize, 1);
    EXPECT_LE(g.maxProbe, kMaxCellProbe);
    size_t used = 0;
    for (const CellSlot& s : g.slots) used += s.key[0] != INT32_MIN;
    EXPECT_LE(2 * used, g.slots.size());
    for (const CellSlot& s : g.slots) {
      if (s.key[0] == INT32_MIN) continue;
      const glm::dvec3 centre =
          glm::dvec3(g.min) + (glm::dvec3(s.key[0], s.key[1], s.key[2]) + 0.5) * double(cellSize);
      int32_t key[3], root = 0;
      ASSERT_TRUE(cellGridKey(g, centre, key));
      EXPECT_TRUE(std::equal(key, key + 3, s.key));
      EXPECT_TRUE(cellGridFind(g, key, cellGridSlot(g, key), &root));
      EXPECT_EQ(root, s.root);
    }
    // Far away: absent, no tet, no crash (also for non-finite input).
    EXPECT_EQ(cellGridLeaf(g, glm::dvec3(1e7)), -1);
    EXPECT_EQ(cellGridLeaf(g, glm::dvec3(std::nan(""), 0.0, 0.0)), -1);
  }
}

// Threads only split the work: the grid is the same for any thread count.
TEST(CellGrid, DeterministicForAnyThreadCount) {
  const Level level = ballLevel();
  const CellGrid a = buildCellGrid(level.probes, level.tets, 4.0f, 1);
  for (int threads : {2, 3, 8}) {
    const CellGrid b = buildCellGrid(level.probes, level.tets, 4.0f, threads);
    ASSERT_EQ(a.nodes.size(), b.nodes.size());
    EXPECT_EQ(std::memcmp(a.nodes.data(), b.nodes.data(), a.nodes.size() * sizeof(BspNode)), 0);
    EXPECT_EQ(a.leaves, b.leaves);
    EXPECT_EQ(a.meanDepth, b.meanDepth);
    ASSERT_EQ(a.slots.size(), b.slots.size());
    EXPECT_EQ(std::memcmp(a.slots.data(), b.slots.data(), a.slots.size() * sizeof(CellSlot)), 0);
  }
}

// The level file stores a node as the tet face its plane was cut from (CGR4) and recomputes the plane on load
// with cellGridFacePlane: that holds only if every node plane is, bit for bit, some face's cellGridFacePlane.
TEST(CellGrid, EveryNodePlaneIsTheFloatPlaneOfATetFace) {
  for (const Level& level : {ballLevel(), boxLevel(), latticeLevel()}) {
    std::set<std::array<uint32_t, 4>> faces;
    for (const Tet& t : level.tets) {
      glm::vec3 corners[4];
      for (int i = 0; i < 4; ++i) corners[i] = level.probes[size_t(t.v[i])];
      for (int f = 0; f < 4; ++f) {
        float plane[4];
        ASSERT_TRUE(cellGridFacePlane(corners, f, plane));
        faces.insert({std::bit_cast<uint32_t>(plane[0]), std::bit_cast<uint32_t>(plane[1]),
                      std::bit_cast<uint32_t>(plane[2]), std::bit_cast<uint32_t>(plane[3])});
      }
    }
    const CellGrid grid = buildCellGrid(level.probes, level.tets, 4.0f, 2);
    ASSERT_GT(grid.nodes.size(), 10u);
    for (const BspNode& node : grid.nodes)
      EXPECT_TRUE(
          faces.count({std::bit_cast<uint32_t>(node.plane[0]), std::bit_cast<uint32_t>(node.plane[1]),
                       std::bit_cast<uint32_t>(node.plane[2]), std::bit_cast<uint32_t>(node.plane[3])}));
  }
  // A face with collinear corners has no plane: false, not a NaN plane.
  const glm::vec3 flat[4] = {{0, 0, 0}, {1, 1, 1}, {2, 2, 2}, {0, 1, 0}};
  float plane[4];
  EXPECT_FALSE(cellGridFacePlane(flat, 3, plane));
  // Face 0 (corners 1-3) is not flat: a unit normal, its corners on the plane.
  ASSERT_TRUE(cellGridFacePlane(flat, 0, plane));
  const glm::vec3 normal(plane[0], plane[1], plane[2]);
  EXPECT_NEAR(glm::length(normal), 1.0f, 1e-6f);
  for (int i = 1; i < 4; ++i) EXPECT_NEAR(glm::dot(normal, flat[i]) + plane[3], 0.0f, 1e-6f);
}

// The tets' adjacency distance (steps across shared faces) from tet `from` to tet `to`, by breadth-first
// search; -1 when more than maxSteps.
int tetDistance(const Level& level, int32_t from, int32_t to, int maxSteps) {
  std::map<int32_t, int> seen{{from, 0}};
  std::vector<int32_t> frontier{from};
  for (int d = 0; d <= maxSteps; ++d) {
    std::vector<int32_t> next;
    for (int32_t t : frontier) {
      if (t == to) return d;
      for (int32_t n : level.tets[size_t(t)].n)
        if (n >= 0 && seen.emplace(n, d + 1).second) next.push_back(n);
    }
    frontier.swap(next);
  }
  return -1;
}

// Points well inside a tet (all weights >= 1e-3): x, its tet t and the level's tets, for the leaf tests.
template <typename F>
size_t forPointsInsideTets(const Level& level, uint64_t seed, F&& f) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  size_t points = 0;
  for (size_t t = 0; t < level.tets.size(); ++t) {
    glm::dvec3 p[4];
    for (int i = 0; i < 4; ++i) p[i] = glm::dvec3(level.probes[size_t(level.tets[t].v[i])]);
    for (int s = 0; s < 20; ++s) {
      double w[4], sum = 0.0;
      for (double& x : w) sum += (x = u(rng));
      for (double& x : w) x = 1e-3 + (1.0 - 4e-3) * x / sum;
      glm::dvec3 x(0.0);
      for (int i = 0; i < 4; ++i) x += w[i] * p[i];
      double exact[4];
      test::exactTetWeights(level, level.tets[t], x, exact);
      if (*std::min_element(exact, exact + 4) < 5e-4) continue;  // a sliver: x is not well inside
      ++points;
      f(x, int32_t(t));
    }
  }
  return points;
}

// With one tet a leaf (leafTets = 1), a point inside a tet (all weights >= 1e-3) descends to a leaf naming
// that tet: the regions the build tracks are exact, so the leaf tet is the answer itself and the walk takes
// no step. Leaves the build could not prove (unprovenLeaves: a region thinner than the margin that no face
// plane cuts) are rare and tiny, and no sampled point falls in one. Also: the tree's statistics are
// consistent.
TEST(CellGrid, OneTetLeafNamesTheTetHoldingThePoint) {
  for (int which = 0; which < 3; ++which) {
    const Level level = which == 0 ? ballLevel() : which == 1 ? boxLevel() : latticeLevel();
    for (float cellSize : {16.0f, 2.0f}) {
      const CellGrid g = buildCellGrid(level.probes, level.tets, cellSize, 2, 1);
      EXPECT_LE(100 * g.unprovenLeaves, g.leaves) << "level " << which << ", " << cellSize << " m cells";
      EXPECT_GE(g.leaves, level.tets.size());                  // every tet holds a point in some leaf
      EXPECT_EQ(g.leaves, g.nodes.size() + occupiedCells(g));  // a binary tree per cell: leaves = nodes + 1
      EXPECT_LE(g.meanDepth, double(g.maxDepth));
      size_t misses = 0;
      const size_t points =
          forPointsInsideTets(level, 5 + uint64_t(which),
                              [&](const glm::dvec3& x, int32_t t) { misses += cellGridLeaf(g, x) != t; });
      EXPECT_GT(points, 10 * level.tets.size());
      EXPECT_EQ(misses, 0u) << "level " << which << ", " << cellSize << " m cells: " << misses << " of "
                            << points;
      std::printf(
          "level %d, %g m cells: %zu tets, %zu leaves, %zu nodes (%.1f bytes/tet), depth max %d, mean "
          "%.2f\n",
          which, double(cellSize), level.tets.size(), g.leaves, g.nodes.size(),
          double(cellGridBytes(g)) / double(level.tets.size()), g.maxDepth, g.meanDepth);
    }
  }
}

// The default tree stops at kDefaultLeafTets tets a leaf and names the tet holding the leaf region's centre:
// it has fewer nodes than the one-tet tree (memory, docs/point_location.md), and from the leaf's tet the tet
// holding a point is at most kDefaultLeafTets - 1 face steps away (the tets meeting a convex region are
// connected through faces meeting it, and the leaf's list holds all of them), and locate() still answers
// with that tet. Would fail if a leaf were made with more tets than the stop, or named a tet off its region.
TEST(CellGrid, SmallLeavesNameATetAFewStepsFromThePoint) {
  for (int which = 0; which < 3; ++which) {
    const Level level = which == 0 ? ballLevel() : which == 1 ? boxLevel() : latticeLevel();
    const CellGrid one = buildCellGrid(level.probes, level.tets, 16.0f, 2, 1);
    const CellGrid g = buildCellGrid(level.probes, level.tets, 16.0f, 2);
    EXPECT_LT(3 * g.nodes.size(), 2 * one.nodes.size()) << "level " << which;
    EXPECT_EQ(g.leaves, g.nodes.size() + occupiedCells(g));
    Level withGrid = level;
    withGrid.cellGrid = g;
    const ProbeQuery query(withGrid, 16.0f, 2);
    ASSERT_EQ(query.cellGrid().nodes.size(), g.nodes.size());
    size_t hits = 0, located = 0;
    int worst = 0;
    const size_t points =
        forPointsInsideTets(level, 9 + uint64_t(which), [&](const glm::dvec3& x, int32_t t) {
          const int32_t leaf = cellGridLeaf(g, x);
          hits += leaf == t;
          const int d = leaf < 0 ? -1 : tetDistance(level, leaf, t, 8);
          worst = d < 0 ? 99 : std::max(worst, d);
          located += query.locate(level.origin + x).tet == t;
        });
    EXPECT_LE(worst, kDefaultLeafTets - 1) << "level " << which;
    EXPECT_EQ(located, points) << "level " << which;
    std::printf(
        "level %d: nodes %zu (one tet a leaf: %zu), leaf tet is the point's for %.3f, worst %d steps\n",
        which, g.nodes.size(), one.nodes.size(), double(hits) / double(points), worst);
  }
}

}  // namespace
}  // namespace tetraprobe
