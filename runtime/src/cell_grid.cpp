// Sparse hash grid of BSP trees over the probe tets (Valient, "Taking Killzone Shadow Fall image quality
// into the next generation", GDC 2014: 16 m cells found through a hash, a BSP per cell; split scoring after
// Godot 4's LightmapGI, scene/3d/lightmap_gi.cpp).
//
// Robustness: a tet goes to a child when any of its vertices lies within `margin` of that child's side of the
// plane (evaluated in double from the float plane the query uses), so a query point within rounding of a
// plane finds its tet on either side; the query starts the walk (query.cpp) from a leaf tet, which makes the
// answer independent of the splits. A split is kept only when each child sheds at least a fifth of the
// node's tets (kMaxChildShare): below about one tet per region every face plane straddles most of them, and
// copying straddlers into both children would grow the tree without shrinking its leaves.
#include "tetraprobe/runtime/cell_grid.h"

#include "tetraprobe/runtime/level.h"

#include <algorithm>
#include <atomic>
#include <climits>
#include <cmath>
#include <system_error>
#include <thread>

#include <glm/common.hpp>
#include <glm/geometric.hpp>

namespace tetraprobe {
namespace {

constexpr size_t kLeafTets = 8;
constexpr double kMaxChildShare = 0.8;  // each child of a split holds at most this share of the node's tets
constexpr int kMaxDepth = 48;
constexpr size_t kCandidateTets = 4;  // tets whose 4 faces are tried as split planes, per node
constexpr size_t kScoreSample = 64;   // tets a candidate is scored on, per node
constexpr int64_t kMaxCellsPerTet =
    4096;  // a tet bigger than this many cells is kept to them (walk covers it)

}  // namespace

uint32_t cellHash(int32_t x, int32_t y, int32_t z) {
  uint32_t h = uint32_t(x) * 0x8DA6B343u ^ uint32_t(y) * 0xD8163841u ^ uint32_t(z) * 0xCB1AB31Fu;
  h ^= h >> 16;
  h *= 0x7FEB352Du;
  h ^= h >> 15;
  h *= 0x846CA68Bu;
  h ^= h >> 16;
  return h;
}

namespace {

struct CellTree {  // one cell's tree, built apart and appended in cell order (deterministic with threads)
  std::vector<BspNode> nodes;
  std::vector<int32_t> leafTets;
  int32_t root = 0;
  int maxDepth = 0;
  double depthSum = 0.0;
  size_t refs = 0;
};

class TreeBuilder {
 public:
  // corners: the 4 vertex positions of every tet, contiguous (one cache line a tet instead of five).
  TreeBuilder(const std::vector<glm::vec3>& corners, const std::vector<glm::vec3>& probes,
              const std::vector<Tet>& tets, double margin, CellTree& out)
      : corners_(corners), probes_(probes), tets_(tets), margin_(margin), out_(out) {}

  int32_t build(std::vector<int32_t>& list, int depth) {
    if (list.size() > kLeafTets && depth < kMaxDepth) {
      float plane[4];
      if (choosePlane(list, plane)) {
        std::vector<int32_t> under, over;
        for (int32_t t : list) {
          const int side = classify(t, plane);
          if (side <= 0) under.push_back(t);
          if (side >= 0) over.push_back(t);
        }
        // A split must shed a real share of the tets on both sides; otherwise straddlers copied into both
        // children grow the tree faster than they shrink the leaves.
        const double limit = kMaxChildShare * double(list.size());
        if (double(under.size()) <= limit && double(over.size()) <= limit) {
          std::vector<int32_t>().swap(list);
          const auto index = int32_t(out_.nodes.size());
          out_.nodes.push_back(BspNode{{plane[0], plane[1], plane[2], plane[3]}, {0, 0}, {0, 0}});
          const int32_t u = build(under, depth + 1);
          const int32_t o = build(over, depth + 1);
          out_.nodes[size_t(index)].child[0] = u;
          out_.nodes[size_t(index)].child[1] = o;
          return index;
        }
      }
    }
    const auto at = int32_t(out_.leafTets.size());
    out_.leafTets.push_back(int32_t(list.size()));
    out_.leafTets.insert(out_.leafTets.end(), list.begin(), list.end());
    out_.maxDepth = std::max(out_.maxDepth, depth);
    out_.depthSum += double(depth) * double(list.size());
    out_.refs += list.size();
    return -(at + 1);
  }

 private:
  // -1 under, +1 over, 0 both (straddling, or within the margin of the plane).
  int classify(int32_t t, const float plane[4]) const {
    bool under = false, over = false;
    for (int i = 0; i < 4; ++i) {
      const glm::dvec3 p(corners_[4 * size_t(t) + size_t(i)]);
      const double s =
          double(plane[0]) * p.x + double(plane[1]) * p.y + double(plane[2]) * p.z + double(plane[3]);
      if (s < margin_) under = true;
      if (s > -margin_) over = true;
    }
    return under && over ? 0 : under ? -1 : 1;
  }

