// The point-location accelerator of Valient (GDC 2014, Killzone Shadow Fall): a sparse grid of cubic cells
// (16 m by default) found through a hash table, and in each occupied cell a BSP tree over the tets that
// overlap it. Descending the tree names a list of tets (a leaf) that holds every tet overlapping the leaf's
// region (LeafHoldsContainingTet); ProbeQuery::locate starts the ordinary walk (query.cpp) from one of them,
// so the answer is the walk's, whatever the tree's splits. Permissive: standard library and GLM only.
#pragma once

#include <climits>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <vector>

#include <glm/vec3.hpp>

namespace tetraprobe {

struct Tet;  // level.h (which holds a CellGrid)

// One BSP node, flat array (32 bytes). A point x (local frame) goes to child[1] when
// dot(plane.xyz, x) + plane.w >= 0, else to child[0]. A child >= 0 is a node index; a child < 0 is the leaf
// at leafTets[-(child + 1)]: a count, then that many tet indices.
struct BspNode {
  float plane[4];
  int32_t child[2];
  int32_t pad[2];
};
static_assert(sizeof(BspNode) == 32, "BspNode is 32 bytes");

// One slot of the cell hash table (16 bytes). key = integer cell coordinates; root = the cell's tree (node
// index >= 0, or a leaf code < 0 as in BspNode::child). Empty slots have key[0] == INT32_MIN.
struct CellSlot {
  int32_t key[3];
  int32_t root;
};
static_assert(sizeof(CellSlot) == 16, "CellSlot is 16 bytes");

struct CellGrid {
  glm::vec3 min{0.0f};  // local frame, metres: cell (i,j,k) covers min + [i, i+1) * cellSize per axis
  float cellSize = 16.0f;
  // Open addressing with linear probing over a power-of-two table at most half full. A lookup inspects at
  // most maxProbe slots (the longest probe sequence any stored key needed; the build grows the table until it
  // is <= kMaxCellProbe) and then knows the cell is absent.
  uint32_t maxProbe = 0;
  std::vector<CellSlot> slots;
  std::vector<BspNode> nodes;
  std::vector<int32_t> leafTets;
  // Statistics of the build: deepest leaf, mean leaf depth weighted by the leaf's tets, and tet references
  // held by leaves (a tet straddling split planes or cells is held by several).
  int maxDepth = 0;
  double meanDepth = 0.0;
  size_t leafReferences = 0;
};

inline constexpr uint32_t kMaxCellProbe = 8;

// The table's hash of cell coordinates (32-bit arithmetic, mirrored by tetraprobeCellHash in
// shaders/tetraprobe.glsl): a slot search starts at cellHash(key) & (slots.size() - 1).
uint32_t cellHash(int32_t x, int32_t y, int32_t z);

// Buckets `tets` (over `probes`, local frame) into cells of `cellSize` metres by their bounding boxes and
// builds each cell's BSP: split planes are tet face planes, scored as Godot's LightmapGI does
// (min/max balance times the squared fraction of tets not straddling); tets within a rounding margin of a
// plane go to both sides; a leaf holds at most 8 tets (more only where no face plane separates them, or at
// depth 48). Deterministic for any `threads` (0 = all cores). Allocates the result.
CellGrid buildCellGrid(const std::vector<glm::vec3>& probes, const std::vector<Tet>& tets,
                       float cellSize = 16.0f, int threads = 0);

// The leaf holding local point x: a pointer to its tet indices and their count (0 when x's cell is absent or
// its leaf is empty: x is then outside every tet overlapping the grid). `depth` (optional) gets the number
// of nodes descended.
const int32_t* cellGridLeaf(const CellGrid& grid, const glm::dvec3& x, int32_t* count, int* depth = nullptr);

// The steps of cellGridLeaf one by one, for callers interleaving many queries (ProbeQuery::irradianceBatch
// prefetches each step's memory for a group of queries before taking it). cellGridLeaf is exactly
// cellGridKey, then cellGridFind from cellGridSlot, then cellGridChild until the code is a leaf (< 0).

// x's cell coordinates; false when x is beyond any representable cell (or NaN): no cell, no leaf.
inline bool cellGridKey(const CellGrid& grid, const glm::dvec3& x, int32_t key[3]) {
  for (int a = 0; a < 3; ++a) {
    const double f = std::floor((x[a] - double(grid.min[a])) / double(grid.cellSize));
    if (!(f >= -2e9 && f <= 2e9)) return false;  // also NaN
    key[a] = int32_t(f);
  }
  return true;
}

// The slot where the search for `key` starts (the table must not be empty).
inline size_t cellGridSlot(const CellGrid& grid, const int32_t key[3]) {
  return size_t(cellHash(key[0], key[1], key[2])) & (grid.slots.size() - 1);
}

// The cell's tree (a node index >= 0 or a leaf code < 0), searching from slot h; false when absent.
inline bool cellGridFind(const CellGrid& grid, const int32_t key[3], size_t h, int32_t* root) {
  const size_t mask = grid.slots.size() - 1;
  for (uint32_t probe = 0; probe < grid.maxProbe; ++probe, h = (h + 1) & mask) {
    const CellSlot& s = grid.slots[h];
    if (s.key[0] == INT32_MIN) return false;
    if (s.key[0] == key[0] && s.key[1] == key[1] && s.key[2] == key[2]) {
      *root = s.root;
      return true;
    }
  }
  return false;
}

// The child of node `n` on x's side of its plane (evaluated in double).
inline int32_t cellGridChild(const BspNode& n, const glm::dvec3& x) {
  const double s =
      double(n.plane[0]) * x.x + double(n.plane[1]) * x.y + double(n.plane[2]) * x.z + double(n.plane[3]);
  return n.child[s >= 0.0 ? 1 : 0];
}

}  // namespace tetraprobe
