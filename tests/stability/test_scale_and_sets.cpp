// Scale and awkward probe sets: levels 10 km and 1000 km from the world origin, spacings from 1 cm to 1 km in
// one level, coplanar / collinear subsets, near-duplicates and a perfectly regular (cospherical) lattice.
// Whole sets that are coplanar, collinear or hold exact duplicates are rejected with a named InputError:
// Tetrahedralize.RejectsCoplanarPoints / RejectsCollinearPoints / RejectsDuplicatePoints
// (tests/tetra/test_tetrahedralize.cpp) and Degenerate.InfinityAndLargeCoplanarSetsAreNamed pin those.
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "stability_checks.h"
#include "tetraprobe/common/error.h"
#include "tetraprobe/tetra/tetrahedralize.h"

namespace tetraprobe {
namespace {

using stability::checkLevel;
using stability::Figures;

// A 3x3x3 lattice of `spacing`, jittered by up to 0.3 spacing (deterministic), starting at `corner`.
std::vector<glm::dvec3> jitteredLattice(const glm::dvec3& corner, double spacing, uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(-0.3, 0.3);
  std::vector<glm::dvec3> pts;
  for (int z = 0; z < 3; ++z)
    for (int y = 0; y < 3; ++y)
      for (int x = 0; x < 3; ++x)
        pts.push_back(corner + spacing * (glm::dvec3(x, y, z) + glm::dvec3(u(rng), u(rng), u(rng))));
  return pts;
}

// 10 km and 1000 km out, with the level's local frame beside the probes (as bakes store it): the same
// answers as near the origin. Guard: ProbeQuery::locate() (runtime/src/query.cpp) subtracts the level
// origin from the world point in double; in float, 1000 km out rounds the point to 6 cm and the vertex and
// face weights fail by up to ~0.1.
TEST(Stability, TenAndThousandKmFromTheOriginKeepExactWeights) {
  for (double far : {1e4, 1e6}) {
    const glm::dvec3 corner(far, -far, 0.5 * far);
    const Level level = test::makeLevel(jitteredLattice(corner, 1.0, 2), corner + glm::dvec3(1.0), 9);
    const std::string name = "lattice " + std::to_string(int(far / 1000)) + " km out";
    checkLevel(level, name.c_str());
    ASSERT_FALSE(HasFatalFailure()) << name;
  }
}

// 1000 km out with the local frame left at the world origin, where the float spacing is 6 cm: a lattice
// whose positions are exact there is answered within the contract (a 1 cm one is refused,
// TetsFlatInFloatAreNamedAtBuild). Guard: ProbeQuery::locate() subtracting the origin in double, as above.
TEST(Stability, ThousandKmOutWithTheFrameAtTheWorldOrigin) {
  const glm::dvec3 corner(1e6, 2e5, -3e5);
  std::vector<glm::dvec3> exact;
  for (int z = 0; z < 3; ++z)
    for (int y = 0; y < 3; ++y)
      for (int x = 0; x < 3; ++x) exact.push_back(corner + glm::dvec3(x, y, z));
  checkLevel(test::makeLevel(exact, glm::dvec3(0.0), 10), "1 m lattice 1000 km out, frame at 0");
}

// Spacings from 1 cm to 1 km in one level: a 1 km box, a 10 m lattice and a 1 cm lattice inside it, off the
// local origin (so the 1 cm tets' rows, entries ~100 at 100 m, carry rounding of ~1e-3, more than the walk's
// 1e-4 band). Guard: nearFace() and clearlyInside() (runtime/src/query.cpp) compare the rows' smallest weight
// with rowErrorBound() as well as with kBoundaryBand; without that term the 1 cm tets' face points are
// decided by rows that err by 1e-3 and the exact-weight check fails.
TEST(Stability, CentimetreToKilometreSpacingInOneLevel) {
  std::vector<glm::dvec3> pts;
  for (int c = 0; c < 8; ++c) pts.emplace_back(c & 1 ? 500 : -500, c & 2 ? 500 : -500, c & 4 ? 500 : -500);
  for (const glm::dvec3& p : jitteredLattice({-150, 40, 60}, 10.0, 4)) pts.push_back(p);
  for (const glm::dvec3& p : jitteredLattice({123.4, -56.7, 89.1}, 0.01, 5)) pts.push_back(p);
  const Level level = test::makeLevel(pts, glm::dvec3(0.0), 11);
  const Figures fig = checkLevel(level, "1 cm to 1 km");
  ASSERT_FALSE(HasFatalFailure());
  EXPECT_GE(fig.worstCondition, 1e3);  // tets joining the 1 cm cluster to the 1 km box
}

// Coplanar and collinear subsets (a 5x5 planar grid with one probe above and one below; 8 probes on a line
// with four around it), and probes 1e-9 m apart near the local origin (kept: distinct floats there).
// Guard: CGAL's exact predicates in tetrahedralizeDelaunay() (tetra/src/tetrahedralize.cpp) make every tet
// positive (and these stay positive in float); the runtime's exact weights then hold.
TEST(Stability, CoplanarCollinearAndNearDuplicateSubsetsStayExact) {
  std::vector<glm::dvec3> plane;
  for (int y = 0; y < 5; ++y)
    for (int x = 0; x < 5; ++x) plane.emplace_back(x * 0.5, y * 0.5, 0.0);
  plane.emplace_back(1.0, 1.1, 0.8);
  plane.emplace_back(0.9, 1.0, -0.7);
  checkLevel(test::makeLevel(plane, glm::dvec3(1, 1, 0), 12), "coplanar subset");
  ASSERT_FALSE(HasFatalFailure());
  std::vector<glm::dvec3> line;
  for (int i = 0; i < 8; ++i) line.emplace_back(0.25 * i, 0.0, 0.0);
  for (const glm::dvec3& p :
       {glm::dvec3(1, 1, 0), glm::dvec3(1, -1, 0.1), glm::dvec3(0.8, 0, 1), glm::dvec3(1.1, 0.2, -1)})
    line.push_back(p);
  checkLevel(test::makeLevel(line, glm::dvec3(1, 0, 0), 13), "collinear subset");
  ASSERT_FALSE(HasFatalFailure());
  const std::vector<glm::dvec3> pair = {{-1, -1, -1}, {1, -1, -1}, {-1, 1, -1}, {-1, -1, 1},
                                        {1, 1, 1},    {0, 0, 0},   {1e-9, 0, 0}};
  const Level near = test::makeLevel(pair, glm::dvec3(0.0), 14);
  const Figures fig = checkLevel(near, "1e-9 apart at the origin");
  ASSERT_FALSE(HasFatalFailure());
  EXPECT_GE(fig.worstCondition, 1e8);
}

// A perfectly regular 4x4x4 lattice: every cube's corners cospherical, every query on a shared face, edge or
// vertex of several tets. Guard: CGAL's exact predicates with symbolic perturbation (tetrahedralizeDelaunay)
// give a valid mesh with no flat tets (Degenerate.RegularGridTilesItsBoxWithoutFlatTets checks the volume);
// here the answers on it are exact and continuous.
TEST(Stability, RegularLatticeIsContinuousOnEveryFace) {
  std::vector<glm::dvec3> pts;
  for (int z = 0; z < 4; ++z)
    for (int y = 0; y < 4; ++y)
      for (int x = 0; x < 4; ++x) pts.emplace_back(0.5 * x, 0.5 * y, 0.5 * z);
  const Level level = test::makeLevel(pts, glm::dvec3(1, 1, 1), 15);
  checkLevel(level, "regular lattice");
}

}  // namespace
}  // namespace tetraprobe
