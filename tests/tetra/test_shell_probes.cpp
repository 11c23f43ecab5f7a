// Shell probes (placeShellProbes): a lattice on the surface of the grown bounds, so the probes' hull holds
// the whole level.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <set>
#include <stdexcept>
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

// The thinned shell: with a ground plane at y = 0 (the bounds' bottom), the points within 2 m of it keep the
// full lattice, the rest of the box keeps only the coarse sub-lattice; every kept point is a point of the
// full lattice; the corners are kept, so the hull of interior probes plus the thinned shell is still the
// whole grown box.
TEST(ShellProbes, ThinnedShellKeepsTheFullLatticeNearGeometryAndTheHull) {
  const glm::dvec3 lo(0.0, 0.0, 0.0), hi(24.0, 5.0, 16.0);
  const double step = 1.0, farStep = 8.0;
  const auto nearGround = [](const std::vector<glm::dvec3>& pts) {
    std::vector<uint8_t> out(pts.size());
    for (size_t i = 0; i < pts.size(); ++i) out[i] = std::abs(pts[i].y) <= 2.0;
    return out;
  };
  const std::vector<glm::dvec3> full = placeShellProbes(lo, hi, step);
  const std::vector<glm::dvec3> thin = placeShellProbes(lo, hi, step, farStep, nearGround);
  std::set<std::tuple<double, double, double>> fullSet, thinSet;
  for (const glm::dvec3& q : full) fullSet.insert({q.x, q.y, q.z});
  for (const glm::dvec3& q : thin) {
    EXPECT_TRUE(fullSet.count({q.x, q.y, q.z})) << "not a lattice point " << q.x << " " << q.y << " " << q.z;
    EXPECT_TRUE(thinSet.insert({q.x, q.y, q.z}).second);
  }
  size_t nearInFull = 0;
  for (const glm::dvec3& q : full) {
    if (std::abs(q.y) > 2.0) continue;
    ++nearInFull;
    EXPECT_TRUE(thinSet.count({q.x, q.y, q.z})) << "near point dropped " << q.x << " " << q.y << " " << q.z;
  }
  // Far from the ground only the coarse sub-lattice is left: every far point has its face coordinates on
  // multiples of farStep from the grown box's low corner (or on its high corner).
  const glm::dvec3 a = lo - 0.5 * step, b = hi + 0.5 * step;
  size_t far = 0;
  for (const glm::dvec3& q : thin) {
    if (!(std::abs(q.y) > 2.0)) continue;
    ++far;
    for (int k = 0; k < 3; ++k) {
      const double m = std::fmod(q[k] - a[k], farStep);
      EXPECT_TRUE(q[k] == b[k] || std::min(m, farStep - m) < 1e-9) << "axis " << k << " at " << q[k];
    }
  }
  EXPECT_EQ(thin.size(), nearInFull + far);
  EXPECT_LT(thin.size(), full.size() * 6 / 10);  // the top and sides thinned
  EXPECT_GT(far, 0u);
  // The hull is still the grown box.
  std::vector<glm::dvec3> pts = {{5, 1, 5}, {12, 3, 8}, {20, 2, 3}, {7, 4, 12}};
  pts.insert(pts.end(), thin.begin(), thin.end());
  const TetMesh mesh = tetrahedralizeDelaunay(pts);
  double volume = 0.0;
  for (const auto& t : mesh.tets) {
    const glm::dvec3 a = pts[size_t(t[0])], b = pts[size_t(t[1])], c = pts[size_t(t[2])],
                     d = pts[size_t(t[3])];
    volume += std::abs(glm::dot(b - a, glm::cross(c - a, d - a))) / 6.0;
  }
  EXPECT_NEAR(volume, 25.0 * 6.0 * 17.0, 1e-6);
}

// With every point near geometry, or a far step no larger than the step, the thinned shell is the full one
// (a closed level's shell is unchanged); a query answering the wrong count is a logic error.
TEST(ShellProbes, ThinnedShellIsTheFullShellWhereEverythingIsNear) {
  const glm::dvec3 lo(-1.0, 0.5, 2.0), hi(9.0, 4.0, 7.5);
  const auto all = [](const std::vector<glm::dvec3>& pts) { return std::vector<uint8_t>(pts.size(), 1); };
  const auto none = [](const std::vector<glm::dvec3>& pts) { return std::vector<uint8_t>(pts.size(), 0); };
  const std::vector<glm::dvec3> full = placeShellProbes(lo, hi, 0.5);
  EXPECT_EQ(placeShellProbes(lo, hi, 0.5, 10.0, all), full);
  EXPECT_EQ(placeShellProbes(lo, hi, 0.5, 0.5, none), full);
  EXPECT_EQ(placeShellProbes(lo, hi, 0.5, 10.0, nullptr), full);
  const auto wrong = [](const std::vector<glm::dvec3>& pts) { return std::vector<uint8_t>(pts.size() / 2); };
  EXPECT_THROW(placeShellProbes(lo, hi, 0.5, 10.0, wrong), std::logic_error);
}

}  // namespace
}  // namespace tetraprobe
