// Invariants of tetrahedralizeDelaunay(), checked with CGAL's exact predicates (the only test file that
// includes CGAL).
#include "tetraprobe/tetra/tetrahedralize.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <set>

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>

#include "tetraprobe/common/error.h"

namespace tetraprobe {
namespace {

using K = CGAL::Exact_predicates_inexact_constructions_kernel;

K::Point_3 cgal(const glm::dvec3& p) {
  return {p.x, p.y, p.z};
}

std::vector<glm::dvec3> randomPoints(size_t n, uint64_t seed, double scale = 10.0) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(-scale, scale);
  std::vector<glm::dvec3> pts(n);
  for (auto& p : pts) p = {u(rng), u(rng), u(rng)};
  return pts;
}

// An n^3 regular grid: every cube's 8 corners are cospherical, the worst case for Delaunay ties.
std::vector<glm::dvec3> gridPoints(int n, double spacing = 1.0) {
  std::vector<glm::dvec3> pts;
  for (int z = 0; z < n; ++z)
    for (int y = 0; y < n; ++y)
      for (int x = 0; x < n; ++x) pts.emplace_back(x * spacing, y * spacing, z * spacing);
  return pts;
}

// det[v1-v0 | v2-v0 | v3-v0] / 6: positive for a positively oriented tet.
double signedVolume(const std::vector<glm::dvec3>& p, const std::array<int32_t, 4>& t) {
  const glm::dvec3 a = p[size_t(t[1])] - p[size_t(t[0])], b = p[size_t(t[2])] - p[size_t(t[0])],
                   c = p[size_t(t[3])] - p[size_t(t[0])];
  return (a.x * (b.y * c.z - b.z * c.y) - a.y * (b.x * c.z - b.z * c.x) + a.z * (b.x * c.y - b.y * c.x)) /
         6.0;
}

std::vector<std::vector<glm::dvec3>> testSets() {
  auto sphere = randomPoints(200, 7);
  for (auto& p : sphere) p = 5.0 * p / std::sqrt(p.x * p.x + p.y * p.y + p.z * p.z);  // near-cospherical
  return {randomPoints(300, 1), gridPoints(6), sphere};
}

// The runtime indexes probes through tets only: a probe missing from the mesh would never be interpolated.
TEST(Tetrahedralize, EveryProbeIsAVertex) {
  for (const auto& pts : testSets()) {
    const TetMesh mesh = tetrahedralizeDelaunay(pts);
    std::vector<bool> seen(pts.size(), false);
    for (const auto& t : mesh.tets)
      for (int32_t v : t) {
        ASSERT_GE(v, 0);
        ASSERT_LT(size_t(v), pts.size());
        seen[size_t(v)] = true;
      }
    for (size_t i = 0; i < pts.size(); ++i) EXPECT_TRUE(seen[i]) << "probe " << i << " is in no tet";
  }
}

// Barycentric rows and the walk's "step across the most negative weight" assume positive orientation.
TEST(Tetrahedralize, TetsArePositivelyOriented) {
  for (const auto& pts : testSets()) {
    const TetMesh mesh = tetrahedralizeDelaunay(pts);
    for (size_t t = 0; t < mesh.tets.size(); ++t) {
      const auto& v = mesh.tets[t];
      EXPECT_EQ(CGAL::orientation(cgal(pts[size_t(v[0])]), cgal(pts[size_t(v[1])]), cgal(pts[size_t(v[2])]),
                                  cgal(pts[size_t(v[3])])),
                CGAL::POSITIVE)
          << "tet " << t << " (" << v[0] << ", " << v[1] << ", " << v[2] << ", " << v[3] << ")";
    }
  }
}

// The walk steps through neighbours[t][i]; a neighbour that does not share that face sends it astray.
TEST(Tetrahedralize, NeighboursAreSymmetric) {
  for (const auto& pts : testSets()) {
    const TetMesh mesh = tetrahedralizeDelaunay(pts);
    ASSERT_EQ(mesh.neighbours.size(), mesh.tets.size());
    size_t hullFaces = 0;
    for (size_t t = 0; t < mesh.tets.size(); ++t)
      for (int i = 0; i < 4; ++i) {
        const int32_t n = mesh.neighbours[t][size_t(i)];
        if (n < 0) {
          EXPECT_EQ(n, -1);
          ++hullFaces;
          continue;
        }
        ASSERT_LT(size_t(n), mesh.tets.size());
        std::set<int32_t> face(mesh.tets[t].begin(), mesh.tets[t].end());
        face.erase(mesh.tets[t][size_t(i)]);
        int back = -1;
        for (int j = 0; j < 4; ++j)
          if (mesh.neighbours[size_t(n)][size_t(j)] == int32_t(t)) back = j;
        ASSERT_GE(back, 0) << "tet " << t << " face " << i << ": neighbour " << n << " does not name it back";
        std::set<int32_t> other(mesh.tets[size_t(n)].begin(), mesh.tets[size_t(n)].end());
        other.erase(mesh.tets[size_t(n)][size_t(back)]);
        EXPECT_EQ(face, other) << "tets " << t << " and " << n << " do not share the face between them";
      }
    EXPECT_GT(hullFaces, 0u);
  }
}

// Delaunay is what keeps tets as round as the probes allow; checked exactly, so cospherical grids count.
TEST(Tetrahedralize, EmptyCircumsphere) {
  for (const auto& pts : testSets()) {
    const TetMesh mesh = tetrahedralizeDelaunay(pts);
    for (size_t t = 0; t < mesh.tets.size(); ++t) {
      const auto& v = mesh.tets[t];
      const K::Point_3 a = cgal(pts[size_t(v[0])]), b = cgal(pts[size_t(v[1])]), c = cgal(pts[size_t(v[2])]),
                       d = cgal(pts[size_t(v[3])]);
      for (size_t p = 0; p < pts.size(); ++p) {
        if (std::find(v.begin(), v.end(), int32_t(p)) != v.end()) continue;
        ASSERT_NE(CGAL::side_of_oriented_sphere(a, b, c, d, cgal(pts[p])), CGAL::ON_POSITIVE_SIDE)
            << "probe " << p << " lies inside the circumsphere of tet " << t;
      }
    }
  }
}

// Tets must tile the convex hull exactly: no gaps (unlit holes) and no overlaps (double counting).
TEST(Tetrahedralize, VolumeEqualsConvexHullVolume) {
  const glm::dvec3 size(2.0, 3.0, 5.0);
  std::vector<glm::dvec3> pts;
  for (int c = 0; c < 8; ++c)
    pts.emplace_back((c & 1) * size.x, ((c >> 1) & 1) * size.y, ((c >> 2) & 1) * size.z);
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  for (int i = 0; i < 400; ++i) pts.emplace_back(u(rng) * size.x, u(rng) * size.y, u(rng) * size.z);
  for (int i = 0; i < 40; ++i) pts.emplace_back(u(rng) * size.x, 0.0, u(rng) * size.z);  // on a hull face
  const TetMesh mesh = tetrahedralizeDelaunay(pts);
  double volume = 0.0;
  for (const auto& t : mesh.tets) {
    const double v = signedVolume(pts, t);
    EXPECT_GT(v, 0.0);
    volume += v;
  }
  EXPECT_NEAR(volume, size.x * size.y * size.z, 1e-9 * size.x * size.y * size.z);
}

// A re-bake of unchanged input must give a bit-identical level file (diffable, cacheable).
TEST(Tetrahedralize, Deterministic) {
  for (const auto& pts : testSets()) {
    const TetMesh a = tetrahedralizeDelaunay(pts), b = tetrahedralizeDelaunay(pts);
    EXPECT_EQ(a.tets, b.tets);
    EXPECT_EQ(a.neighbours, b.neighbours);
    for (const auto& t : a.tets) {  // canonical: smallest vertex first, second-smallest second
      EXPECT_LT(t[0], std::min({t[1], t[2], t[3]}));
      EXPECT_LT(t[1], std::min(t[2], t[3]));
    }
  }
}

// Each degenerate class must name the problem, not crash inside CGAL or return an empty mesh.
void expectInputError(const std::vector<glm::dvec3>& pts, const std::string& needle) {
  try {
    tetrahedralizeDelaunay(pts);
    ADD_FAILURE() << "expected InputError mentioning '" << needle << "'";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find(needle), std::string::npos) << e.what();
  }
}

