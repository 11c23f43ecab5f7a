// The point-location accelerator of Valient (GDC 2014, Killzone Shadow Fall): a sparse grid of cubic cells
// (16 m by default) found through a hash table, and in each occupied cell a BSP tree over the tets that
// overlap it, descended to a leaf naming one tet: the tet holding the leaf's whole region, or, in a leaf
// whose region meets at most a handful of tets, the one holding its centre (built with exact region
// tracking, cell_grid.cpp). ProbeQuery::locate takes that tet and lets the ordinary walk (query.cpp) confirm
// it or step on to the tet holding the point, so the answer is the walk's, whatever the tree's splits.
// Permissive: standard library and GLM only.
#pragma once

#include <climits>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <vector>

#include <glm/vec3.hpp>

namespace tetraprobe {

struct Tet;  // level.h (which holds a CellGrid)

// One BSP node, flat array (24 bytes). A point x (local frame) goes to child[1] when
// dot(plane.xyz, x) + plane.w >= 0, else to child[0]. A child >= 0 is a node index (always larger than its
// parent's); a child < 0 is a leaf: the tet ~child (= -(child + 1)), or kEmptyLeaf (no tet: the region lies
// outside every tet).
struct BspNode {
  float plane[4];
  int32_t child[2];
};
static_assert(sizeof(BspNode) == 24, "BspNode is 24 bytes (6 ints on the GPU)");

inline constexpr int32_t kEmptyLeaf = INT32_MIN;

// The tet a leaf code (< 0) names, or -1 for kEmptyLeaf.
inline int32_t bspLeafTet(int32_t code) {
  return code == kEmptyLeaf ? -1 : ~code;
}

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
  // Statistics of the build: the deepest leaf; the mean leaf depth weighted by the leaf regions' volumes
  // (the expected descent of a uniformly random point in the occupied cells); leaves; and the leaves whose
  // tet was chosen without proof that it holds the whole region (the depth bound or no cutting face plane
  // was reached first; the walk from such a tet still gives the right answer, a step or two later).
  int maxDepth = 0;
  double meanDepth = 0.0;
  size_t leaves = 0;
  size_t unprovenLeaves = 0;
};

inline constexpr uint32_t kMaxCellProbe = 8;

// Occupied cells (used hash slots), and the grid's size in memory, on the GPU and in the level file
// (16 bytes a slot, 24 a node).
inline size_t occupiedCells(const CellGrid& grid) {
  size_t n = 0;
  for (const CellSlot& s : grid.slots) n += s.key[0] != INT32_MIN;
  return n;
}
inline size_t cellGridBytes(const CellGrid& grid) {
  return grid.slots.size() * sizeof(CellSlot) + grid.nodes.size() * sizeof(BspNode);
}

// The table's hash of cell coordinates (32-bit arithmetic, mirrored by tetraprobeCellHash in
// shaders/tetraprobe_locate.glsl): a slot search starts at cellHash(key) & (slots.size() - 1).
uint32_t cellHash(int32_t x, int32_t y, int32_t z);

// Buckets `tets` (over `probes`, local frame) into cells of `cellSize` metres by their bounding boxes and
// builds each cell's BSP: split planes are tet face planes cutting the node's region, scored on balance
// (min/max of the tets on either side, as Godot's LightmapGI) and, more strongly, on the share of tets not
// straddling (straddlers are copied into both children); each node keeps the
// tets that overlap its region (a convex polytope, clipped at every split; a tet touching it only within a
// rounding margin is dropped), and a node whose region lies inside one tet is a leaf naming it; so is a node
// with at most `leafTets` tets left, naming the one holding its region's centroid best (the query's walk
// takes the remaining steps, usually one or two: leafTets = 1 makes the leaf's tet the answer for every
// point, at about four times the nodes of the default on placed levels (docs/point_location.md)). A tet whose cells would lie beyond +-2^30 on an axis (huge coordinates for the cell size) or
// number more than 4096 is left out, to be found by the walk; no float reaches an int conversion unchecked.
// Nodes are laid out tree by tree in cell order, each tree in preorder (a node, its under subtree, its over
// subtree): the level file relies on it to store no node indices (CGR4). Deterministic for any `threads`
// (0 = all cores). Allocates the result.
inline constexpr int kDefaultLeafTets = 6;
CellGrid buildCellGrid(const std::vector<glm::vec3>& probes, const std::vector<Tet>& tets,
                       float cellSize = 16.0f, int threads = 0, int leafTets = kDefaultLeafTets);

// The split plane buildCellGrid cuts from a tet face: the face opposite corners[f] (corners: the tet's four
// probe positions in its v order), unit outward normal (away from corners[f]) and offset, computed in double
// and rounded to float (`plane`, what a BspNode stores). False for a flat face. Every node plane
// buildCellGrid makes is one of these, which lets the level file store a node as the face it was cut from
// (docs/level_format.md, CGR4) and the loader recompute the same floats.
bool cellGridFacePlane(const glm::vec3 corners[4], int f, float plane[4]);

// The tet named by the leaf holding local point x, or -1 (x's cell is absent or its leaf empty: x is then
// outside every tet overlapping the grid, up to rounding). `depth` (optional) gets the nodes descended.
int32_t cellGridLeaf(const CellGrid& grid, const glm::dvec3& x, int* depth = nullptr);

// The steps of cellGridLeaf one by one, for callers interleaving many queries (ProbeQuery::irradianceBatch
// prefetches each step's memory for a group of queries before taking it). cellGridLeaf is exactly
// cellGridKey, then cellGridFind from cellGridSlot, then cellGridChild until the code is a leaf (< 0), then
// bspLeafTet.

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
