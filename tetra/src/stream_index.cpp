// Streaming index (stream_index.h): sectors from the cell grid's occupied cells, each holding the tets whose
// bounding boxes touch the cell (grown by a margin) and the tets sharing a probe with one that the face blend
// may consult there with their face neighbours, their probes and the cell's
// BSP renumbered from 0; and a coarse probe set (one probe per coarse cube, nearest its centre) tetrahedralized with CGAL Delaunay. Layout
// in docs/level_format.md (section STRM).
#include "tetraprobe/tetra/stream_index.h"

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <map>
#include <string>

#include <glm/common.hpp>

#include "tetraprobe/common/error.h"
#include "tetraprobe/runtime/face_blend.h"
#include "tetraprobe/tetra/tetrahedralize.h"

namespace tetraprobe {

namespace {

struct Bytes {
  std::vector<uint8_t> b;
  void u32(uint32_t v) {
    for (int i = 0; i < 4; ++i) b.push_back(uint8_t(v >> (8 * i)));
  }
  void u64(uint64_t v) {
    u32(uint32_t(v));
    u32(uint32_t(v >> 32));
  }
  void i32(int32_t v) { u32(uint32_t(v)); }
  void f32(float v) { u32(std::bit_cast<uint32_t>(v)); }
};

struct SectorData {
  int32_t key[3];
  int32_t root = kEmptyLeaf;
  std::vector<uint32_t> tets, probes;
  std::vector<BspNode> nodes;
};

// The coarse set: kept probe indices (increasing) and their tets, at `spacing`; empty when it cannot be
// tetrahedralized.
bool coarseSet(const Level& level, double spacing, std::vector<uint32_t>& kept, TetMesh& mesh) {
  std::map<std::array<int64_t, 3>, std::pair<double, uint32_t>> best;
  for (size_t i = 0; i < level.probes.size(); ++i) {
    const glm::dvec3 p(level.probes[i]);
    std::array<int64_t, 3> cube;
    double d2 = 0.0;
    for (int a = 0; a < 3; ++a) {
      cube[size_t(a)] = int64_t(std::floor(p[a] / spacing));
      const double c = (double(cube[size_t(a)]) + 0.5) * spacing - p[a];
      d2 += c * c;
    }
    auto [it, fresh] = best.try_emplace(cube, d2, uint32_t(i));
    if (!fresh && d2 < it->second.first) it->second = {d2, uint32_t(i)};
  }
  kept.clear();
  for (const auto& [cube, v] : best) kept.push_back(v.second);
  std::sort(kept.begin(), kept.end());
  if (kept.size() < 4) return false;
  std::vector<glm::dvec3> pts;
  for (uint32_t i : kept) pts.push_back(glm::dvec3(level.probes[i]) + level.origin);
  try {
    mesh = tetrahedralizeDelaunay(pts);
    buildTetRecords(pts, mesh, level.origin);  // refuses collapsed tets
  } catch (const InputError&) {
    return false;
  }
  return !mesh.tets.empty();
}

}  // namespace

std::vector<uint8_t> buildStreamIndex(const Level& level, const StreamIndexOptions& options,
                                      StreamIndexStats* stats) {
  const CellGrid& g = level.cellGrid;
  if (g.slots.empty()) throw InputError("stream index: the level has no cell grid (re-bake it)");
  if (!(options.coarseSpacing > 0.0) || !(options.margin >= 0.0))
    throw InputError("stream index: the coarse spacing must be > 0 and the margin >= 0");
  const double cs = double(g.cellSize);

  // Sectors: the occupied cells, in key order.
  std::map<std::array<int32_t, 3>, SectorData> sectors;
  for (const CellSlot& s : g.slots) {
    if (s.key[0] == INT32_MIN) continue;
    SectorData d;
    std::copy(s.key, s.key + 3, d.key);
    d.root = s.root;
    sectors.emplace(std::array<int32_t, 3>{s.key[0], s.key[1], s.key[2]}, d);
  }
  // The tets holding each probe (a probe's star), for the sectors' rings below.
  std::vector<uint32_t> starStart(level.probes.size() + 1, 0), starTets(4 * level.tets.size());
  for (const Tet& t : level.tets)
    for (int32_t v : t.v) ++starStart[size_t(v) + 1];
  for (size_t p = 0; p < level.probes.size(); ++p) starStart[p + 1] += starStart[p];
  {
    std::vector<uint32_t> fill(starStart.begin(), starStart.end() - 1);
    for (size_t t = 0; t < level.tets.size(); ++t)
      for (int32_t v : level.tets[t].v) starTets[fill[size_t(v)]++] = uint32_t(t);
  }
  // Tets by bounding box (grown by the margin) into the cells they touch.
  for (size_t t = 0; t < level.tets.size(); ++t) {
    glm::dvec3 lo(level.probes[size_t(level.tets[t].v[0])]), hi = lo;
    for (int32_t v : level.tets[t].v) {
      lo = glm::min(lo, glm::dvec3(level.probes[size_t(v)]));
      hi = glm::max(hi, glm::dvec3(level.probes[size_t(v)]));
    }
    int64_t a0[3], a1[3];
    for (int a = 0; a < 3; ++a) {
      a0[a] = int64_t(std::floor((lo[a] - options.margin - double(g.min[a])) / cs));
      a1[a] = int64_t(std::floor((hi[a] + options.margin - double(g.min[a])) / cs));
    }
    for (int64_t x = a0[0]; x <= a1[0]; ++x)
      for (int64_t y = a0[1]; y <= a1[1]; ++y)
        for (int64_t z = a0[2]; z <= a1[2]; ++z) {
          const auto it = sectors.find({int32_t(x), int32_t(y), int32_t(z)});
          if (it != sectors.end()) it->second.tets.push_back(uint32_t(t));
        }
  }
  // Each cell's BSP, renumbered in increasing global order (children stay later than parents); its leaves'
  // tets join the sector if the boxes missed them (within rounding).
  for (auto& [key, d] : sectors) {
    std::vector<int32_t> reach;
    std::vector<int32_t> stack;
    if (d.root >= 0) stack.push_back(d.root);
    while (!stack.empty()) {
      const int32_t n = stack.back();
      stack.pop_back();
      reach.push_back(n);
      for (int32_t c : g.nodes[size_t(n)].child)
        if (c >= 0) stack.push_back(c);
    }
    std::sort(reach.begin(), reach.end());
    auto local = [&](int32_t c) {
      if (c >= 0) return int32_t(std::lower_bound(reach.begin(), reach.end(), c) - reach.begin());
      if (c != kEmptyLeaf) d.tets.push_back(uint32_t(~c));
      return c;
    };
    d.root = local(d.root);
    for (int32_t n : reach) {
      BspNode node = g.nodes[size_t(n)];
      node.child[0] = local(node.child[0]);
      node.child[1] = local(node.child[1]);
      d.nodes.push_back(node);
    }
    // The face blend (runtime/face_blend.h) consults the tets holding a tet's probes that reach the point:
    // those that may reach the cell (grown by the margin) join the sector too, so a loaded sector answers
    // as the full level does.
    glm::dvec3 cellLo, cellHi;
    for (int a = 0; a < 3; ++a) {
      cellLo[a] = double(g.min[a]) + double(d.key[a]) * cs - options.margin;
      cellHi[a] = cellLo[a] + cs + 2.0 * options.margin;
    }
    const size_t own = d.tets.size();
    std::vector<uint32_t> ring;
    for (size_t i = 0; i < own; ++i)
      for (int32_t v : level.tets[d.tets[i]].v)
        for (uint32_t k = starStart[size_t(v)]; k < starStart[size_t(v) + 1]; ++k)
          ring.push_back(starTets[k]);
    std::sort(ring.begin(), ring.end());
    ring.erase(std::unique(ring.begin(), ring.end()), ring.end());
    for (uint32_t t : ring)
      if (faceBlendMayReach(level, int32_t(t), cellLo, cellHi)) d.tets.push_back(t);
    // A reaching tet's weight reads the tet across each face the point lies past (its height): those join too.
    const size_t reaching = d.tets.size();
    for (size_t i = 0; i < reaching; ++i)
      for (int32_t nb : level.tets[d.tets[i]].n)
        if (nb >= 0) d.tets.push_back(uint32_t(nb));
    std::sort(d.tets.begin(), d.tets.end());
    d.tets.erase(std::unique(d.tets.begin(), d.tets.end()), d.tets.end());
    for (uint32_t t : d.tets)
      for (int32_t v : level.tets[t].v) d.probes.push_back(uint32_t(v));
    std::sort(d.probes.begin(), d.probes.end());
    d.probes.erase(std::unique(d.probes.begin(), d.probes.end()), d.probes.end());
  }

  // The coarse set.
  std::vector<uint32_t> kept;
  TetMesh mesh;
  double spacing = options.coarseSpacing;
  bool ok = false;
  for (int halvings = 0; halvings <= 6 && !ok; ++halvings, spacing *= 0.5)
    ok = coarseSet(level, spacing, kept, mesh);
  spacing *= 2.0;  // the one that worked (or the last tried)
  if (!ok) {
    kept.resize(level.probes.size());
    for (size_t i = 0; i < kept.size(); ++i) kept[i] = uint32_t(i);
    std::vector<glm::dvec3> pts;
    for (const glm::vec3& p : level.probes) pts.push_back(glm::dvec3(p) + level.origin);
    mesh = tetrahedralizeDelaunay(pts);
    spacing = 0.0;
  }
  std::vector<glm::dvec3> pts;
  for (uint32_t i : kept) pts.push_back(glm::dvec3(level.probes[i]) + level.origin);
  const std::vector<Tet> coarseTets = buildTetRecords(pts, mesh, level.origin);

  // Serialise (docs/level_format.md, STRM).
  size_t tetRefs = 0, probeRefs = 0, nodes = 0, maxSector = 0;
  for (const auto& [key, d] : sectors) {
    tetRefs += d.tets.size();
    probeRefs += d.probes.size();
    nodes += d.nodes.size();
    maxSector = std::max(maxSector, (d.tets.size() + d.probes.size()) * 4 + d.tets.size() * (32 + 8) +
                                        d.probes.size() * 120 + d.nodes.size() * 24);
  }
  // The checksums (the index's, at byte 56, and each sector's, at byte 40 of its record) are left zero:
  // saveLevel computes them over the bytes it writes (runtime/src/stream_format.h).
  Bytes w;
  w.u32(2);  // version
  w.u32(uint32_t(sectors.size()));
  for (int a = 0; a < 3; ++a) w.f32(g.min[a]);
  w.f32(g.cellSize);
  w.u64(tetRefs);
  w.u64(probeRefs);
  w.u64(nodes);
  w.u32(uint32_t(kept.size()));
  w.u32(uint32_t(coarseTets.size()));
  w.u32(0);  // the index's CRC
  w.u32(0);
  uint32_t tetAt = 0, probeAt = 0, nodeAt = 0;
  for (const auto& [key, d] : sectors) {
    for (int32_t k : d.key) w.i32(k);
    w.i32(d.root);
    w.u32(tetAt);
    w.u32(uint32_t(d.tets.size()));
    w.u32(probeAt);
    w.u32(uint32_t(d.probes.size()));
    w.u32(nodeAt);
    w.u32(uint32_t(d.nodes.size()));
    w.u32(0);  // the sector's CRC
    tetAt += uint32_t(d.tets.size());
    probeAt += uint32_t(d.probes.size());
    nodeAt += uint32_t(d.nodes.size());
  }
  for (const auto& [key, d] : sectors)
    for (uint32_t t : d.tets) w.u32(t);
  for (const auto& [key, d] : sectors)
    for (uint32_t p : d.probes) w.u32(p);
  for (const auto& [key, d] : sectors)
    for (const BspNode& n : d.nodes) {
      for (float x : n.plane) w.f32(x);
      w.i32(n.child[0]);
      w.i32(n.child[1]);
    }
  for (uint32_t i : kept)
    for (int a = 0; a < 3; ++a) w.f32(level.probes[i][a]);
  for (uint32_t i : kept)
    for (const glm::vec3& c : level.sh[i].c)
      for (int a = 0; a < 3; ++a) w.f32(c[a]);
  for (const Tet& t : coarseTets) {
    for (int32_t v : t.v) w.i32(v);
    for (int32_t n : t.n) w.i32(n);
  }
  if (stats) {
    stats->sectors = sectors.size();
    stats->tetRefs = tetRefs;
    stats->probeRefs = probeRefs;
    stats->nodes = nodes;
    stats->coarseProbes = kept.size();
    stats->coarseTets = coarseTets.size();
    stats->coarseSpacing = spacing;
    stats->bytes = w.b.size();
    stats->maxSectorBytes = maxSector;
  }
  return w.b;
}

}  // namespace tetraprobe
