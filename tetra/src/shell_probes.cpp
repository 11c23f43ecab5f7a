// Shell probes: a lattice on the level's bounding box grown by half a step, so the probes' convex hull holds
// every surface and per-tet occlusion, not outer-cell extrapolation, answers surfaces near the level's
// outside. Contract: tetra/placement.h (placeShellProbes).
#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include "tetraprobe/common/error.h"
#include "tetraprobe/tetra/placement.h"

namespace tetraprobe {

namespace {

// The lattice of placeShellProbes: its cell counts per axis and its corners, checked before allocating.
struct ShellLattice {
  glm::dvec3 a{0.0}, b{0.0};
  int64_t n[3] = {1, 1, 1};
  glm::dvec3 point(int64_t x, int64_t y, int64_t z) const {
    // The last point of each axis is placed exactly on b (no accumulated rounding).
    return {x == n[0] ? b.x : a.x + (b.x - a.x) * double(x) / double(n[0]),
            y == n[1] ? b.y : a.y + (b.y - a.y) * double(y) / double(n[1]),
            z == n[2] ? b.z : a.z + (b.z - a.z) * double(z) / double(n[2])};
  }
  // Visits every point of the box surface once, z, then y, then x.
  template <class F>
  void forEach(F&& f) const {
    for (int64_t z = 0; z <= n[2]; ++z)
      for (int64_t y = 0; y <= n[1]; ++y) {
        const bool faceYZ = z == 0 || z == n[2] || y == 0 || y == n[1];
        for (int64_t x = 0; x <= n[0]; x += (faceYZ || x == n[0]) ? 1 : n[0]) f(x, y, z);
      }
  }
};

ShellLattice shellLattice(const glm::dvec3& lo, const glm::dvec3& hi, double step, size_t maxProbes) {
  if (!std::isfinite(step) || step <= 0.0)
    throw InputError("shell probes: step " + std::to_string(step) + " m must be positive and finite");
  for (int a = 0; a < 3; ++a)
    if (!std::isfinite(lo[a]) || !std::isfinite(hi[a]) || hi[a] < lo[a])
      throw InputError("shell probes: the level bounds are empty or not finite");
  ShellLattice l;
  l.a = lo - 0.5 * step;
  l.b = hi + 0.5 * step;
  glm::dvec3 cells;
  for (int k = 0; k < 3; ++k) cells[k] = std::max(1.0, std::ceil((l.b[k] - l.a[k]) / step - 1e-9));
  // Points on the box surface: all lattice points minus the interior ones (checked before allocating).
  const double all = (cells.x + 1.0) * (cells.y + 1.0) * (cells.z + 1.0);
  const double interior =
      std::max(0.0, cells.x - 1.0) * std::max(0.0, cells.y - 1.0) * std::max(0.0, cells.z - 1.0);
  if (!(all - interior <= double(maxProbes)))
    throw InputError("shell probes: more than " + std::to_string(maxProbes) + " probes at a step of " +
                     std::to_string(step) + " m; use a larger spacing");
  for (int k = 0; k < 3; ++k) l.n[k] = int64_t(cells[k]);
  return l;
}

}  // namespace

std::vector<glm::dvec3> placeShellProbes(const glm::dvec3& lo, const glm::dvec3& hi, double step,
                                         size_t maxProbes) {
  const ShellLattice l = shellLattice(lo, hi, step, maxProbes);
  std::vector<glm::dvec3> out;
  l.forEach([&](int64_t x, int64_t y, int64_t z) { out.push_back(l.point(x, y, z)); });
  return out;
}

std::vector<glm::dvec3> placeShellProbes(const glm::dvec3& lo, const glm::dvec3& hi, double step,
                                         double farStep, const NearGeometryQuery& nearGeometry,
                                         size_t maxProbes) {
  if (!std::isfinite(farStep))
    throw InputError("shell probes: far step " + std::to_string(farStep) + " m must be finite");
  const ShellLattice l = shellLattice(lo, hi, step, maxProbes);
  const int64_t k = farStep > step && nearGeometry ? std::max<int64_t>(1, int64_t(farStep / step)) : 1;
  auto coarse = [&](int64_t i, int axis) { return i % k == 0 || i == l.n[axis]; };
  // Points off the coarse sub-lattice are kept where the query says they are near geometry: asked in one
  // batch, in visiting order, then the lattice visited again in the same order.
  std::vector<glm::dvec3> candidates;
  l.forEach([&](int64_t x, int64_t y, int64_t z) {
    if (!(coarse(x, 0) && coarse(y, 1) && coarse(z, 2))) candidates.push_back(l.point(x, y, z));
  });
  std::vector<uint8_t> near;
  if (!candidates.empty()) {
    near = nearGeometry(candidates);
    if (near.size() != candidates.size())
      throw std::logic_error("shell probes: the near-geometry query answered " + std::to_string(near.size()) +
                             " of " + std::to_string(candidates.size()) + " points");
  }
  std::vector<glm::dvec3> out;
  size_t c = 0;
  l.forEach([&](int64_t x, int64_t y, int64_t z) {
    if (coarse(x, 0) && coarse(y, 1) && coarse(z, 2))
      out.push_back(l.point(x, y, z));
    else if (near[c++])
      out.push_back(l.point(x, y, z));
  });
  return out;
}

}  // namespace tetraprobe
