// Outer cells (runtime/outer_cells.h): the cubic's degenerate cases on literal inputs, continuity across the
// hull boundary and across cells, finite answers far away, and path independence of the outside answer.
#include "tetraprobe/runtime/outer_cells.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <map>
#include <random>

#include <glm/geometric.hpp>

#include "test_levels.h"
#include "tetraprobe/runtime/query.h"

namespace tetraprobe {
namespace {

using test::maxDifference;
using test::probeWeights;

const glm::dvec3 kOrigin(-3000.0, 12.0, 7000.0);

// Random probes in a ball of radius 10 m: a round hull whose vertex normals all differ (a true cubic).
const Level& ballLevel() {
  static const Level level = test::makeLevel(
      [] {
        std::mt19937_64 rng(5);
        std::normal_distribution<double> n(0.0, 1.0);
        std::uniform_real_distribution<double> u(0.0, 1.0);
        std::vector<glm::dvec3> pts;
        for (int k = 0; k < 500; ++k) {
          const glm::dvec3 d = glm::normalize(glm::dvec3(n(rng), n(rng), n(rng)));
          const double r = k < 200 ? 10.0 : 10.0 * std::cbrt(u(rng));  // 200 on the sphere
          pts.push_back(kOrigin + r * d);
        }
        return pts;
      }(),
      kOrigin, 3);
  return level;
}

// A box with random probes inside: flat hull sides (parallel normals: linear and quadratic cells) and
// sharp edges and corners.
const Level& boxLevel() {
  static const Level level = test::makeLevel(
      [] {
        auto pts = test::randomBoxPoints(300, 17, {-8, -3, -5}, {6, 4, 9});
        for (auto& p : pts) p += kOrigin;
        return pts;
      }(),
      kOrigin, 4);
  return level;
}

void expectNormalized(const Location& loc) {
  float sum = 0.0f;
  for (int i = 0; i < 4; ++i) {
    ASSERT_TRUE(std::isfinite(loc.weights[i]));
    ASSERT_GE(loc.weights[i], 0.0f);
    sum += loc.weights[i];
  }
  ASSERT_NEAR(sum, 1.0f, 1e-6f);
}

glm::dvec3 probe(const Level& level, int32_t p) {
  return glm::dvec3(level.probes[size_t(p)]);
}
glm::dvec3 normalOf(const OuterCell& c, int i) {
  return {c.normal[i][0], c.normal[i][1], c.normal[i][2]};
}

std::string describe(const ProbeQuery& q, int32_t cell, const glm::dvec3& world) {
  const OuterWeights w =
      outerCellWeights(q.outerCells()[size_t(cell)], q.level().probes, world - q.level().origin);
  return " [cell " + std::to_string(cell) + ": t " + std::to_string(w.t) + ", b " + std::to_string(w.b[0]) +
         " " + std::to_string(w.b[1]) + " " + std::to_string(w.b[2]) + (w.valid ? "" : ", no root") + "]";
}

// --- the cubic on literal inputs -------------------------------------------------------------------------

// All three normals equal: det is linear in t (t^3 and t^2 vanish exactly): t = distance along the normal.
TEST(OuterCellCubic, ParallelNormalsAreLinear) {
  const std::vector<glm::vec3> probes = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
  OuterCell cell{};
  cell.v[0] = 0, cell.v[1] = 1, cell.v[2] = 2;
  for (auto& n : cell.normal) n[0] = 0, n[1] = 0, n[2] = 1, n[3] = 0;
  double c[4];
  outerCellCubic(cell, probes, {0.2, 0.3, 2.5}, c);
  EXPECT_EQ(c[3], 0.0);
  EXPECT_EQ(c[2], 0.0);
  const OuterWeights w = outerCellWeights(cell, probes, {0.2, 0.3, 2.5});
  ASSERT_TRUE(w.valid);
  EXPECT_NEAR(w.t, 2.5, 1e-12);
  EXPECT_NEAR(w.b[0], 0.5, 1e-12);
  EXPECT_NEAR(w.b[1], 0.2, 1e-12);
  EXPECT_NEAR(w.b[2], 0.3, 1e-12);
  // Below the face the straight prism is never reached for t >= 0.
  EXPECT_FALSE(outerCellWeights(cell, probes, {0.2, 0.3, -1.0}).valid);
}

// Two equal normals and one tilted: A' x B' = 0, so t^3 vanishes and the equation is quadratic.
TEST(OuterCellCubic, TwoEqualNormalsAreQuadratic) {
  const std::vector<glm::vec3> probes = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
  OuterCell cell{};
  cell.v[0] = 0, cell.v[1] = 1, cell.v[2] = 2;
  const glm::vec3 n[3] = {glm::normalize(glm::vec3(-1, 0, 2)), {0, 0, 1}, {0, 0, 1}};
  for (int i = 0; i < 3; ++i)
    cell.normal[i][0] = n[i].x, cell.normal[i][1] = n[i].y, cell.normal[i][2] = n[i].z;
  const glm::dvec3 x(0.3, 0.3, 1.7);
  double c[4];
  outerCellCubic(cell, probes, x, c);
  EXPECT_NEAR(c[3], 0.0, 1e-15);
  EXPECT_NE(c[2], 0.0);
  const OuterWeights w = outerCellWeights(cell, probes, x);
  ASSERT_TRUE(w.valid);
  // x lies on the extruded triangle it reports: rebuild it from the weights.
  glm::dvec3 back(0.0);
  for (int i = 0; i < 3; ++i) back += w.b[i] * (glm::dvec3(probes[size_t(i)]) + w.t * glm::dvec3(n[i]));
  EXPECT_LT(glm::length(back - x), 1e-12);
}

// The polynomial solver on hand-made coefficients, each degree and the edge cases.
TEST(OuterCellCubic, SmallestNonNegativeRootEveryDegree) {
  double t = -1.0;
  const double cubic[4] = {-6.0, 11.0, -6.0, 1.0};  // (t-1)(t-2)(t-3)
  ASSERT_TRUE(smallestNonNegativeRoot(cubic, 1.0, &t));
  EXPECT_NEAR(t, 1.0, 1e-14);
  const double straddle[4] = {2.0, -2.5, -3.5, 1.0};  // (t+1)(t-0.5)(t-4): negative root skipped
  ASSERT_TRUE(smallestNonNegativeRoot(straddle, 1.0, &t));
  EXPECT_NEAR(t, 0.5, 1e-14);
  const double negative[4] = {6.0, 11.0, 6.0, 1.0};  // (t+1)(t+2)(t+3): no root >= 0
  EXPECT_FALSE(smallestNonNegativeRoot(negative, 1.0, &t));
  const double quadratic[4] = {2.0, -3.0, 1.0, 0.0};  // (t-1)(t-2)
  ASSERT_TRUE(smallestNonNegativeRoot(quadratic, 1.0, &t));
  EXPECT_NEAR(t, 1.0, 1e-14);
  // A t^3 term of 1e-20 is negligible at this scale (its own root is near -1e20): still the quadratic's root.
  const double almostQuadratic[4] = {2.0, -3.0, 1.0, 1e-20};
  ASSERT_TRUE(smallestNonNegativeRoot(almostQuadratic, 1.0, &t));
  EXPECT_NEAR(t, 1.0, 1e-14);
  const double noRealRoot[4] = {1.0, 0.0, 1.0, 0.0};  // t^2 + 1
  EXPECT_FALSE(smallestNonNegativeRoot(noRealRoot, 1.0, &t));
  const double linear[4] = {2.0, -1.0, 0.0, 0.0};
  ASSERT_TRUE(smallestNonNegativeRoot(linear, 1.0, &t));
  EXPECT_NEAR(t, 2.0, 1e-15);
  const double almostLinear[4] = {2.0, -1.0, 1e-18, -1e-30};
  ASSERT_TRUE(smallestNonNegativeRoot(almostLinear, 1.0, &t));
  EXPECT_NEAR(t, 2.0, 1e-12);
  const double constant[4] = {3.0, 0.0, 0.0, 0.0};
  EXPECT_FALSE(smallestNonNegativeRoot(constant, 1.0, &t));
  const double onFace[4] = {0.0, -1.0, 0.5, 0.1};
  ASSERT_TRUE(smallestNonNegativeRoot(onFace, 1.0, &t));
  EXPECT_EQ(t, 0.0);
  const double justInside[4] = {-1e-15, -1.0, 0.0, 0.0};  // root at -1e-15: on the face within rounding
  ASSERT_TRUE(smallestNonNegativeRoot(justInside, 1.0, &t));
  EXPECT_EQ(t, 0.0);
  // Far away: roots near 1e6 with coefficients of all sizes.
  const double far[4] = {-1e6 * 2e6 * 3e6, 1e6 * 2e6 + 2e6 * 3e6 + 1e6 * 3e6, -6e6, 1.0};
  ASSERT_TRUE(smallestNonNegativeRoot(far, 1e6, &t));
  EXPECT_NEAR(t, 1e6, 1e-6);
  // Non-finite input: no root, no NaN.
  const double nan = std::numeric_limits<double>::quiet_NaN(), inf = std::numeric_limits<double>::infinity();
  const double bad1[4] = {nan, 1.0, 0.0, 0.0}, bad2[4] = {1.0, -inf, 0.0, 1.0};
  t = 7.0;
  EXPECT_FALSE(smallestNonNegativeRoot(bad1, 1.0, &t));
  EXPECT_FALSE(smallestNonNegativeRoot(bad2, 1.0, &t));
  EXPECT_EQ(t, 7.0);
}

// --- construction --------------------------------------------------------------------------------------

// Every hull face has one cell, wound outward, with unit normals pointing out of it and mutual links.
TEST(OuterCells, OnePerHullFaceOutwardAndLinked) {
  for (const Level* level : {&ballLevel(), &boxLevel()}) {
    const std::vector<OuterCell> cells = buildOuterCells(level->probes, level->tets);
    size_t hullFaces = 0;
    for (const Tet& t : level->tets)
      for (int f = 0; f < 4; ++f) hullFaces += t.n[f] < 0;
    ASSERT_EQ(cells.size(), hullFaces);
    for (size_t k = 0; k < cells.size(); ++k) {
      const OuterCell& c = cells[k];
      ASSERT_EQ(findOuterCell(cells, c.tet, c.face), int32_t(k));
      const glm::dvec3 p0 = probe(*level, c.v[0]), p1 = probe(*level, c.v[1]), p2 = probe(*level, c.v[2]);
      const glm::dvec3 opp = probe(*level, level->tets[size_t(c.tet)].v[c.face]);
      const glm::dvec3 fn = glm::normalize(glm::cross(p1 - p0, p2 - p0));
      EXPECT_GT(glm::dot(fn, p0 - opp), 0.0) << "cell " << k;
      for (int i = 0; i < 3; ++i) {
        EXPECT_NEAR(glm::length(normalOf(c, i)), 1.0, 1e-6);
        EXPECT_GT(glm::dot(normalOf(c, i), fn), 0.0) << "cell " << k;  // convex hull: within 90 degrees
        ASSERT_GE(c.n[i], 0) << "closed hull: every edge has two faces";
        const OuterCell& o = cells[size_t(c.n[i])];
        EXPECT_TRUE(o.n[0] == int32_t(k) || o.n[1] == int32_t(k) || o.n[2] == int32_t(k));
      }
    }
    EXPECT_EQ(buildOuterCells(level->probes, level->tets).size(), cells.size());
  }
}

// --- continuity -----------------------------------------------------------------------------------------

// At t = 0 a cell's weights are the hull tet's barycentrics; a hair outside, they differ by O(distance).
// Measured on random points of every hull face: the jump between the inside answer just below the face and
// the outside answer just above it, 2e-7 m apart, stays below 1e-5 plus what the tet's float rows and the gap
// explain (their slope times the rows' rounding and the gap; up to ~1e-3 on the box's flattest hull slivers).
TEST(OuterCells, ContinuousAcrossHullBoundary) {
  for (const Level* level : {&ballLevel(), &boxLevel()}) {
    const ProbeQuery q(*level);
    const std::vector<OuterCell>& cells = q.outerCells();
    std::mt19937_64 rng(31);
    std::uniform_real_distribution<double> u(0.0, 1.0);
    double worst = 0.0;
    int measured = 0;
    for (size_t k = 0; k < cells.size(); ++k) {
      const OuterCell& c = cells[k];
      const glm::dvec3 p0 = probe(*level, c.v[0]), p1 = probe(*level, c.v[1]), p2 = probe(*level, c.v[2]);
      const glm::dvec3 fn = glm::normalize(glm::cross(p1 - p0, p2 - p0));
      for (size_t s = 0; s < std::max<size_t>(8, 3000 / cells.size()); ++s) {
        double a = u(rng), b = u(rng);
        if (a + b > 1.0) a = 1.0 - a, b = 1.0 - b;
        a = 0.02 + 0.96 * a, b = 0.02 + 0.96 * b * (1.0 - a);  // keep off the edges: one face, one cell
        const glm::dvec3 on = a * p0 + b * p1 + (1.0 - a - b) * p2;
        // The cell itself at the face: exactly the triangle barycentrics.
        const OuterWeights w0 = outerCellWeights(c, level->probes, on);
        ASSERT_TRUE(w0.valid);
        EXPECT_LT(w0.t, 1e-9);
        EXPECT_NEAR(w0.b[0], a, 1e-6);
        EXPECT_NEAR(w0.b[1], b, 1e-6);
        const Location in = q.locate(level->origin + on - 1e-7 * fn);
        const Location out = q.locate(level->origin + on + 1e-7 * fn);
        expectNormalized(in);
        expectNormalized(out);
        const double jump = maxDifference(probeWeights(*level, in), probeWeights(*level, out));
        // The weights' slope (largest on hull slivers) times the 2e-7 m gap, and a rounding allowance of
        // ~1.2e-7 of |x| times it, bound the jump besides the outer cell's own.
        const BaryFrame frame = baryFrame(level->tets[size_t(in.tet)], level->probes);
        double slope = 0.0;
        glm::dvec3 sum(0.0);
        for (int r = 0; r < 3; ++r) {
          const glm::dvec3 g(frame.grad[r]);
          slope = std::max(slope, glm::length(g));
          sum += g;
        }
        slope = std::max(slope, glm::length(sum));
        const double allowed = 1e-5 + slope * (4.0 * 1.2e-7 * (glm::length(on) + 1.0) + 2e-7);
        worst = std::max(worst, jump / allowed);
        ++measured;
        ASSERT_LT(jump, allowed) << "cell " << k << " in tet " << in.tet << " (outer " << in.outerCell
                                 << "), out tet " << out.tet << " (outer " << out.outerCell << ")";
      }
    }
    std::printf("hull boundary: %d crossings, largest jump %.3g of its tolerance\n", measured, worst);
  }
}

// Neighbouring cells share their extruded edge: a point on it gets the same weights from both cells.
TEST(OuterCells, ContinuousAcrossCells) {
  for (const Level* level : {&ballLevel(), &boxLevel()}) {
    const std::vector<OuterCell> cells = buildOuterCells(level->probes, level->tets);
    std::mt19937_64 rng(32);
    std::uniform_real_distribution<double> u(0.0, 1.0);
    for (size_t k = 0; k < cells.size(); ++k)
      for (int i = 0; i < 3; ++i) {
        const OuterCell& c = cells[k];
        const OuterCell& o = cells[size_t(c.n[i])];
        const int ia = (i + 1) % 3, ib = (i + 2) % 3;
        const double s = u(rng), t = 20.0 * u(rng);
        const glm::dvec3 x = (1.0 - s) * (probe(*level, c.v[ia]) + t * normalOf(c, ia)) +
                             s * (probe(*level, c.v[ib]) + t * normalOf(c, ib));
        const OuterWeights wc = outerCellWeights(c, level->probes, x),
                           wo = outerCellWeights(o, level->probes, x);
        ASSERT_TRUE(wc.valid && wo.valid) << "cell " << k;
        std::map<int32_t, double> mc, mo;
        for (int j = 0; j < 3; ++j) mc[c.v[j]] += wc.b[j], mo[o.v[j]] += wo.b[j];
        EXPECT_LT(maxDifference(mc, mo), 1e-6) << "cell " << k << " edge " << i << " t " << t;
      }
  }
}

// --- answers outside ------------------------------------------------------------------------------------

// Far away (1 km and 1000 km) the answer is still an outer cell with finite, normalized weights, and the
// walk finds the cell the exhaustive scan finds.
TEST(OuterCells, FarPointsAreFiniteNormalizedAndMatchTheScan) {
  for (const Level* level : {&ballLevel(), &boxLevel()}) {
    const ProbeQuery q(*level);
    std::mt19937_64 rng(33);
    std::normal_distribution<double> n(0.0, 1.0);
    for (double dist : {1e3, 1e6}) {
      for (int k = 0; k < 300; ++k) {
        const glm::dvec3 x = kOrigin + dist * glm::normalize(glm::dvec3(n(rng), n(rng), n(rng)));
        const Location loc = q.locate(x), brute = q.bruteForceLocate(x);
        expectNormalized(loc);
        EXPECT_FALSE(loc.inside);
        ASSERT_GE(loc.outerCell, 0) << dist;
        ASSERT_GE(brute.outerCell, 0) << dist;
        EXPECT_LT(maxDifference(probeWeights(*level, loc), probeWeights(*level, brute)), 1e-5)
            << "distance " << dist << " point " << k << ": walk cell " << loc.outerCell << ", scan cell "
            << brute.outerCell << describe(q, loc.outerCell, x) << describe(q, brute.outerCell, x);
        const glm::vec3 e = q.irradiance(x, glm::vec3(0, 1, 0));
        EXPECT_TRUE(std::isfinite(e.x) && std::isfinite(e.y) && std::isfinite(e.z));
      }
    }
  }
}

// Outside the hull the hint (and so the hull face the walk leaves by) must not change the answer.
TEST(OuterCells, OutsideAnswerIndependentOfHint) {
  for (const Level* level : {&ballLevel(), &boxLevel()}) {
    const ProbeQuery q(*level);
    std::mt19937_64 rng(34);
    std::uniform_real_distribution<double> u(-30.0, 30.0);
    std::uniform_int_distribution<int32_t> anyTet(0, int32_t(level->tets.size()) - 1);
    int outside = 0;
    for (int k = 0; k < 3000; ++k) {
      const glm::dvec3 x = kOrigin + glm::dvec3(u(rng), u(rng), u(rng));
      const Location ref = q.locate(x);
      if (ref.inside) continue;
      ++outside;
      const auto expected = probeWeights(*level, ref);
      EXPECT_LT(maxDifference(probeWeights(*level, q.bruteForceLocate(x)), expected), 1e-5) << k;
      for (int h = 0; h < 4; ++h) {
        const int32_t hint = anyTet(rng);
        ASSERT_LT(maxDifference(probeWeights(*level, q.locate(x, hint)), expected), 1e-5)
            << "point " << k << " hint " << hint;
      }
    }
    EXPECT_GT(outside, 1000);
  }
}

// Moving the level (probes and origin) by 10 km moves its answers with it.
TEST(OuterCells, TranslationBy10KmKeepsAnswers) {
  const glm::dvec3 shift(10'000.0, -4'000.0, 7'500.0);
  const Level& a = ballLevel();
  std::vector<glm::dvec3> moved;
  for (const glm::vec3& p : a.probes) moved.push_back(a.origin + glm::dvec3(p) + shift);
  const Level b = test::makeLevel(moved, a.origin + shift, 3);
  const ProbeQuery qa(a), qb(b);
  std::mt19937_64 rng(35);
  std::uniform_real_distribution<double> u(-40.0, 40.0);
  std::normal_distribution<float> n(0.0f, 1.0f);
  for (int k = 0; k < 3000; ++k) {
    const glm::dvec3 x = a.origin + glm::dvec3(u(rng), u(rng), u(rng));
    const glm::vec3 normal = glm::normalize(glm::vec3(n(rng), n(rng), n(rng)));
    const glm::vec3 ea = qa.irradiance(x, normal), eb = qb.irradiance(x + shift, normal);
    for (int c = 0; c < 3; ++c)
      ASSERT_NEAR(ea[c], eb[c], 1e-5f * std::max(1.0f, std::abs(ea[c]))) << "point " << k;
  }
}

}  // namespace
}  // namespace tetraprobe
