// Occlusion holes: surface points whose tet's occlusion data hides all four of its probes, so the lookup can
// only fall back (runtime/occlusion.h, occludedIrradiance) and draws a dark, hard-edged polygon. Each such
// point gets a new probe in front of it, on its own side of the geometry, so that once the level is
// tetrahedralized again the point lies in a tet with a probe it sees. Build side.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include <glm/vec3.hpp>

#include "tetraprobe/bake/tracer.h"
#include "tetraprobe/runtime/level.h"

namespace tetraprobe {

struct OcclusionHoleOptions {
  double spacing = 1.0;  // probe spacing near geometry, metres: new probes sit at most spacing / 2 in
                         // front of their point, one per spacing / 2 cell
  double pointsPerSquareMetre = 4.0;  // surface points checked, per m^2 of surface x (1 m / spacing)^2
  int minPoints = 4096, maxPoints = 50000;
  uint64_t seed = 0x401e5ull;  // surface points (sampleSurfacePoints)
};

struct OcclusionHoles {
  size_t pointsChecked = 0;  // surface points drawn (on their open side)
  size_t holePoints = 0;     // of those, points that see none of their tet's probes (fallback share > 0)
  std::vector<glm::dvec3> probes;  // new probe positions, world metres, deterministic order
};

// Finds the holes of `level` (which must store occlusion; none: an empty result) at area-uniform surface
// points and proposes one probe per hole cell: at point + normal x d with d = min(spacing / 2, half the free
// distance along the normal), skipped when d < spacing / 50 (no room) or when an existing probe or an earlier
// proposal lies within spacing / 10 (the placement's merge distance); proposals de-duplicated on a grid of
// spacing / 2 (the first point of a cell, in draw order, wins). Deterministic. Throws InputError for a
// non-positive or non-finite spacing.
OcclusionHoles findOcclusionHoles(const SceneTracer& tracer, const Level& level,
                                  const OcclusionHoleOptions& options);

}  // namespace tetraprobe
