// Start bricks for the GPU lookup: per occupied cell of the sparse cell grid a dense brick of start tets,
// read by the shader in one hash search and one load instead of the BSP descent. Contract:
// runtime/include/tetraprobe/runtime/start_bricks.h. The idea is the dense "start where the pixel is" grid of
// issue 30, bricked over the cell grid's hash so that empty space costs nothing.
#include "tetraprobe/runtime/start_bricks.h"

#include "tetraprobe/runtime/gpu_tets.h"

#include <algorithm>
#include <cmath>

namespace tetraprobe {
namespace {

// The walk's step bound when a brick is built: a start, not an answer (the shader walks on from it).
constexpr int kBrickWalkSteps = 64;

// The start grid's cell of x, clamped (as tetraprobeStartCellTet).
int32_t startGridTet(const StartGrid& g, const glm::dvec3& x) {
  int c[3];
  for (int a = 0; a < 3; ++a) {
    const double f = std::floor((x[a] - double(g.min[a])) / double(g.cellSize[a]));
    c[a] = int(std::clamp(f, 0.0, double(g.dims[a] - 1)));
  }
  return g.startTet[size_t(c[0] + g.dims.x * (c[1] + g.dims.y * c[2]))];
}

}  // namespace

int32_t startBrickWalk(const Level& level, int32_t cur, const glm::vec3& x) {
  for (int step = 0; step < kBrickWalkSteps; ++step) {
    const Tet& t = level.tets[size_t(cur)];
    const glm::vec4 w = baryWeights(baryFrame(t, level.probes), x);
    int m = 0;
    for (int i = 1; i < 4; ++i)
      if (w[i] < w[m]) m = i;
    if (!(w[m] < 0.0f) || t.n[m] < 0) break;  // inside (or not finite), or a hull face
    cur = t.n[m];
  }
  return cur;
}

size_t startBricksBytes(const CellGrid& cellGrid, size_t tets, int32_t dim) {
  const size_t cells = occupiedCells(cellGrid);
  if (cells == 0) return 0;
  const uint64_t entries = uint64_t(cells) * uint64_t(dim) * uint64_t(dim) * uint64_t(dim);
  return cellGrid.slots.size() * sizeof(CellSlot) +
         packedFieldWords(entries, bitsFor(tets)) * sizeof(uint32_t);
}

StartBricks buildStartBricks(const Level& level, const StartGrid& grid, const CellGrid& cellGrid,
                             int32_t dim) {
  StartBricks b;
  dim = std::clamp(dim, 1, 64);
  if (level.tets.empty() || grid.startTet.empty() || occupiedCells(cellGrid) == 0) return b;
  b.min = cellGrid.min;
  b.cellSize = cellGrid.cellSize;
  b.maxProbe = cellGrid.maxProbe;
  b.dim = dim;
  b.slots = cellGrid.slots;
  int32_t brick = 0;
  for (CellSlot& s : b.slots) {
    if (s.key[0] == INT32_MIN) continue;
    s.root = brick++;
    for (int k = 0; k < dim; ++k)
      for (int j = 0; j < dim; ++j)
        for (int i = 0; i < dim; ++i) {
          const glm::dvec3 sub(i, j, k);
          const glm::dvec3 centre = glm::dvec3(cellGrid.min) +
                                    (glm::dvec3(s.key[0], s.key[1], s.key[2]) + (sub + 0.5) / double(dim)) *
                                        double(cellGrid.cellSize);
          int32_t start = cellGridLeaf(cellGrid, centre);
          if (start < 0 || size_t(start) >= level.tets.size()) start = startGridTet(grid, centre);
          b.startTet.push_back(startBrickWalk(level, start, glm::vec3(centre)));
        }
  }
  return b;
}

}  // namespace tetraprobe
