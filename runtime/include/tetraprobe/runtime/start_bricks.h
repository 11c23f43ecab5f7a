// The GPU lookup's start: for each occupied cell of the sparse cell grid (cell_grid.h; 16 m by default) a
// dense brick of dim^3 sub-cells, each naming a tet at or a few face steps from the tet that holds the
// sub-cell's centre. The shader (tetraprobeCellStartTet, shaders/tetraprobe_locate.glsl) finds the cell with
// one hash search (the cell grid's own table and keys; usually its first slot) and reads one int, where the
// CPU descends the cell's BSP; the walk then finishes in a step or a few. The start never changes the answer,
// only the walk's length: the walk decides (tests/render: GPU == CPU per pixel). The BSP nodes stay on the
// CPU (ProbeQuery's exact start); the GPU holds the hash slots and the bricks instead. Built at upload, not
// stored in the level file. Permissive: standard library and GLM only.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include <glm/vec3.hpp>

#include "tetraprobe/runtime/cell_grid.h"
#include "tetraprobe/runtime/level.h"
#include "tetraprobe/runtime/query.h"

namespace tetraprobe {

// Sub-cells along a brick's edge: 16 m cells in 1 m sub-cells (docs/rendering.md: measured against 4 and 8).
inline constexpr int32_t kStartBrickDim = 16;

struct StartBricks {
  glm::vec3 min{0.0f};  // the cell grid's: cell (i,j,k) covers min + [i, i+1) * cellSize per axis
  float cellSize = 16.0f;
  uint32_t maxProbe = 0;  // the cell grid's table bound (0: no bricks, the walk starts from the start grid)
  int32_t dim = 0;        // sub-cells a brick edge
  // The cell grid's hash table, slot for slot (same keys, same places), with root = the cell's brick index.
  std::vector<CellSlot> slots;
  // Brick b's sub-cell (i,j,k) (i along x) names startTet[b * dim^3 + i + dim * (j + dim * k)].
  std::vector<int32_t> startTet;
};

// Bricks of `dim` (1..64) sub-cells an edge for every occupied cell of `cellGrid` (built on `level`, as
// ProbeQuery::cellGrid()), in slot order. A sub-cell names the tet a walk from its centre's BSP leaf tet
// reaches (up to 64 steps of the ordinary walk in float, stopping at a hull face): the tet holding the
// centre, or for a centre outside the hull the hull tet the walk stops at; where the centre's leaf is empty,
// the walk starts from the start grid's cell (`grid`, ProbeQuery::startGrid()). Deterministic. Empty when
// the level has no tets or the cell grid no cells. `cellGrid` must be well formed (indices in range, children
// after their parents: as buildCellGrid makes it and loadLevel checks it; packLevelBuffers checks it first).
// Allocates the result.
StartBricks buildStartBricks(const Level& level, const StartGrid& grid, const CellGrid& cellGrid,
                             int32_t dim = kStartBrickDim);

// A brick entry's walk: from tet `start` across the face of the most negative float weight until local point
// x is inside, a face without a neighbour is reached, or 64 steps; returns where it stopped (a start for the
// shader's own walk, not an answer). `start` must be a tet of `level`.
int32_t startBrickWalk(const Level& level, int32_t start, const glm::vec3& x);

// What the bricks take on the GPU for `cellGrid` on a level of `tets` tets: 16 bytes a hash slot, and the
// sub-cells' start tets packed at bitsFor(tets) bits each (the tets' neighbour width, gpu_tets.h) in whole
// words plus one zero word; 0 without cells.
size_t startBricksBytes(const CellGrid& cellGrid, size_t tets, int32_t dim = kStartBrickDim);

}  // namespace tetraprobe
