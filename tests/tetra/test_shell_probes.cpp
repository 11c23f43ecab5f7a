// Shell probes (placeShellProbes): a lattice on the surface of the grown bounds, so the probes' hull holds
// the whole level.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <set>
#include <tuple>

#include <glm/geometric.hpp>

#include "tetraprobe/common/error.h"
#include "tetraprobe/tetra/placement.h"
#include "tetraprobe/tetra/tetrahedralize.h"

namespace tetraprobe {
namespace {

bool onBoxSurface(const glm::dvec3& p, const glm::dvec3& a, const glm::dvec3& b) {
  bool inside = true, onFace = false;
  for (int k = 0; k < 3; ++k) {
    inside = inside && p[k] >= a[k] && p[k] <= b[k];
    onFace = onFace || p[k] == a[k] || p[k] == b[k];
  }
  return inside && onFace;
}

// Every point is on the grown box's surface, once; the corners are there; neighbours along each face axis
// are at most one step apart; the count is the lattice's surface count.
TEST(ShellProbes, LatticeCoversTheGrownBoxSurfaceOnce) {
  const glm::dvec3 lo(-1.25, 0.0, 3.0), hi(6.5, 2.9, 7.1);
  const double step = 0.75;
  const std::vector<glm::dvec3> p = placeShellProbes(lo, hi, step);
  const glm::dvec3 a = lo - 0.5 * step, b = hi + 0.5 * step;
  std::set<std::tuple<double, double, double>> seen;
  for (const glm::dvec3& q : p) {
    EXPECT_TRUE(onBoxSurface(q, a, b)) << q.x << " " << q.y << " " << q.z;
    EXPECT_TRUE(seen.insert({q.x, q.y, q.z}).second) << "duplicate " << q.x << " " << q.y << " " << q.z;
  }
  for (int c = 0; c < 8; ++c) {
    const glm::dvec3 corner((c & 1) ? b.x : a.x, (c & 2) ? b.y : a.y, (c & 4) ? b.z : a.z);
    EXPECT_TRUE(seen.count({corner.x, corner.y, corner.z})) << "corner " << c;
  }
  glm::dvec3 n(0.0);
  for (int k = 0; k < 3; ++k) {
    n[k] = std::ceil((b[k] - a[k]) / step - 1e-9);
    EXPECT_LE((b[k] - a[k]) / n[k], step * (1.0 + 1e-12));
  }
  const double expected = (n.x + 1) * (n.y + 1) * (n.z + 1) - (n.x - 1) * (n.y - 1) * (n.z - 1);
  EXPECT_EQ(double(p.size()), expected);
}

// The point of the shell: the tetrahedralization of interior probes plus the shell contains the whole box
// [lo, hi] (its hull is the grown box), so no point of the level is left to the outer cells.
TEST(ShellProbes, HullOfInteriorPlusShellContainsTheBounds) {
  const glm::dvec3 lo(0.0, 0.0, 0.0), hi(4.0, 3.0, 2.0);
  std::vector<glm::dvec3> pts = {{1, 1, 1}, {3, 2, 1}, {2, 1.5, 0.5}, {1.5, 2.5, 1.5}};
  const std::vector<glm::dvec3> shell = placeShellProbes(lo, hi, 1.0);
  pts.insert(pts.end(), shell.begin(), shell.end());
  const TetMesh mesh = tetrahedralizeDelaunay(pts);
  double volume = 0.0;
  for (const auto& t : mesh.tets) {
    const glm::dvec3 a = pts[size_t(t[0])], b = pts[size_t(t[1])], c = pts[size_t(t[2])],
                     d = pts[size_t(t[3])];
    volume += std::abs(glm::dot(b - a, glm::cross(c - a, d - a))) / 6.0;
  }
  EXPECT_NEAR(volume, 5.0 * 4.0 * 3.0, 1e-9);  // the grown box, (4+1) x (3+1) x (2+1)
}

// A flat or point-like box still gets a closed shell (at least one cell per axis); bad input is an error.
TEST(ShellProbes, DegenerateBoundsAndBadStepAreHandled) {
  EXPECT_EQ(placeShellProbes({0, 0, 0}, {0, 0, 0}, 1.0).size(), 8u);
  EXPECT_EQ(placeShellProbes({0, 0, 0}, {3, 0, 0}, 1.0).size(), 5u * 2u * 2u);
  const double nan = std::numeric_limits<double>::quiet_NaN();
  EXPECT_THROW(placeShellProbes({0, 0, 0}, {1, 1, 1}, 0.0), InputError);
  EXPECT_THROW(placeShellProbes({0, 0, 0}, {1, 1, 1}, nan), InputError);
  EXPECT_THROW(placeShellProbes({0, nan, 0}, {1, 1, 1}, 1.0), InputError);
  EXPECT_THROW(placeShellProbes({0, 0, 0}, {1, -1, 1}, 1.0), InputError);
  EXPECT_THROW(placeShellProbes({0, 0, 0}, {1e4, 1e4, 1e4}, 0.01), InputError);
}

}  // namespace
}  // namespace tetraprobe
