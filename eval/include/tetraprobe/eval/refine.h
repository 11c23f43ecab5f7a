// Error-driven probe refinement: after a first bake, measure the lookup's error against the path-traced
// oracle at surface points the bake can afford, and propose probes where it is largest. Build side.
//
// Error of a point (lookup x, reference r, luminance Y floored at 0.01 W/m^2):
//   e = |log2(Y(x) / Y(r))|, counted only when |Y(x) - Y(r)| exceeds 3 standard errors of the reference
//   (noise in the oracle is not error). gross = the fraction with e > 1 (off by more than 2x either way).
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include <glm/vec3.hpp>

#include "tetraprobe/bake/bake.h"
#include "tetraprobe/runtime/level.h"

namespace tetraprobe {

struct RefineOptions {
  double spacing = 1.0;  // probe spacing near geometry, metres: proposals sit at most spacing / 2 in front
                         // of their point, at most one per spacing / 2 cell, never within spacing / 10
                         // of an existing probe
  int points = 2048;     // surface points, area-uniform (sampleSurfacePoints)
  int samplesPerPoint = 256;           // reference paths per point (unbounded depth)
  uint32_t content = kContentDefault;  // the level's light content
  uint64_t seed = 0x2ef1eull;
  int threads = 0;
  bool progress = false;  // progress over the points' references (common/progress.h)
  // When set (and its `references`), the points' references are traced there as one ReferenceBatch
  // (traceReferences: the same results, each point's seed travels with it). Not owned.
  const TraceFarm* farm = nullptr;
};

// One surface point and what it measured.
struct RefinePoint {
  SurfacePoint surface;
  ReferenceIrradiance reference;
  double error = 0.0;  // e above (0 within the reference's noise)
};

struct ErrorEstimate {
  size_t points = 0;
  double meanLogError = 0.0;  // mean e over the points
  double gross = 0.0;         // fraction with e > 1
};

// Draws options.points surface points and their references (parallel, deterministic for any thread count).
std::vector<RefinePoint> refinePoints(const SceneTracer& tracer, const RefineOptions& options);

// Scores the level's `tet` lookup (ProbeQuery, with its stored occlusion) at the points (fills error) and
// summarizes.
ErrorEstimate scoreRefinePoints(const Level& level, std::vector<RefinePoint>& points);

// How far in front of its surface point a refinement probe sits, as a fraction of the spacing (at most; half
// the free distance along the normal when that is less). The error is the surface's, so the probe goes
// where it sees nearly what the surface sees: on Veach Ajar (1 m spacing) a wall beside the door gap is
// 12-17 W/m^2 while 0.5 m in front of it the truth is 148, and camera-view mean rel. error fell from 0.220
// (spacing / 2) to 0.199 (/ 4) and 0.168 (/ 8) (docs/accuracy.md, Tried).
inline constexpr double kRefineOffsetFraction = 1.0 / 8.0;

// Up to `budget` new probe positions (world metres) in front of the worst points (largest e first, ties by
// index; only points with e > minError), at point + normal x min(maxOffset, half the free distance along
// the normal) (maxOffset <= 0: spacing x kRefineOffsetFraction), skipped when that is below spacing / 50,
// de-duplicated as RefineOptions says. Deterministic.
std::vector<glm::dvec3> proposeRefinement(const SceneTracer& tracer, const Level& level,
                                          const std::vector<RefinePoint>& points, size_t budget,
                                          double spacing, double minError = 0.1, double maxOffset = 0.0);

}  // namespace tetraprobe
