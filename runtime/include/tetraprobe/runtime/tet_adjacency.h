// Tet adjacency from vertex indices alone: what the level file no longer stores (docs/level_format.md,
// `TETM`, `TETC`). Two tets are neighbours across a face when they name the same three probes; a face named by one
// tet is on the hull. Permissive: standard library only.
#pragma once

#include <cstddef>
#include <string>
#include <vector>

#include "tetraprobe/runtime/level.h"

namespace tetraprobe {

// Sets every tets[t].n[f] (the face opposite v[f]) to the other tet naming the same three probes, or -1 when
// no other tet does. Precondition: every vertex index is in [0, probeCount) and the four of a tet are
// pairwise distinct (validateLevel's first checks; the loader checks them before calling). Returns an empty
// string on success; when a face is named by three or more tets (not a tetrahedralization) returns one line
// naming the face and its tets, and `tets` keeps unspecified neighbours. Deterministic (a pure function of
// its input), O(T + P) with a counting sort by the face's smallest probe; allocates 16 bytes per face.
std::string linkTetNeighbours(std::vector<Tet>& tets, size_t probeCount);

}  // namespace tetraprobe
