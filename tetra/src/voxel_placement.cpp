// Adaptive voxel probe placement: Valient (GDC 2014, Killzone Shadow Fall) puts a probe in every empty voxel
// next to geometry, 1 m in gameplay space up to 10 m far away. Here the voxels are the levels of a sparse
// octree (edge spacing * 2^L), refined near geometry and inside fine volumes; the "holds geometry" test is
// the exact triangle/box separating-axis test of Akenine-Moller ("Fast 3D triangle-box overlap testing",
// JGT 2001). Filler probes fill open space at a lower frequency, as in Valient's talk.
//
// Every set is a sorted vector of packed cell keys (21 bits per axis), so the output order is a pure
// function of the input: voxelization runs in parallel into per-chunk lists that are concatenated in chunk
// order and sorted.
#include <algorithm>
#include <cmath>
#include <string>
#include <unordered_map>

#include <glm/common.hpp>
#include <glm/geometric.hpp>

#include "tetraprobe/common/error.h"
#include "tetraprobe/common/parallel.h"
#include "tetraprobe/scene/scene.h"
#include "tetraprobe/tetra/placement.h"

namespace tetraprobe {
namespace {

constexpr int kBits = 21;
constexpr int64_t kMaxCellsPerAxis = int64_t(1) << 20;

using Key = uint64_t;
Key pack(int64_t x, int64_t y, int64_t z) {
  return Key(x) | Key(y) << kBits | Key(z) << (2 * kBits);
}
glm::i64vec3 unpack(Key k) {
  const Key m = (Key(1) << kBits) - 1;
  return {int64_t(k & m), int64_t((k >> kBits) & m), int64_t(k >> (2 * kBits))};
}
bool contains(const std::vector<Key>& set, Key k) {
  return std::binary_search(set.begin(), set.end(), k);
}
void sortUnique(std::vector<Key>& v) {
  std::sort(v.begin(), v.end());
  v.erase(std::unique(v.begin(), v.end()), v.end());
}

// Separating-axis test on one axis: projections of the triangle vs the box radius.
bool separated(const glm::dvec3& axis, const glm::dvec3& v0, const glm::dvec3& v1, const glm::dvec3& v2,
               const glm::dvec3& h) {
  const double p0 = glm::dot(axis, v0), p1 = glm::dot(axis, v1), p2 = glm::dot(axis, v2);
  const double r = h.x * std::abs(axis.x) + h.y * std::abs(axis.y) + h.z * std::abs(axis.z);
  return std::min({p0, p1, p2}) > r || std::max({p0, p1, p2}) < -r;
}

struct Grid {
  glm::dvec3 origin;  // min corner of level-0 cell (0,0,0)
  double spacing;
  glm::i64vec3 cells;  // level-0 cells per axis (a multiple of 2^top)
  int top;
  double edge(int level) const { return spacing * double(int64_t(1) << level); }
  glm::i64vec3 cellsAt(int level) const { return cells >> int64_t(level); }
  glm::dvec3 centre(Key k, int level) const { return origin + (glm::dvec3(unpack(k)) + 0.5) * edge(level); }
};

// Level-0 cells a triangle overlaps, by recursive halving of its cell range (a huge triangle costs its
// surface area in cells, not its bounding-box volume).
void voxelizeTriangle(const Grid& g, const glm::dvec3& a, const glm::dvec3& b, const glm::dvec3& c,
                      glm::i64vec3 lo, glm::i64vec3 hi, std::vector<Key>& out) {
  const glm::dvec3 blo = g.origin + glm::dvec3(lo) * g.spacing;
  const glm::dvec3 bhi = g.origin + glm::dvec3(hi + int64_t(1)) * g.spacing;
  if (!triangleBoxOverlap(a, b, c, blo, bhi)) return;
  const glm::i64vec3 n = hi - lo + int64_t(1);
  if (n.x == 1 && n.y == 1 && n.z == 1) {
    out.push_back(pack(lo.x, lo.y, lo.z));
    return;
  }
  const int axis = n.x >= n.y && n.x >= n.z ? 0 : (n.y >= n.z ? 1 : 2);
  const int64_t mid = lo[axis] + n[axis] / 2;
  glm::i64vec3 hiA = hi, loB = lo;
  hiA[axis] = mid - 1;
  loB[axis] = mid;
  voxelizeTriangle(g, a, b, c, lo, hiA, out);
  voxelizeTriangle(g, a, b, c, loB, hi, out);
}

std::string metres(double v) {
  char buf[64];
  std::snprintf(buf, sizeof(buf), "%g m", v);
  return buf;
}

}  // namespace

const char* probeKindName(ProbeKind kind) {
  switch (kind) {
    case ProbeKind::kUser:
      return "user";
    case ProbeKind::kSurface:
      return "surface";
    case ProbeKind::kVolume:
      return "volume";
    case ProbeKind::kOpen:
      return "open";
    case ProbeKind::kFiller:
      return "filler";
    case ProbeKind::kShell:
      return "shell";
  }
  return "?";
}

size_t PlacedProbes::count(ProbeKind k) const {
  return size_t(std::count(kinds.begin(), kinds.end(), k));
}

bool triangleBoxOverlap(const glm::dvec3& a, const glm::dvec3& b, const glm::dvec3& c, const glm::dvec3& lo,
                        const glm::dvec3& hi) {
  const glm::dvec3 centre = 0.5 * (lo + hi), h = 0.5 * (hi - lo);
  const glm::dvec3 v0 = a - centre, v1 = b - centre, v2 = c - centre;
  // Box face normals (the triangle's bounding box against the box).
  for (int i = 0; i < 3; ++i) {
    if (std::min({v0[i], v1[i], v2[i]}) > h[i] || std::max({v0[i], v1[i], v2[i]}) < -h[i]) return false;
  }
  const glm::dvec3 e[3] = {v1 - v0, v2 - v1, v0 - v2};
  // Triangle normal.
  const glm::dvec3 n = glm::cross(e[0], e[1]);
  if (separated(n, v0, v1, v2, h)) return false;
  // The nine edge x box-axis cross products.
  for (const glm::dvec3& edge : e) {
    if (separated({0.0, -edge.z, edge.y}, v0, v1, v2, h)) return false;
    if (separated({edge.z, 0.0, -edge.x}, v0, v1, v2, h)) return false;
    if (separated({-edge.y, edge.x, 0.0}, v0, v1, v2, h)) return false;
  }
  return true;
}

PlacedProbes placeVoxelProbes(const Scene& scene, const VoxelPlacementOptions& options) {
  const double s = options.spacing;
  if (!std::isfinite(s) || s <= 0.0)
    throw InputError("voxel placement: --spacing " + metres(s) + " must be positive and finite");
  if (!std::isfinite(options.maxSpacing) || options.maxSpacing < s)
    throw InputError("voxel placement: --max-spacing " + metres(options.maxSpacing) +
                     " must be finite and at least --spacing " + metres(s));
  if (!std::isfinite(options.fillerSpacing) || options.fillerSpacing < 0.0)
    throw InputError("voxel placement: --filler-spacing " + metres(options.fillerSpacing) +
                     " must be finite and >= 0 (0 = no filler lattice)");
  if (scene.triangles.empty() || scene.positions.empty())
    throw InputError("voxel placement: the scene has no triangles to place probes around");

  // Domain: scene bounds and fine volumes, grown by one spacing.
  glm::dvec3 lo(scene.positions[0]), hi(scene.positions[0]);
  for (const glm::vec3& p : scene.positions) {
    if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z))
      throw InputError("voxel placement: the scene has a non-finite vertex position");
    lo = glm::min(lo, glm::dvec3(p));
    hi = glm::max(hi, glm::dvec3(p));
  }
  for (const Volume& v : scene.fineVolumes) {
    lo = glm::min(lo, glm::dvec3(v.min));
    hi = glm::max(hi, glm::dvec3(v.max));
  }
  Grid g;
  g.spacing = s;
  g.top = 0;
  while (g.top < 20 && g.edge(g.top + 1) <= options.maxSpacing * (1.0 + 1e-9)) ++g.top;
  // Voxel centres on the world lattice spacing * Z^3, so geometry on whole-spacing planes (metre-aligned
  // walls, floors) lies in the middle of a voxel rather than on the face between two; the first voxel layer
  // lies outside the bounds.
  g.origin = (glm::floor(lo / s) - 1.5) * s;
  const int64_t topCell = int64_t(1) << g.top;
  for (int a = 0; a < 3; ++a) {
    const double n = std::ceil((hi[a] + s - g.origin[a]) / s);
    if (!(n <= double(kMaxCellsPerAxis)))
      throw InputError("voxel placement: the level spans " + metres(hi[a] - lo[a]) + " on axis " +
                       std::to_string(a) + ", more than 2^20 voxels of " + metres(s) +
                       "; use a larger --spacing");
    g.cells[a] = (std::max<int64_t>(int64_t(n), 1) + topCell - 1) / topCell * topCell;
  }
  while (g.top > 0 && (g.cells >> int64_t(g.top)) == glm::i64vec3(0)) --g.top;  // never happens; safety

  // Level 0: voxels holding geometry.
  const size_t chunk = 1024;
  const size_t chunks = (scene.triangles.size() + chunk - 1) / chunk;
  std::vector<std::vector<Key>> perChunk(chunks);
  parallelFor(chunks, options.threads, [&](size_t ci) {
    std::vector<Key>& out = perChunk[ci];
    const size_t end = std::min(scene.triangles.size(), (ci + 1) * chunk);
    for (size_t t = ci * chunk; t < end; ++t) {
      const glm::uvec3 tri = scene.triangles[t];
      if (tri.x >= scene.positions.size() || tri.y >= scene.positions.size() ||
          tri.z >= scene.positions.size())
        continue;  // the loader rejects these; stay safe
      const glm::dvec3 a(scene.positions[tri.x]), b(scene.positions[tri.y]), c(scene.positions[tri.z]);
      if (glm::length(glm::cross(b - a, c - a)) == 0.0) continue;  // zero area: no surface
      const glm::dvec3 tlo = glm::min(a, glm::min(b, c)), thi = glm::max(a, glm::max(b, c));
      glm::i64vec3 clo, chi;
      for (int k = 0; k < 3; ++k) {  // one cell of slack: closed boxes touch on their shared faces
        clo[k] = std::clamp(int64_t(std::floor((tlo[k] - g.origin[k]) / s)) - 1, int64_t(0), g.cells[k] - 1);
        chi[k] = std::clamp(int64_t(std::floor((thi[k] - g.origin[k]) / s)) + 1, int64_t(0), g.cells[k] - 1);
      }
      voxelizeTriangle(g, a, b, c, clo, chi, out);
    }
    sortUnique(out);
  });
  std::vector<Key> geometry;
  for (auto& v : perChunk) geometry.insert(geometry.end(), v.begin(), v.end());
  perChunk.clear();
  sortUnique(geometry);

  PlacedProbes out;
  // Probes stay inside the level's bounds (a probe outside a closed level only sees the backs of its walls;
  // outside an open one there is nothing to light), each axis grown to at least two spacings so that a flat
  // level (a lone floor) still gets the probes above it.
  glm::dvec3 keepLo = lo, keepHi = hi;
  for (int a = 0; a < 3; ++a) {
    const double grow = std::max(0.0, s - 0.5 * (hi[a] - lo[a]));
    keepLo[a] -= grow;
    keepHi[a] += grow;
  }
  auto inDomain = [&](const glm::dvec3& p) {
    return p.x >= keepLo.x && p.y >= keepLo.y && p.z >= keepLo.z && p.x <= keepHi.x && p.y <= keepHi.y &&
           p.z <= keepHi.z;
  };
  auto budget = [&](size_t more) {
    if (out.size() + more > options.maxProbes)
      throw InputError("voxel placement: more than " + std::to_string(options.maxProbes) +
                       " probes at --spacing " + metres(s) + "; use a larger spacing");
  };

  // Cells of level `level` overlapping a fine volume (closed boxes).
  auto volumeCells = [&](int level, std::vector<Key>& into) {
    const double h = g.edge(level);
    const glm::i64vec3 n = g.cellsAt(level);
    for (const Volume& v : scene.fineVolumes) {
      glm::i64vec3 a, b;
      for (int k = 0; k < 3; ++k) {
        a[k] = std::clamp(int64_t(std::floor((double(v.min[k]) - g.origin[k]) / h)), int64_t(0), n[k] - 1);
        b[k] = std::clamp(int64_t(std::floor((double(v.max[k]) - g.origin[k]) / h)), int64_t(0), n[k] - 1);
      }
      const double count = double(b.x - a.x + 1) * double(b.y - a.y + 1) * double(b.z - a.z + 1);
      if (count > double(options.maxProbes))
        throw InputError("voxel placement: fine volume '" + v.name + "' holds more than " +
                         std::to_string(options.maxProbes) + " voxels of " + metres(h));
      for (int64_t z = a.z; z <= b.z; ++z)
        for (int64_t y = a.y; y <= b.y; ++y)
          for (int64_t x = a.x; x <= b.x; ++x) into.push_back(pack(x, y, z));
    }
  };
  auto inVolume = [&](const glm::dvec3& lo3, const glm::dvec3& hi3) {
    for (const Volume& v : scene.fineVolumes)
      if (lo3.x <= v.max.x && hi3.x >= v.min.x && lo3.y <= v.max.y && hi3.y >= v.min.y && lo3.z <= v.max.z &&
          hi3.z >= v.min.z)
        return true;
    return false;
  };

  // Split sets S_L for L = 1..top: geometry cells of the level dilated by one cell, plus fine volumes.
  std::vector<std::vector<Key>> split(size_t(g.top) + 1);
  for (int level = 1; level <= g.top; ++level) {
    const glm::i64vec3 n = g.cellsAt(level);
    std::vector<Key> cells;
    cells.reserve(geometry.size() * 2);
    Key last = ~Key(0);
    for (Key k : geometry) {
      const glm::i64vec3 c = unpack(k) >> int64_t(level);
      const Key parent = pack(c.x, c.y, c.z);
      if (parent == last) continue;
      last = parent;
      for (int64_t dz = -1; dz <= 1; ++dz)
        for (int64_t dy = -1; dy <= 1; ++dy)
          for (int64_t dx = -1; dx <= 1; ++dx) {
            const glm::i64vec3 q = c + glm::i64vec3(dx, dy, dz);
            if (q.x < 0 || q.y < 0 || q.z < 0 || q.x >= n.x || q.y >= n.y || q.z >= n.z) continue;
            cells.push_back(pack(q.x, q.y, q.z));
          }
    }
    volumeCells(level, cells);
    sortUnique(cells);
    split[size_t(level)] = std::move(cells);
  }

  // Leaves, coarse to fine. Parents of level L: all top cells for L = top, else S_{L+1}.
  std::vector<std::vector<Key>> leaves(size_t(g.top) + 1);
  for (int level = g.top; level >= 0; --level) {
    std::vector<Key> candidates;
    if (level == g.top) {
      const glm::i64vec3 n = g.cellsAt(level);
      const double total = double(n.x) * double(n.y) * double(n.z);
      if (total > 8.0 * double(options.maxProbes))
        throw InputError("voxel placement: " + std::to_string(uint64_t(total)) + " top-level cells of " +
                         metres(g.edge(level)) + "; raise --max-spacing or --spacing");
      if (level == 0) {
        // No coarser level: only level-0 voxels next to geometry or in fine volumes can get probes.
        for (Key k : geometry) {
          const glm::i64vec3 c = unpack(k);
          for (int64_t dz = -1; dz <= 1; ++dz)
            for (int64_t dy = -1; dy <= 1; ++dy)
              for (int64_t dx = -1; dx <= 1; ++dx) {
                const glm::i64vec3 q = c + glm::i64vec3(dx, dy, dz);
                if (q.x < 0 || q.y < 0 || q.z < 0 || q.x >= n.x || q.y >= n.y || q.z >= n.z) continue;
                candidates.push_back(pack(q.x, q.y, q.z));
              }
        }
        volumeCells(0, candidates);
      } else {
        for (int64_t z = 0; z < n.z; ++z)
          for (int64_t y = 0; y < n.y; ++y)
            for (int64_t x = 0; x < n.x; ++x) candidates.push_back(pack(x, y, z));
      }
    } else {
      for (Key k : split[size_t(level) + 1]) {
        const glm::i64vec3 c = unpack(k) * int64_t(2);
        for (int64_t i = 0; i < 8; ++i) {
          const glm::i64vec3 q = c + glm::i64vec3(i & 1, (i >> 1) & 1, (i >> 2) & 1);
          candidates.push_back(pack(q.x, q.y, q.z));
        }
      }
    }
    sortUnique(candidates);
    std::vector<Key>& mine = leaves[size_t(level)];
    for (Key k : candidates) {
      if (level > 0) {
        if (!contains(split[size_t(level)], k)) mine.push_back(k);
      } else if (!contains(geometry, k)) {
        mine.push_back(k);
      }
    }
  }

  // Probes: level 0 first (surface / volume), then coarser open cells.
  for (Key k : leaves[0]) {
    const glm::i64vec3 c = unpack(k);
    bool nearGeometry = false;
    for (int64_t dz = -1; dz <= 1 && !nearGeometry; ++dz)
      for (int64_t dy = -1; dy <= 1 && !nearGeometry; ++dy)
        for (int64_t dx = -1; dx <= 1 && !nearGeometry; ++dx) {
          const glm::i64vec3 q = c + glm::i64vec3(dx, dy, dz);
          if (q.x < 0 || q.y < 0 || q.z < 0) continue;
          nearGeometry = contains(geometry, pack(q.x, q.y, q.z));
        }
    const glm::dvec3 clo = g.origin + glm::dvec3(c) * s;
    if (!inDomain(g.centre(k, 0))) continue;
    if (nearGeometry) {
      budget(1);
      out.add(g.centre(k, 0), ProbeKind::kSurface, s);
    } else if (inVolume(clo, clo + glm::dvec3(s))) {
      budget(1);
      out.add(g.centre(k, 0), ProbeKind::kVolume, s);
    }
  }
  for (int level = 1; level <= g.top; ++level) {
    budget(leaves[size_t(level)].size());
    for (Key k : leaves[size_t(level)])
      if (const glm::dvec3 c = g.centre(k, level); inDomain(c)) out.add(c, ProbeKind::kOpen, g.edge(level));
  }

  // Filler lattice: open space at fillerSpacing where no probe is within half of it.
  const double f = options.fillerSpacing;
  if (f > 0.0) {
    const double cell = 0.5 * f;
    std::unordered_map<Key, std::vector<uint32_t>> hash;
    auto hashKey = [&](const glm::dvec3& p) {
      const glm::dvec3 q = glm::floor((p - g.origin) / cell) + 2.0;  // >= 1: keys stay unsigned
      return pack(int64_t(q.x), int64_t(q.y), int64_t(q.z));
    };
    for (size_t i = 0; i < out.size(); ++i) hash[hashKey(out.positions[i])].push_back(uint32_t(i));
    const glm::dvec3 extent = keepHi - keepLo;
    glm::i64vec3 n;
    for (int a = 0; a < 3; ++a) n[a] = std::max<int64_t>(1, int64_t(std::floor(extent[a] / f)));
    if (double(n.x) * double(n.y) * double(n.z) > double(options.maxProbes))
      throw InputError("voxel placement: --filler-spacing " + metres(f) + " gives more than " +
                       std::to_string(options.maxProbes) + " lattice points");
    const glm::dvec3 start = keepLo + 0.5 * (extent - glm::dvec3(n - int64_t(1)) * f);
    for (int64_t z = 0; z < n.z; ++z)
      for (int64_t y = 0; y < n.y; ++y)
        for (int64_t x = 0; x < n.x; ++x) {
          const glm::dvec3 p = start + glm::dvec3(x, y, z) * f;
          const glm::i64vec3 vc = glm::i64vec3(glm::floor((p - g.origin) / s));
          if (contains(geometry, pack(vc.x, vc.y, vc.z))) continue;
          const glm::i64vec3 hc = unpack(hashKey(p));
          bool near = false;
          for (int64_t dz = -1; dz <= 1 && !near; ++dz)
            for (int64_t dy = -1; dy <= 1 && !near; ++dy)
              for (int64_t dx = -1; dx <= 1 && !near; ++dx) {
                const auto it = hash.find(pack(hc.x + dx, hc.y + dy, hc.z + dz));
                if (it == hash.end()) continue;
                for (uint32_t i : it->second)
                  if (glm::distance(out.positions[i], p) < cell) {
                    near = true;
                    break;
                  }
              }
          if (near) continue;
          budget(1);
          out.add(p, ProbeKind::kFiller, f);
        }
  }
  return out;
}

}  // namespace tetraprobe
