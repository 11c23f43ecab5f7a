// Shell probes: a lattice on the level's bounding box grown by half a step, so the probes' convex hull holds
// every surface and per-tet occlusion, not outer-cell extrapolation, answers surfaces near the level's
// outside. Contract: tetra/placement.h (placeShellProbes).
#include <cmath>
#include <string>

#include "tetraprobe/common/error.h"
#include "tetraprobe/tetra/placement.h"

namespace tetraprobe {

std::vector<glm::dvec3> placeShellProbes(const glm::dvec3& lo, const glm::dvec3& hi, double step,
                                         size_t maxProbes) {
  if (!std::isfinite(step) || step <= 0.0)
    throw InputError("shell probes: step " + std::to_string(step) + " m must be positive and finite");
  for (int a = 0; a < 3; ++a)
    if (!std::isfinite(lo[a]) || !std::isfinite(hi[a]) || hi[a] < lo[a])
      throw InputError("shell probes: the level bounds are empty or not finite");
  const glm::dvec3 a = lo - 0.5 * step, b = hi + 0.5 * step;
  glm::dvec3 cells;
  for (int k = 0; k < 3; ++k) cells[k] = std::max(1.0, std::ceil((b[k] - a[k]) / step - 1e-9));
  // Points on the box surface: all lattice points minus the interior ones (checked before allocating).
  const double all = (cells.x + 1.0) * (cells.y + 1.0) * (cells.z + 1.0);
  const double interior =
      std::max(0.0, cells.x - 1.0) * std::max(0.0, cells.y - 1.0) * std::max(0.0, cells.z - 1.0);
  if (!(all - interior <= double(maxProbes)))
    throw InputError("shell probes: more than " + std::to_string(maxProbes) + " probes at a step of " +
                     std::to_string(step) + " m; use a larger spacing");
  const int64_t nx = int64_t(cells.x), ny = int64_t(cells.y), nz = int64_t(cells.z);
  std::vector<glm::dvec3> out;
  out.reserve(size_t(all - interior));
  for (int64_t z = 0; z <= nz; ++z)
    for (int64_t y = 0; y <= ny; ++y) {
      const bool faceYZ = z == 0 || z == nz || y == 0 || y == ny;
      for (int64_t x = 0; x <= nx; x += (faceYZ || x == nx) ? 1 : nx) {
        // The last point of each axis is placed exactly on b (no accumulated rounding).
        const glm::dvec3 p(x == nx ? b.x : a.x + (b.x - a.x) * double(x) / double(nx),
                           y == ny ? b.y : a.y + (b.y - a.y) * double(y) / double(ny),
                           z == nz ? b.z : a.z + (b.z - a.z) * double(z) / double(nz));
        out.push_back(p);
      }
    }
  return out;
}

}  // namespace tetraprobe
