// The level file's packed form of the tets' probe indices (TETM, docs/level_format.md). Internal to the
// runtime (level_io.cpp).
//
// The tetrahedralizer writes tets in Morton order of their centroids, so a tet's probes were mostly named by
// the tets just before it: on the shared levels 73-80 % of indices are among the last 15 distinct probes
// named. Each tet is two control bytes, a nibble per vertex in v order (v[0] in the low nibble of the first
// byte, v[1] its high nibble, v[2] and v[3] likewise in the second), then the vertices the nibbles do not
// give, as LEB128 varints in v order:
//   nibble 0..14  the probe at that position of a move-to-front list of the probes last named,
//   nibble 15     the next varint: zigzag(probe - the last probe given this way), starting from 0.
// After each vertex its probe moves to the front of the list (at most 15 entries: a probe new to the list
// pushes out the last). Every tet keeps its vertex order (faces, orientation and the other sections refer to
// it). 3.3-4.0 bytes a tet on the shared levels, against 8 in TETC.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "tetraprobe/runtime/level.h"

namespace tetraprobe::runtime_detail {

// Appends the tets' probe indices (v only) to `out`. Every index must be >= 0.
void encodeTetProbes(const std::vector<Tet>& tets, std::string& out);

// Decodes `tetCount` tets' v from the `size` bytes at `p`, which must be exactly their stream; sets every n
// to -1. Returns "" on success, else what is wrong, naming the tet: a list position not yet filled, a probe
// outside [0, probeCount), a probe twice in one tet, a truncated or overlong varint, bytes left over. Never
// reads outside [p, p + size) and allocates nothing before checking 2 tetCount <= size.
std::string decodeTetProbes(const uint8_t* p, size_t size, size_t tetCount, size_t probeCount,
                            std::vector<Tet>& tets);

}  // namespace tetraprobe::runtime_detail
