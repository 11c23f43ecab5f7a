// The TetGen backend keeps the CGAL backend's contract: every probe a vertex, positive orientation
// (checked with CGAL's exact predicate), symmetric neighbours, the hull tiled exactly, determinism.
#include <gtest/gtest.h>

#include <algorithm>
#include <random>
#include <set>

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>

#include "tetraprobe/common/error.h"
#include "tetraprobe/tetra/quality.h"
#include "tetraprobe/tetra/tetrahedralize.h"

namespace tetraprobe {
namespace {

using K = CGAL::Exact_predicates_inexact_constructions_kernel;

std::vector<glm::dvec3> boxCloud(size_t n, uint64_t seed, glm::dvec3 size) {
  std::vector<glm::dvec3> pts;
  for (int c = 0; c < 8; ++c)
    pts.emplace_back((c & 1) * size.x, ((c >> 1) & 1) * size.y, ((c >> 2) & 1) * size.z);
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  for (size_t i = 0; i < n; ++i) pts.emplace_back(u(rng) * size.x, u(rng) * size.y, u(rng) * size.z);
  for (int y = 0; y < 4; ++y)  // a regular patch on a hull face: cospherical ties
    for (int x = 0; x < 4; ++x) pts.emplace_back(0.5 + x * 0.25, 0.0, 0.5 + y * 0.25);
  return pts;
}

void checkMesh(const std::vector<glm::dvec3>& pts, const TetMesh& mesh, double hullVolume) {
  ASSERT_EQ(mesh.neighbours.size(), mesh.tets.size());
  std::vector<bool> seen(pts.size(), false);
  double volume = 0.0;
  for (size_t t = 0; t < mesh.tets.size(); ++t) {
    const auto& v = mesh.tets[t];
    K::Point_3 p[4];
    for (size_t i = 0; i < 4; ++i) {
      ASSERT_GE(v[i], 0);
      ASSERT_LT(size_t(v[i]), pts.size());
      seen[size_t(v[i])] = true;
      const glm::dvec3& q = pts[size_t(v[i])];
      p[i] = K::Point_3(q.x, q.y, q.z);
    }
    ASSERT_EQ(CGAL::orientation(p[0], p[1], p[2], p[3]), CGAL::POSITIVE) << "tet " << t;
    EXPECT_LT(v[0], std::min({v[1], v[2], v[3]}));  // canonical, as the CGAL backend
    EXPECT_LT(v[1], std::min(v[2], v[3]));
    volume += CGAL::to_double(CGAL::volume(p[0], p[1], p[2], p[3]));
    for (size_t i = 0; i < 4; ++i) {
      const int32_t n = mesh.neighbours[t][i];
      if (n < 0) continue;
      std::set<int32_t> face(v.begin(), v.end());
      face.erase(v[i]);
      int back = -1;
      for (size_t j = 0; j < 4; ++j)
        if (mesh.neighbours[size_t(n)][j] == int32_t(t)) back = int(j);
      ASSERT_GE(back, 0) << "tet " << t << " neighbour " << n << " does not name it back";
      std::set<int32_t> other(mesh.tets[size_t(n)].begin(), mesh.tets[size_t(n)].end());
      other.erase(mesh.tets[size_t(n)][size_t(back)]);
      EXPECT_EQ(face, other);
    }
  }
  for (size_t i = 0; i < pts.size(); ++i) EXPECT_TRUE(seen[i]) << "probe " << i << " is in no tet";
  EXPECT_NEAR(volume, hullVolume, 1e-9 * hullVolume);
}

TEST(TetGen, DelaunayKeepsTheMeshContract) {
  const glm::dvec3 size(2.0, 3.0, 5.0);
  const auto pts = boxCloud(500, 3, size);
  const TetGenResult r = tetrahedralizeTetGen(pts);
  EXPECT_TRUE(r.steiner.empty());
  checkMesh(pts, r.mesh, size.x * size.y * size.z);
  // Same tet count as CGAL's Delaunay on points in general position inside (the regular patch allows
  // different but equally valid tie breaks, so only the count is compared).
  EXPECT_EQ(r.mesh.tets.size(), tetrahedralizeDelaunay(pts).tets.size());
}

TEST(TetGen, RefinementAppendsSteinerPointsAndKeepsProbes) {
  const glm::dvec3 size(4.0, 1.0, 4.0);
  std::vector<glm::dvec3> pts = boxCloud(200, 4, size);
  TetGenOptions opt;
  opt.refine = true;
  const TetGenResult r = tetrahedralizeTetGen(pts, opt);
  EXPECT_GT(r.steiner.size(), 0u);
  std::vector<glm::dvec3> all = pts;
  all.insert(all.end(), r.steiner.begin(), r.steiner.end());
  checkMesh(all, r.mesh, size.x * size.y * size.z);
  const MeshQuality before = meshQuality(pts, tetrahedralizeTetGen(pts).mesh);
  const MeshQuality after = meshQuality(all, r.mesh);
  EXPECT_GT(after.worstMinDihedralDeg, before.worstMinDihedralDeg);
}

TEST(TetGen, Deterministic) {
  const auto pts = boxCloud(300, 5, {2, 2, 2});
  TetGenOptions opt;
  opt.refine = true;
  const TetGenResult a = tetrahedralizeTetGen(pts, opt), b = tetrahedralizeTetGen(pts, opt);
  EXPECT_EQ(a.steiner, b.steiner);
  EXPECT_EQ(a.mesh.tets, b.mesh.tets);
  EXPECT_EQ(a.mesh.neighbours, b.mesh.neighbours);
}

void expectInputError(const std::vector<glm::dvec3>& pts, const std::string& needle) {
  try {
    tetrahedralizeTetGen(pts);
    ADD_FAILURE() << "expected InputError mentioning '" << needle << "'";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find(needle), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("tetgen"), std::string::npos) << e.what();
  }
}

// TetGen exits or returns nothing on these; the backend must name the problem first.
TEST(TetGen, DegenerateInputsAreNamed) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  expectInputError({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}}, "at least 4");
  expectInputError({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {1, 1, 0}, {3, 7, 0}}, "coplanar");
  expectInputError({{0, 0, 0}, {1, 1, 1}, {2, 2, 2}, {3, 3, 3}, {-4, -4, -4}}, "collinear");
  expectInputError({{1e30, 1e30, 1e30}, {-1e30, -1e30, -1e30}, {3e29, 3e29, 3e29}, {0, 0, 0}}, "collinear");
  expectInputError({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, nan}}, "probe 3 has a non-finite");
  expectInputError({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}, {1, 0, 0}}, "probes 1 and 4");
}

}  // namespace
}  // namespace tetraprobe
