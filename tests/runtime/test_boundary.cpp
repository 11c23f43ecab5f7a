// Points on tet faces, edges and vertices (or within rounding of them) of sliver-rich levels, near the origin
// and 10 km from it: ProbeQuery::locate must name a tet that holds the point with exact weights within
// [-1e-6, 1 + 1e-6], report those weights to 1e-6, and give the interpolation of a tet that an exact-predicate
// brute force (CGAL::orientation over every tet) finds holding the point.
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <random>
#include <vector>

#include <glm/geometric.hpp>

#include "test_levels.h"
#include "tetraprobe/runtime/query.h"
#include "tetraprobe/runtime/sh.h"

namespace tetraprobe {
namespace {

using K = CGAL::Exact_predicates_inexact_constructions_kernel;

// A jittered lattice: nearly cospherical everywhere, so the Delaunay tetrahedralization is full of slivers.
std::vector<glm::dvec3> sliverPoints(const glm::dvec3& at, double jitter, uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(-jitter, jitter);
  std::vector<glm::dvec3> pts;
  for (int z = 0; z < 6; ++z)
    for (int y = 0; y < 5; ++y)
      for (int x = 0; x < 7; ++x) pts.push_back(at + glm::dvec3(x + u(rng), y + u(rng), z + u(rng)) * 1.5);
  return pts;
}

// Tets that hold local point x by exact predicates (every face's orientation with x agrees with the tet's,
// or is zero).
std::vector<int32_t> exactContainers(const Level& level, const glm::dvec3& x) {
  std::vector<int32_t> out;
  const K::Point_3 q(x.x, x.y, x.z);
  for (size_t t = 0; t < level.tets.size(); ++t) {
    K::Point_3 p[4];
    for (int i = 0; i < 4; ++i) {
      const glm::vec3& v = level.probes[size_t(level.tets[t].v[i])];
      p[i] = K::Point_3(v.x, v.y, v.z);
    }
    const CGAL::Orientation o = CGAL::orientation(p[0], p[1], p[2], p[3]);
    bool inside = o != CGAL::COPLANAR;
    for (int i = 0; i < 4 && inside; ++i) {
      K::Point_3 r[4] = {p[0], p[1], p[2], p[3]};
      r[i] = q;
      const CGAL::Orientation s = CGAL::orientation(r[0], r[1], r[2], r[3]);
      inside = s == o || s == CGAL::COPLANAR;
    }
    if (inside) out.push_back(int32_t(t));
  }
  return out;
}

std::map<int32_t, double> exactProbeWeights(const Level& level, int32_t tet, const glm::dvec3& x) {
  double w[4];
  test::exactTetWeights(level, level.tets[size_t(tet)], x, w);
  std::map<int32_t, double> m;
  for (int i = 0; i < 4; ++i)
    if (w[i] != 0.0) m[level.tets[size_t(tet)].v[i]] += w[i];
  return m;
}

// Vertices, edge points and face points of every tet (random and exactly midway), through locate() with no
// hint and with a hint: the named tet's exact weights lie in [-1e-6, 1 + 1e-6], the reported weights match
// them to 1e-6, and the interpolation is that of a tet the exact predicates find holding the point.
void checkBoundaryPoints(const Level& level, const char* what) {
  const ProbeQuery q(level, 4.0f, 1);
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::uniform_int_distribution<int32_t> anyTet(0, int32_t(level.tets.size()) - 1);
  size_t checked = 0, slivers = 0;
  std::vector<glm::dvec3> all;
  for (size_t t = 0; t < level.tets.size(); ++t) {
    glm::dvec3 p[4];
    for (int i = 0; i < 4; ++i) p[i] = glm::dvec3(level.probes[size_t(level.tets[t].v[i])]);
    const double volume = std::abs(glm::dot(p[0] - p[3], glm::cross(p[1] - p[3], p[2] - p[3]))) / 6.0;
    slivers += volume < 0.01 * 1.5 * 1.5 * 1.5;
    const double a = u(rng), b = u(rng) * (1.0 - a);
    const glm::dvec3 points[] = {p[t % 4], 0.5 * (p[0] + p[1]), a * p[2] + (1.0 - a) * p[3],
                                 a * p[0] + b * p[1] + (1.0 - a - b) * p[2], (p[1] + p[2] + p[3]) / 3.0};
    for (const glm::dvec3& x : points) {
      const glm::dvec3 world = level.origin + x;
      all.push_back(world);
      const std::vector<int32_t> holders = exactContainers(level, world - level.origin);
      if (holders.empty()) continue;  // rounded just outside the hull: the outer cells' business
      for (int32_t hint : {int32_t(-1), anyTet(rng)}) {
        const Location loc = q.locate(world, hint);
        ASSERT_GE(loc.tet, 0);
        ASSERT_TRUE(loc.inside) << what << " tet " << t;
        double w[4];
        test::exactTetWeights(level, level.tets[size_t(loc.tet)], world - level.origin, w);
        for (int i = 0; i < 4; ++i) {
          ASSERT_GE(w[i], -1e-6) << what << ": tet " << t << " point (" << x.x << ", " << x.y << ", " << x.z
                                 << ") named tet " << loc.tet << ", hint " << hint;
          ASSERT_LE(w[i], 1.0 + 1e-6) << what << ": tet " << t;
          ASSERT_NEAR(loc.weights[i], w[i], 1e-6)
              << what << ": tet " << t << " named tet " << loc.tet << " hint " << hint << " w " << w[0] << " "
              << w[1] << " " << w[2] << " " << w[3] << " got " << loc.weights[0] << " " << loc.weights[1]
              << " " << loc.weights[2] << " " << loc.weights[3];
        }
        const double d = test::maxDifference(test::probeWeights(level, loc),
                                             exactProbeWeights(level, holders[0], world - level.origin));
        ASSERT_LE(d, 1e-6) << what << ": tet " << t << " named tet " << loc.tet << ", exact holder "
                           << holders[0] << " of " << holders.size();
        ++checked;
      }
    }
  }
  // The batch (interleaved, trying the previous point's tet) answers these exactly as single queries.
  std::vector<glm::vec3> normal(all.size(), glm::normalize(glm::vec3(0.3f, 1.0f, -0.2f))), batch(all.size());
  q.irradianceBatch(all.data(), normal.data(), batch.data(), all.size(), 2);
  for (size_t i = 0; i < all.size(); ++i)
    ASSERT_EQ(batch[i], q.irradiance(all[i], normal[i])) << what << " " << i;
  EXPECT_GT(slivers, 0u) << what << ": the level should hold slivers";
  EXPECT_GT(checked, 4 * level.tets.size()) << what;
}

TEST(Locate, BoundaryPointsGetWeightsWithinToleranceOnSlivers) {
  const glm::dvec3 at(-4.0, 1.0, 2.0);
  checkBoundaryPoints(test::makeLevel(sliverPoints(at, 0.02, 5), at + glm::dvec3(4.0), 2), "slivers");
}

// 10 km from the world origin, with the local frame there (as bakes store it) and, harder, with the local
// frame left at the world origin: float probe positions 10 km out, rows rounded at that scale.
TEST(Locate, BoundaryPointsGetWeightsWithinToleranceTenKmOut) {
  const glm::dvec3 at(10'000.0, 35.0, -10'000.0);
  checkBoundaryPoints(test::makeLevel(sliverPoints(at, 0.02, 6), at + glm::dvec3(4.0), 3), "10 km, local");
  checkBoundaryPoints(test::makeLevel(sliverPoints(at, 0.02, 7), glm::dvec3(0.0), 4), "10 km, world");
}

// Irradiance E(n) of local point x answered from tet `tet` with its exact weights (clamped to >= 0, as locate()
// clamps): the public SH API (shBlend, shIrradiance) on the tet's four probes, in the order tet.v[] names
// them, or rotated by `rotate` places (the test's own control: a wrong probe order). `scale` gets the sum of
// the magnitudes of the terms E is made of (sum over coefficients of |A_l Y(n)| sum_k w_k |SH_k|): float
// rounding is relative to that, not to |E|, which may cancel to near 0.
glm::vec3 irradianceFromTet(const Level& level, int32_t tet, const glm::dvec3& x, const glm::vec3& normal,
                            int rotate, double* scale) {
  const Tet& t = level.tets[size_t(tet)];
  double w[4];
  test::exactTetWeights(level, t, x, w);
  const ShRgb* probes[4];
  float wf[4];
  for (int i = 0; i < 4; ++i) {
    probes[i] = &level.sh[size_t(t.v[(i + rotate) % 4])];
    wf[i] = float(std::max(w[i], 0.0));
  }
  const auto y = shBasis<double>(normal.x, normal.y, normal.z);
  *scale = 0.0;
  for (int c = 0; c < kShCoeffCount; ++c)
    for (int i = 0; i < 4; ++i)
      for (int ch = 0; ch < 3; ++ch)
        *scale +=
            std::abs(y[size_t(c)] * shCosineLobe(c)) * double(wf[i]) * std::abs(double(probes[i]->c[c][ch]));
  return shIrradiance(shBlend(probes, wf, 4), normal);
}

double relativeDifference(const glm::vec3& a, const glm::vec3& b, double scale) {
  double d = 0.0;
  for (int ch = 0; ch < 3; ++ch) d = std::max(d, std::abs(double(a[ch]) - double(b[ch])));
  return d / scale;
}

// Points shared by two or more tets (every tet's vertices, edge midpoints and edge points, face points and
// centroids of sliver-rich and cospherical levels): the irradiance answered from each tet holding the point
// (exact weights within 1e-9 of [0, 1], through shBlend/shIrradiance), and the query's own answers
// (irradiance() without a hint, with each holder as the cached tet, and irradianceBatch) agree to 1e-6
// relative. Why 1e-6: the weights agree to ~1e-12 across holders (exact signed volumes), float weights and
// the float blend + 9-term sum add at most ~15 roundings of 2^-24 of the terms' magnitudes (~1e-6 in the
// worst case, ~1e-7 typically), so a correct pipeline stays inside it, while a wrong probe order or weights
// off by more than ~1e-6 (the rows' own error on slivers reaches 1e-4) leave it. The control checks that:
// the same points with one holder's probes rotated must fail the check.
void checkIrradianceWhereTetsSharePoint(const Level& level, const char* what) {
  const ProbeQuery q(level, 4.0f, 1);
  std::mt19937_64 rng(9);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::normal_distribution<float> g(0.0f, 1.0f);
  std::vector<glm::dvec3> shared;  // world
  std::vector<glm::vec3> normals;
  std::vector<std::vector<int32_t>> holders;
  size_t vertices = 0, edges = 0, faces = 0;
  for (size_t t = 0; t < level.tets.size(); ++t) {
    glm::dvec3 p[4];
    for (int i = 0; i < 4; ++i) p[i] = glm::dvec3(level.probes[size_t(level.tets[t].v[i])]);
    const double a = u(rng), b = u(rng) * (1.0 - a);
    const glm::dvec3 points[] = {p[t % 4],                                          // a vertex
                                 0.5 * (p[0] + p[1]), a * p[2] + (1.0 - a) * p[3],  // edges
                                 a * p[0] + b * p[1] + (1.0 - a - b) * p[2],
                                 (p[1] + p[2] + p[3]) / 3.0};  // faces
    for (int k = 0; k < 5; ++k) {
      const glm::dvec3& x = points[k];
      std::vector<int32_t> h;
      for (size_t s = 0; s < level.tets.size(); ++s) {
        double w[4];
        test::exactTetWeights(level, level.tets[s], x, w);
        if (std::min({w[0], w[1], w[2], w[3]}) >= -1e-9) h.push_back(int32_t(s));
      }
      if (h.size() < 2) continue;  // on the hull: one tet (and the outer cells)
      (k == 0 ? vertices : k < 3 ? edges : faces) += 1;
      shared.push_back(level.origin + x);
      normals.push_back(glm::normalize(glm::vec3(g(rng), g(rng), g(rng)) + glm::vec3(0.0f, 1e-3f, 0.0f)));
      holders.push_back(std::move(h));
    }
  }
  ASSERT_GT(vertices, 0u) << what;
  ASSERT_GT(edges, level.tets.size() / 2) << what;
  ASSERT_GT(faces, level.tets.size() / 2) << what;
  std::vector<glm::vec3> batch(shared.size());
  q.irradianceBatch(shared.data(), normals.data(), batch.data(), shared.size(), 2);
  double worst = 0.0;
  size_t controlCaught = 0;
  for (size_t i = 0; i < shared.size() && !::testing::Test::HasFailure(); ++i) {  // stop at the first
    const glm::dvec3 x = shared[i] - level.origin;
    double scale = 0.0;
    const glm::vec3 ref = irradianceFromTet(level, holders[i][0], x, normals[i], 0, &scale);
    const auto expectAgrees = [&](const glm::vec3& e, const char* from, int32_t tet) {
      const double r = relativeDifference(e, ref, scale);
      worst = std::max(worst, r);
      ASSERT_LE(r, 1e-6) << what << ": point (" << x.x << ", " << x.y << ", " << x.z << "), " << from << " "
                         << tet << " gives (" << e.x << ", " << e.y << ", " << e.z << "), tet "
                         << holders[i][0] << " (" << ref.x << ", " << ref.y << ", " << ref.z << "); "
                         << holders[i].size() << " tets hold the point";
    };
    for (int32_t h : holders[i]) {
      double s = 0.0;
      expectAgrees(irradianceFromTet(level, h, x, normals[i], 0, &s), "holder", h);
      int32_t cache = h;  // the cached-tet walk starting in this holder
      expectAgrees(q.irradiance(shared[i], normals[i], &cache), "irradiance() cached from", h);
    }
    expectAgrees(q.irradiance(shared[i], normals[i]), "irradiance() from tet", q.locate(shared[i]).tet);
    expectAgrees(batch[i], "irradianceBatch from tet", q.locate(shared[i]).tet);
    double s = 0.0;
    const glm::vec3 wrong = irradianceFromTet(level, holders[i][1], x, normals[i], 1, &s);
    controlCaught += relativeDifference(wrong, ref, scale) > 1e-6;
  }
  EXPECT_GT(controlCaught, shared.size() * 9 / 10) << what << ": a wrong probe order should fail the check";
  std::printf("[ %s: %zu shared points (%zu vertices, %zu edges, %zu faces), worst %.2g relative ]\n", what,
              shared.size(), vertices, edges, faces, worst);
}

TEST(Locate, IrradianceAgreesWhereTetsSharePoint) {
  const glm::dvec3 at(-4.0, 1.0, 2.0);
  checkIrradianceWhereTetsSharePoint(test::makeLevel(sliverPoints(at, 0.02, 5), at + glm::dvec3(4.0), 2),
                                     "slivers");
  const glm::dvec3 far(10'000.0, 35.0, -10'000.0);
  checkIrradianceWhereTetsSharePoint(test::makeLevel(sliverPoints(far, 0.02, 7), glm::dvec3(0.0), 4),
                                     "10 km, world frame");
  checkIrradianceWhereTetsSharePoint(test::makeLevel(sliverPoints(at, 0.0, 8), at, 5), "cospherical lattice");
}

}  // namespace
}  // namespace tetraprobe