  // The best face plane of a few evenly spread tets, scored on an evenly spread sample of the list.
  bool choosePlane(const std::vector<int32_t>& list, float best[4]) const {
    double bestScore = 0.0;
    const size_t n = list.size();
    const size_t sample = std::min(n, kScoreSample);
    for (size_t c = 0; c < kCandidateTets; ++c) {
      const Tet& tet = tets_[size_t(list[(c * n) / kCandidateTets + n / (2 * kCandidateTets)])];
      for (int f = 0; f < 4; ++f) {
        const glm::dvec3 p0(probes_[size_t(tet.v[(f + 1) & 3])]), p1(probes_[size_t(tet.v[(f + 2) & 3])]),
            p2(probes_[size_t(tet.v[(f + 3) & 3])]);
        glm::dvec3 nrm = glm::cross(p1 - p0, p2 - p0);
        const double len = glm::length(nrm);
        if (!(len > 0.0)) continue;
        nrm /= len;
        const float plane[4] = {float(nrm.x), float(nrm.y), float(nrm.z), float(-glm::dot(nrm, p0))};
        size_t under = 0, over = 0;
        for (size_t k = 0; k < sample; ++k) {
          const int side = classify(list[(k * n) / sample], plane);
          under += side < 0;
          over += side > 0;
        }
        const double lo = double(std::min(under, over)), hi = double(std::max(under, over));
        if (hi == 0.0) continue;
        const double kept = (lo + hi) / double(sample);
        const double score = (lo / hi) * kept * kept;
        if (score > bestScore) {
          bestScore = score;
          std::copy(plane, plane + 4, best);
        }
      }
    }
    return bestScore > 0.0;
  }

