// After placement: probes inside or on geometry are pushed out or rejected (the inside rule is Unity APV's,
// > 25 % back-face hits; the escape move is in the spirit of its "virtual offset"), then near-coincident
// probes are merged through hash grids (no quadratic loops; Godot's lightmapper is the cautionary tale).
#include <algorithm>
#include <cmath>
#include <map>
#include <numeric>
#include <stdexcept>
#include <unordered_map>

#include <glm/common.hpp>
#include <glm/geometric.hpp>

#include "tetraprobe/tetra/placement.h"

namespace tetraprobe {
namespace {

constexpr double kSurfaceGap = 0.05;  // x local spacing: closest a probe may be to a surface

void keepOnly(PlacedProbes& probes, const std::vector<uint8_t>& keep) {
  PlacedProbes kept;
  for (size_t i = 0; i < probes.size(); ++i)
    if (keep[i]) kept.add(probes.positions[i], probes.kinds[i], probes.spacing[i]);
  probes = std::move(kept);
}

std::vector<Clearance> ask(const ClearanceQuery& query, const std::vector<glm::dvec3>& pts,
                           const std::vector<double>& reach) {
  std::vector<Clearance> c = query(pts, reach);
  if (c.size() != pts.size())
    throw std::logic_error("pushOutProbes: clearance query answered " + std::to_string(c.size()) + " of " +
                           std::to_string(pts.size()) + " points");
  return c;
}

// A uniform grid hashed by packed cell coordinates; cells hold probe indices.
struct HashGrid {
  double cell = 1.0;
  std::unordered_map<uint64_t, std::vector<uint32_t>> cells;
  static uint64_t key(int64_t x, int64_t y, int64_t z) {
    // Mix three signed coordinates into one key (collisions only cost extra distance checks).
    uint64_t h = uint64_t(x) * 0x9E3779B97F4A7C15ull;
    h ^= uint64_t(y) * 0xC2B2AE3D27D4EB4Full + (h << 6) + (h >> 2);
    h ^= uint64_t(z) * 0x165667B19E3779F9ull + (h << 6) + (h >> 2);
    return h;
  }
  glm::i64vec3 coord(const glm::dvec3& p) const { return glm::i64vec3(glm::floor(p / cell)); }
  void insert(const glm::dvec3& p, uint32_t i) {
    const glm::i64vec3 c = coord(p);
    cells[key(c.x, c.y, c.z)].push_back(i);
  }
  // Calls fn(index) for every stored probe in cells within `radius` of p (superset of the ball).
  template <class Fn>
  bool any(const glm::dvec3& p, double radius, Fn&& fn) const {
    const glm::i64vec3 a = coord(p - glm::dvec3(radius)), b = coord(p + glm::dvec3(radius));
    for (int64_t z = a.z; z <= b.z; ++z)
      for (int64_t y = a.y; y <= b.y; ++y)
        for (int64_t x = a.x; x <= b.x; ++x) {
          const auto it = cells.find(key(x, y, z));
          if (it == cells.end()) continue;
          for (uint32_t i : it->second)
            if (fn(i)) return true;
        }
    return false;
  }
};

}  // namespace

bool insideByRays(int rays, int hits, int backHits) {
  if (rays <= 0) return false;
  return backHits * 4 > rays || (backHits * 16 >= rays && backHits * 2 > hits);
}

PushOutStats pushOutProbes(PlacedProbes& probes, const ClearanceQuery& query) {
  PushOutStats stats;
  std::vector<size_t> ids;
  std::vector<glm::dvec3> pts;
  std::vector<double> reach;
  for (size_t i = 0; i < probes.size(); ++i) {
    if (probes.kinds[i] == ProbeKind::kUser) continue;
    ids.push_back(i);
    pts.push_back(probes.positions[i]);
    reach.push_back(probes.spacing[i]);
  }
  if (ids.empty()) return stats;
  const std::vector<Clearance> first = ask(query, pts, reach);

  std::vector<uint8_t> keep(probes.size(), 1);
  std::vector<size_t> moved;  // indices into ids
  std::vector<glm::dvec3> movedPts;
  std::vector<double> movedReach;
  std::vector<uint8_t> wasInside;
  for (size_t k = 0; k < ids.size(); ++k) {
    const Clearance& c = first[k];
    const double s = reach[k];
    if (c.inside) {
      if (glm::length(c.escape) == 0.0 || !std::isfinite(glm::length(c.escape))) {
        keep[ids[k]] = 0;
        continue;
      }
      moved.push_back(k);
      movedPts.push_back(pts[k] + 0.5 * s * glm::normalize(c.escape));
      wasInside.push_back(1);
    } else if (c.nearest < kSurfaceGap * s && glm::length(c.away) > 0.0) {
      moved.push_back(k);
      movedPts.push_back(pts[k] + (kSurfaceGap * s - c.nearest) * glm::normalize(c.away));
      wasInside.push_back(0);
    }
  }
  for (size_t k : moved) movedReach.push_back(reach[k]);
  if (!moved.empty()) {
    const std::vector<Clearance> second = ask(query, movedPts, movedReach);
    for (size_t m = 0; m < moved.size(); ++m) {
      const size_t i = ids[moved[m]];
      const double s = movedReach[m];
      const bool bad = second[m].inside || (wasInside[m] && second[m].nearest < kSurfaceGap * s);
      if (bad) {
        keep[i] = 0;
      } else {
        probes.positions[i] = movedPts[m];
        ++stats.pushed;
      }
    }
  }
  stats.rejected = size_t(std::count(keep.begin(), keep.end(), uint8_t(0)));
  keepOnly(probes, keep);
  return stats;
}

size_t mergeProbes(PlacedProbes& probes, double tolerance) {
  if (!(tolerance >= 0.0) || !std::isfinite(tolerance))
    throw std::invalid_argument("mergeProbes: tolerance must be finite and >= 0");
  if (probes.size() > size_t(UINT32_MAX)) throw std::invalid_argument("mergeProbes: too many probes");
  // Priority order: user first, then by kind, then input order.
  std::vector<uint32_t> order(probes.size());
  std::iota(order.begin(), order.end(), 0u);
  std::stable_sort(order.begin(), order.end(),
                   [&](uint32_t a, uint32_t b) { return probes.kinds[a] < probes.kinds[b]; });
  // One grid (cell = r) per distinct radius r = tolerance x spacing. A kept probe goes into the grids of
  // every radius >= its own. A new probe of radius t conflicts with kept j when their distance is below
  // max(t, r_j): kept probes with r_j <= t are all in grid t (searched within t), and those with r_j = T > t
  // are in grid T (searched within T). Each search looks at 3^3 cells.
  std::map<double, HashGrid> grids;
  for (size_t i = 0; i < probes.size(); ++i) {
    const double r = tolerance * probes.spacing[i];
    if (r > 0.0 && std::isfinite(r) && !grids.count(r)) grids[r].cell = r;
  }
  std::vector<uint8_t> keep(probes.size(), 1);
  auto radius = [&](uint32_t i) { return tolerance * probes.spacing[i]; };
  for (uint32_t i : order) {
    const glm::dvec3& p = probes.positions[i];
    const double t = radius(i);
    if (probes.kinds[i] != ProbeKind::kUser && t > 0.0) {
      bool conflict = false;
      for (auto& [r, grid] : grids) {
        if (r < t) continue;
        // Grid r holds every kept probe of radius <= r; conflict distance is max(t, radius(j)) <= r.
        conflict = grid.any(
            p, r, [&](uint32_t j) { return glm::distance(probes.positions[j], p) < std::max(t, radius(j)); });
        break;  // the smallest grid with r >= t already holds every probe of radius <= r
      }
      if (!conflict)
        for (auto& [r, grid] : grids) {
          if (r <= t) continue;
          conflict = grid.any(
              p, r, [&](uint32_t j) { return radius(j) == r && glm::distance(probes.positions[j], p) < r; });
          if (conflict) break;
        }
      if (conflict) {
        keep[i] = 0;
        continue;
      }
    }
    for (auto& [r, grid] : grids)
      if (r >= t) grid.insert(p, i);
  }
  const size_t dropped = size_t(std::count(keep.begin(), keep.end(), uint8_t(0)));
  keepOnly(probes, keep);
  return dropped;
}

}  // namespace tetraprobe
