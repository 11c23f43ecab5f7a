// Degenerate and extreme inputs to the CGAL backend beyond the basic rejections in test_tetrahedralize.cpp:
// each class gets a correct mesh or an InputError naming the problem (docs/degenerate_input.md).
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "tetraprobe/common/error.h"
#include "tetraprobe/tetra/quality.h"
#include "tetraprobe/tetra/tetrahedralize.h"

namespace tetraprobe {
namespace {

double totalVolume(const std::vector<glm::dvec3>& p, const TetMesh& m) {
  double v = 0.0;
  for (const auto& t : m.tets) {
    const glm::dvec3 a = p[size_t(t[1])] - p[size_t(t[0])], b = p[size_t(t[2])] - p[size_t(t[0])],
                     c = p[size_t(t[3])] - p[size_t(t[0])];
    const double d =
        a.x * (b.y * c.z - b.z * c.y) - a.y * (b.x * c.z - b.z * c.x) + a.z * (b.x * c.y - b.y * c.x);
    EXPECT_GT(d, 0.0);
    v += d / 6.0;
  }
  return v;
}

// A regular grid: every cube's corners are cospherical. Exact predicates and symbolic perturbation give
// 6 tets per cube... or 5; in any case the cubes are tiled exactly, with no flat tets.
TEST(Degenerate, RegularGridTilesItsBoxWithoutFlatTets) {
  std::vector<glm::dvec3> pts;
  for (int z = 0; z < 5; ++z)
    for (int y = 0; y < 5; ++y)
      for (int x = 0; x < 5; ++x) pts.emplace_back(x, y, z);
  const TetMesh m = tetrahedralizeDelaunay(pts);
  EXPECT_NEAR(totalVolume(pts, m), 64.0, 1e-9);
  EXPECT_GT(meshQuality(pts, m).worstMinDihedralDeg, 1.0);
}

// Millimetre and kilometre spacing in one set: the mesh is still exact and tiles the hull, and
// buildTetRecords either gives finite rows or names the tet that is too flat for float rows.
TEST(Degenerate, MillimetreAndKilometreSpacingInOneSet) {
  std::vector<glm::dvec3> pts;
  for (int z = 0; z < 3; ++z)
    for (int y = 0; y < 3; ++y)
      for (int x = 0; x < 3; ++x) {
        pts.emplace_back(x * 0.001, y * 0.001, z * 0.001);              // 1 mm cluster at the origin
        pts.emplace_back(x * 1000.0, y * 1000.0, z * 1000.0 + 5000.0);  // 1 km grid far away
      }
  const TetMesh m = tetrahedralizeDelaunay(pts);
  std::vector<bool> seen(pts.size(), false);
  for (const auto& t : m.tets)
    for (int32_t v : t) seen[size_t(v)] = true;
  for (size_t i = 0; i < pts.size(); ++i) EXPECT_TRUE(seen[i]) << i;
  EXPECT_GT(totalVolume(pts, m), 0.0);
  try {
    const auto records = buildTetRecords(pts, m, glm::dvec3(0.0));
    EXPECT_EQ(records.size(), m.tets.size());
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("too flat"), std::string::npos) << e.what();
  }
}

// Near-duplicates (1e-12 m apart) are not duplicates: they are kept, and the mesh stays valid.
TEST(Degenerate, NearDuplicatesAreKept) {
  std::vector<glm::dvec3> pts = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}, {1e-12, 0, 0}};
  const TetMesh m = tetrahedralizeDelaunay(pts);
  std::vector<bool> seen(pts.size(), false);
  for (const auto& t : m.tets)
    for (int32_t v : t) seen[size_t(v)] = true;
  for (size_t i = 0; i < pts.size(); ++i) EXPECT_TRUE(seen[i]) << i;
  EXPECT_NEAR(totalVolume(pts, m), 1.0 / 6.0, 1e-15);
}

// A sliver-prone set (points on a sphere): every tet positive even when nearly flat.
TEST(Degenerate, SliversArePositiveAndCounted) {
  std::vector<glm::dvec3> pts;
  std::mt19937_64 rng(2);
  std::normal_distribution<double> g;
  for (int i = 0; i < 400; ++i) {
    glm::dvec3 p(g(rng), g(rng), g(rng));
    pts.push_back(p / std::sqrt(p.x * p.x + p.y * p.y + p.z * p.z));
  }
  const TetMesh m = tetrahedralizeDelaunay(pts);
  totalVolume(pts, m);
  const MeshQuality q = meshQuality(pts, m);
  EXPECT_GT(q.tetsBelow10Deg, 0u);  // slivers exist and are reported, not hidden
}

// Infinity is named like NaN; coplanar input with many points is named even with duplicates absent.
TEST(Degenerate, InfinityAndLargeCoplanarSetsAreNamed) {
  std::vector<glm::dvec3> plane;
  for (int i = 0; i < 100; ++i) plane.emplace_back(i % 10, 3.0, i / 10);
  try {
    tetrahedralizeDelaunay(plane);
    ADD_FAILURE();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("coplanar"), std::string::npos);
  }
  std::vector<glm::dvec3> inf = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}, {HUGE_VAL, 0, 0}};
  EXPECT_THROW(tetrahedralizeDelaunay(inf), InputError);
}

}  // namespace
}  // namespace tetraprobe