TEST(Tetrahedralize, RejectsThreePoints) {
  expectInputError({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}}, "at least 4");
}

TEST(Tetrahedralize, RejectsCoplanarPoints) {
  expectInputError({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {1, 1, 0}}, "coplanar");
  expectInputError({{0, 0, 2}, {1, 0, 2}, {0, 1, 2}, {1, 1, 2}, {0.3, 0.7, 2}, {5, -2, 2}}, "coplanar");
}

TEST(Tetrahedralize, RejectsCollinearPoints) {
  expectInputError({{0, 0, 0}, {1, 1, 1}, {2, 2, 2}, {3, 3, 3}, {-4, -4, -4}}, "collinear");
}

TEST(Tetrahedralize, RejectsNonFiniteCoordinates) {
  const double nan = std::numeric_limits<double>::quiet_NaN(), inf = std::numeric_limits<double>::infinity();
  expectInputError({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, nan}}, "probe 3 has a non-finite");
  expectInputError({{0, 0, 0}, {1, 0, 0}, {0, -inf, 0}, {0, 0, 1}}, "probe 2 has a non-finite");
}

TEST(Tetrahedralize, RejectsDuplicatePoints) {
  expectInputError({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}, {1, 0, 0}}, "probes 1 and 4");
}

// Literal regression: a single tet comes out in canonical order with all hull neighbours.
TEST(Tetrahedralize, SingleTetIsCanonical) {
  const TetMesh mesh = tetrahedralizeDelaunay({{0, 0, 1}, {0, 0, 0}, {1, 0, 0}, {0, 1, 0}});
  ASSERT_EQ(mesh.tets.size(), 1u);
  EXPECT_EQ(mesh.tets[0][0], 0);
  EXPECT_EQ(mesh.neighbours[0], (std::array<int32_t, 4>{-1, -1, -1, -1}));
}

}  // namespace
}  // namespace tetraprobe
