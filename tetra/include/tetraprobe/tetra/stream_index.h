// The streaming index of a level (the optional STRM section, docs/level_format.md; read by the runtime's
// StreamingLevel, runtime/streaming.h): per sector (one occupied cell of the level's cell grid) the tets
// whose bounding boxes touch the cell and the tets sharing a probe with one that the run time's face blend
// may read in the cell (faceBlendMayReach) and their face neighbours,
// their probes and the cell's BSP nodes, plus a coarse probe set
// tetrahedralized here for the regions not loaded. Build side (CGAL Delaunay for the coarse set).
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "tetraprobe/runtime/level.h"

namespace tetraprobe {

struct StreamIndexOptions {
  // Coarse set: the level's probes decimated to one per cube of this edge (metres, local frame): the probe
  // nearest the cube's centre (ties: the lower index), keeping its SH. Halved until the kept probes can be
  // tetrahedralized (at least 4, not coplanar); every probe when even 1/64 of it cannot.
  double coarseSpacing = 8.0;
  // A tet belongs to a sector when its bounding box overlaps the cell grown by this margin (metres), so
  // rounding at the cell's faces cannot leave out a tet the walk steps to.
  double margin = 1e-3;
};

struct StreamIndexStats {
  size_t sectors = 0;
  size_t tetRefs = 0, probeRefs = 0, nodes = 0;  // summed over sectors (a tet in k sectors counts k times)
  size_t coarseProbes = 0, coarseTets = 0;
  double coarseSpacing = 0.0;  // the spacing used (after halving)
  size_t bytes = 0;            // the section's size
  size_t maxSectorBytes = 0;   // the largest sector's records as the runtime holds them
};

// The STRM section's bytes for `level` (which must carry its cell grid: InputError otherwise). Deterministic:
// a pure function of the level and options.
std::vector<uint8_t> buildStreamIndex(const Level& level, const StreamIndexOptions& options = {},
                                      StreamIndexStats* stats = nullptr);

}  // namespace tetraprobe
