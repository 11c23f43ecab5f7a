// Validation and deterministic extraction shared by the Delaunay backends (see mesh_internal.h).
#include "mesh_internal.h"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <utility>

#include <glm/common.hpp>

#include "tetraprobe/common/error.h"

namespace tetraprobe::detail {
namespace {

// Applies the even permutation that puts the smallest vertex first and the smallest of the other three
// second. Even permutations keep the orientation, and this representative is unique per tet.
void canonicalize(RawTet& t) {
  auto swapPair = [&](int a, int b, int c, int d) {  // swaps (a,b) and (c,d): an even permutation
    std::swap(t.v[size_t(a)], t.v[size_t(b)]);
    std::swap(t.n[size_t(a)], t.n[size_t(b)]);
    std::swap(t.v[size_t(c)], t.v[size_t(d)]);
    std::swap(t.n[size_t(c)], t.n[size_t(d)]);
  };
  const int m = int(std::min_element(t.v.begin(), t.v.end()) - t.v.begin());
  if (m == 1) swapPair(0, 1, 2, 3);
  if (m == 2) swapPair(0, 2, 1, 3);
  if (m == 3) swapPair(0, 3, 1, 2);
  // Cyclic rotation of positions 1..3 (a 3-cycle, even) until position 1 holds the smallest of them.
  auto rotate = [&] {
    std::rotate(t.v.begin() + 1, t.v.begin() + 2, t.v.end());
    std::rotate(t.n.begin() + 1, t.n.begin() + 2, t.n.end());
  };
  while (t.v[1] > t.v[2] || t.v[1] > t.v[3]) rotate();
}

// 63-bit Morton code (21 bits per axis, x lowest) of p quantized over [lo, hi].
uint64_t mortonKey(const glm::dvec3& p, const glm::dvec3& lo, const glm::dvec3& hi) {
  auto spread = [](uint64_t x) {  // 21 bits -> every third bit
    x &= 0x1FFFFF;
    x = (x | x << 32) & 0x1F00000000FFFFull;
    x = (x | x << 16) & 0x1F0000FF0000FFull;
    x = (x | x << 8) & 0x100F00F00F00F00Full;
    x = (x | x << 4) & 0x10C30C30C30C30C3ull;
    x = (x | x << 2) & 0x1249249249249249ull;
    return x;
  };
  uint64_t code = 0;
  for (int a = 0; a < 3; ++a) {
    const double extent = hi[a] - lo[a];
    const double f = extent > 0.0 ? std::clamp((p[a] - lo[a]) / extent, 0.0, 1.0) : 0.0;
    code |= spread(uint64_t(f * double((1u << 21) - 1))) << a;
  }
  return code;
}

}  // namespace

std::string describe(const glm::dvec3& p) {
  return "(" + std::to_string(p.x) + ", " + std::to_string(p.y) + ", " + std::to_string(p.z) + ")";
}

void validatePoints(const std::vector<glm::dvec3>& points, const std::string& who) {
  if (points.size() < 4)
    throw InputError(who + ": " + std::to_string(points.size()) +
                     " probes; at least 4 non-coplanar probes are needed");
  if (points.size() > size_t(INT32_MAX))
    throw InputError(who + ": " + std::to_string(points.size()) + " probes exceed the int32 index range");
  for (size_t i = 0; i < points.size(); ++i) {
    const glm::dvec3& p = points[i];
    if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z))
      throw InputError(who + ": probe " + std::to_string(i) + " has a non-finite coordinate " + describe(p));
  }
  // Exact duplicates, found by a lexicographic sort of contiguous (x, y, z, index) records (O(n log n); ties
  // by index, so the lowest index of a duplicate group comes first).
  struct Entry {
    double x, y, z;
    int32_t index;
  };
  std::vector<Entry> order(points.size());
  for (size_t i = 0; i < points.size(); ++i) order[i] = {points[i].x, points[i].y, points[i].z, int32_t(i)};
  std::sort(order.begin(), order.end(), [](const Entry& p, const Entry& q) {
    if (p.x != q.x) return p.x < q.x;
    if (p.y != q.y) return p.y < q.y;
    if (p.z != q.z) return p.z < q.z;
    return p.index < q.index;
  });
  for (size_t k = 1; k < order.size(); ++k) {
    const Entry &p = order[k - 1], &q = order[k];
    if (p.x == q.x && p.y == q.y && p.z == q.z)
      throw InputError(who + ": probes " + std::to_string(p.index) + " and " + std::to_string(q.index) +
                       " are at the same position " + describe(points[size_t(p.index)]));
  }
}

TetMesh finalizeMesh(const std::vector<glm::dvec3>& points, std::vector<RawTet> raw) {
  for (RawTet& t : raw) canonicalize(t);
  // Deterministic, cache-friendly order: by the Morton code of the centroid (tets that are close in space are
  // close in memory, which keeps walks on the CPU and GPU in cache), ties by the canonical vertex tuple. Both
  // keys are pure functions of the input coordinates. Then renumber the neighbours.
  glm::dvec3 lo = points[0], hi = points[0];
  for (const glm::dvec3& p : points) {
    lo = glm::min(lo, p);
    hi = glm::max(hi, p);
  }
  // Sorted as contiguous (key, tuple, index) records rather than through an index array: same order, far
  // fewer cache misses on millions of tets.
  struct SortKey {
    uint64_t key;
    std::array<int32_t, 4> v;
    int32_t index;
  };
  std::vector<SortKey> keys(raw.size());
  for (size_t k = 0; k < raw.size(); ++k) {
    glm::dvec3 c(0.0);
    for (int32_t v : raw[k].v) c += points[size_t(v)];
    keys[k] = {mortonKey(0.25 * c, lo, hi), raw[k].v, int32_t(k)};
  }
  std::sort(keys.begin(), keys.end(),
            [](const SortKey& a, const SortKey& b) { return a.key != b.key ? a.key < b.key : a.v < b.v; });
  std::vector<int32_t> order(raw.size());
  for (size_t k = 0; k < keys.size(); ++k) order[k] = keys[k].index;
  keys = {};
  std::vector<int32_t> newIndex(raw.size());
  for (size_t k = 0; k < order.size(); ++k) newIndex[size_t(order[k])] = int32_t(k);

  TetMesh mesh;
  mesh.tets.resize(raw.size());
  mesh.neighbours.resize(raw.size());
  for (size_t k = 0; k < order.size(); ++k) {
    const RawTet& t = raw[size_t(order[k])];
    mesh.tets[k] = t.v;
    for (size_t i = 0; i < 4; ++i) mesh.neighbours[k][i] = t.n[i] < 0 ? -1 : newIndex[size_t(t.n[i])];
  }
  return mesh;
}

}  // namespace tetraprobe::detail