  const std::vector<glm::vec3>& corners_;
  const std::vector<glm::vec3>& probes_;
  const std::vector<Tet>& tets_;
  double margin_;
  CellTree& out_;
};

}  // namespace

CellGrid buildCellGrid(const std::vector<glm::vec3>& probes, const std::vector<Tet>& tets, float cellSize,
                       int threads) {
  CellGrid grid;
  grid.cellSize = cellSize > 0.0f && std::isfinite(cellSize) ? cellSize : 16.0f;
  if (tets.empty()) return grid;
  glm::dvec3 lo(probes[size_t(tets[0].v[0])]), hi = lo;
  double maxAbs = 0.0;
  for (const glm::vec3& p : probes) {
    lo = glm::min(lo, glm::dvec3(p));
    hi = glm::max(hi, glm::dvec3(p));
    maxAbs = std::max({maxAbs, double(std::abs(p.x)), double(std::abs(p.y)), double(std::abs(p.z))});
  }
  grid.min = glm::vec3(lo);
  const double cs = grid.cellSize;
  const glm::dvec3 gmin(grid.min);
  // Float planes evaluated at |x| <= maxAbs err by ~1e-7 |x|: 10x that is the straddle margin.
  const double margin = 1e-6 * (maxAbs + cs);

  // Bucket tets into cells by their bounding boxes (padded by the margin): (cell key, tet) pairs, sorted.
  struct Ref {
    int32_t key[3];
    int32_t tet;
  };
  std::vector<Ref> refs;
  refs.reserve(tets.size() * 2);
  for (size_t t = 0; t < tets.size(); ++t) {
    glm::dvec3 a(probes[size_t(tets[t].v[0])]), b = a;
    for (int i = 1; i < 4; ++i) {
      a = glm::min(a, glm::dvec3(probes[size_t(tets[t].v[i])]));
      b = glm::max(b, glm::dvec3(probes[size_t(tets[t].v[i])]));
    }
    int32_t c0[3], c1[3];
    for (int k = 0; k < 3; ++k) {
      c0[k] = int32_t(std::floor((a[k] - margin - gmin[k]) / cs));
      c1[k] = int32_t(std::floor((b[k] + margin - gmin[k]) / cs));
    }
    if (int64_t(c1[0] - c0[0] + 1) * (c1[1] - c0[1] + 1) * (c1[2] - c0[2] + 1) > kMaxCellsPerTet) continue;
    for (int32_t z = c0[2]; z <= c1[2]; ++z)
      for (int32_t y = c0[1]; y <= c1[1]; ++y)
        for (int32_t x = c0[0]; x <= c1[0]; ++x) refs.push_back({{x, y, z}, int32_t(t)});
  }
  std::sort(refs.begin(), refs.end(), [](const Ref& p, const Ref& q) {
    if (p.key[2] != q.key[2]) return p.key[2] < q.key[2];
    if (p.key[1] != q.key[1]) return p.key[1] < q.key[1];
    if (p.key[0] != q.key[0]) return p.key[0] < q.key[0];
    return p.tet < q.tet;
  });
  std::vector<size_t> cellStart;
  for (size_t i = 0; i < refs.size(); ++i)
    if (i == 0 || !std::equal(refs[i].key, refs[i].key + 3, refs[i - 1].key)) cellStart.push_back(i);
  cellStart.push_back(refs.size());
  const size_t cellCount = cellStart.size() - 1;

  std::vector<glm::vec3> corners(4 * tets.size());
  for (size_t t = 0; t < tets.size(); ++t)
    for (int i = 0; i < 4; ++i) corners[4 * t + size_t(i)] = probes[size_t(tets[t].v[i])];

  // Trees, one per cell, on worker threads taking cells in turn; appended in cell order afterwards.
  std::vector<CellTree> trees(cellCount);
  std::atomic<size_t> next{0};
  auto work = [&] {
    for (size_t c; (c = next.fetch_add(1)) < cellCount;) {
      std::vector<int32_t> list;
      for (size_t i = cellStart[c]; i < cellStart[c + 1]; ++i) list.push_back(refs[i].tet);
      TreeBuilder builder(corners, probes, tets, margin, trees[c]);
      trees[c].root = builder.build(list, 0);
    }
  };
  size_t n = threads > 0 ? size_t(threads) : size_t(std::max(1u, std::thread::hardware_concurrency()));
  n = std::clamp<size_t>(n, 1, std::max<size_t>(1, cellCount));
  std::vector<std::thread> pool;
  for (size_t k = 1; k < n; ++k) {
    try {
      pool.emplace_back(work);
    } catch (const std::system_error&) {
      break;
    }
  }
  work();
  for (std::thread& t : pool) t.join();

  // Hash table: a power of two at least twice the cells, grown until every probe sequence is short.
  size_t capacity = 16;
  while (capacity < 2 * cellCount) capacity *= 2;
  std::vector<int32_t> roots(cellCount);
  double depthSum = 0.0;
  for (size_t c = 0; c < cellCount; ++c) {
    CellTree& tree = trees[c];
    const auto nodeBase = int32_t(grid.nodes.size()), leafBase = int32_t(grid.leafTets.size());
    const auto relocate = [&](int32_t child) { return child >= 0 ? child + nodeBase : child - leafBase; };
    for (BspNode node : tree.nodes) {
      node.child[0] = relocate(node.child[0]);
      node.child[1] = relocate(node.child[1]);
      grid.nodes.push_back(node);
    }
    grid.leafTets.insert(grid.leafTets.end(), tree.leafTets.begin(), tree.leafTets.end());
    roots[c] = relocate(tree.root);
    grid.maxDepth = std::max(grid.maxDepth, tree.maxDepth);
    depthSum += tree.depthSum;
    grid.leafReferences += tree.refs;
    CellTree().nodes.swap(tree.nodes);
  }
  grid.meanDepth = grid.leafReferences > 0 ? depthSum / double(grid.leafReferences) : 0.0;
  for (;;) {
    grid.slots.assign(capacity, CellSlot{{INT32_MIN, 0, 0}, 0});
    grid.maxProbe = 0;
    for (size_t c = 0; c < cellCount; ++c) {
      const int32_t* key = refs[cellStart[c]].key;
      size_t h = size_t(cellHash(key[0], key[1], key[2])) & (capacity - 1);
      uint32_t probe = 1;
      while (grid.slots[h].key[0] != INT32_MIN) {
        h = (h + 1) & (capacity - 1);
        ++probe;
      }
      grid.slots[h] = CellSlot{{key[0], key[1], key[2]}, roots[c]};
      grid.maxProbe = std::max(grid.maxProbe, probe);
    }
    if (grid.maxProbe <= kMaxCellProbe || capacity >= (size_t(1) << 30)) break;
    capacity *= 2;
  }
  return grid;
}

const int32_t* cellGridLeaf(const CellGrid& grid, const glm::dvec3& x, int32_t* count, int* depth) {
  *count = 0;
  if (depth) *depth = 0;
  if (grid.slots.empty()) return nullptr;
  int32_t key[3], node = 0;
  if (!cellGridKey(grid, x, key) || !cellGridFind(grid, key, cellGridSlot(grid, key), &node)) return nullptr;
  int d = 0;
  for (; node >= 0; ++d) node = cellGridChild(grid.nodes[size_t(node)], x);
  if (depth) *depth = d;
  const int32_t* leaf = grid.leafTets.data() + size_t(-(node + 1));
  *count = leaf[0];
  return leaf + 1;
}

}  // namespace tetraprobe
