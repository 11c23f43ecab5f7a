// Probe SH fitted to the surfaces they light: a regularised least-squares fit of every probe's SH so that the
// run-time lookup's own answer (shadeLocated, runtime/shade.h: the located tet's weights with occlusion and
// the face blend applied) matches the path-traced irradiance at surface points. Build side.
//
// Model. At a fit point x with unit normal n whose lookup does not fall back (ShadeRecord::fallback == 0), the
// lookup answers E(x) = sum_s w_s sum_k A_l(k) Y_k(n) SH_{v_s, k} per channel (w = ShadeRecord::weights over
// the located tet's probes v_0..3): linear in the probe SH, with exactly the weights the lookup blends. Points
// that fall back (the fallback's nearest-probe blend and cap are not linear) and points outside any tet are
// left out and counted.
//
// Objective, per colour channel c, over the probes' SH x (x0 = the traced SH, level.sh):
//   sum_p (E_p(x) - T_pc)^2 / (s_pc^2 + (kShFitPointRelFloor max(T_pc, f))^2)
//   + lambda sum_j mean_n (E_j(n; x) - E_j(n; x0))^2 / sd_j^2
// T the point's traced irradiance, s its standard error, f = kRelFloorFraction (evaluate.h) x the points'
// mean target luminance; E_j(n; x) probe j's own irradiance at normal n, whose mean square over the sphere is
// sum_k A_l(k)^2 (x_jk - x0_jk)^2 / (4 pi); sd_j = max(probeRelError_j, probeRelFloor) x max(Y(pi Y00 L00_j),
// f), the probe's irradiance noise. Solved by Jacobi-preconditioned conjugate gradients on the normal
// equations (each point couples 4 probes x 9 coefficients), serially: the result does not depend on threads.
// Then each probe's move is capped: per channel, the RMS change of its irradiance over normals at most
// maxMove x max(its irradiance, f) (scaled down as a whole), and L00 kept >= 0. The caller derings afterwards
// (bake.h, deringProbes), which keeps E(n) >= 0 for every normal.
//
// Cross-validation (ShFitOptions::crossValidate). A probe's fitted value can serve the points it was fitted to
// and miss the ones between them (a probe lighting both sides of a door gap, a probe whose few points happen to
// be noisy). Before the final fit, the points are split in two folds (even and odd index); each fold is fitted
// alone (capped as below), and at every point of the other fold the change of its error, the mean over channels
// of |ln((max(E, 0) + f) / (T + f))| (symmetric in the ratio, as the gate's gross share is), is charged to its
// tet's probes by their lookup weights. A probe whose charge is positive (its fitted values made unseen points worse on balance) is
// held at its traced SH in the final fit over all points, which moves only the others.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include <glm/vec3.hpp>

#include "tetraprobe/bake/bake.h"
#include "tetraprobe/runtime/level.h"
#include "tetraprobe/runtime/sh.h"

namespace tetraprobe {

// A surface point and its traced irradiance (W/m^2 per channel, world metres; unit normal into open space).
struct ShFitPoint {
  glm::dvec3 position{0.0};
  glm::vec3 normal{0.0f};
  glm::vec3 target{0.0f};    // path-traced irradiance
  glm::vec3 stderror{0.0f};  // its standard error
};

// Points' floor on the residual's scale, as a fraction of max(T, f): keeps a point whose 256 paths happened
// to agree closely from outweighing its neighbours.
inline constexpr double kShFitPointRelFloor = 0.1;

struct ShFitOptions {
  double lambda = 1.0;            // weight of the pull toward the traced SH; >= 0 (infinite: x = x0)
  double probeRelFloor = 0.02;    // sd_j's relative noise at least this (a converged probe is not exact)
  double unknownRelError = 0.05;  // probes with no noise estimate (probeRelError < 0 or missing)
  double maxMove = 0.3;           // cap on a probe's RMS irradiance change, x max(its irradiance, f)
  int maxIterations = 400;        // conjugate-gradient iterations per channel
  double tolerance = 1e-6;        // stop when the preconditioned residual falls below this x its start
  bool crossValidate = true;      // hold probes whose fit worsens the points left out (see below)
};

struct ShFitStats {
  size_t points = 0;          // points given
  size_t fitted = 0;          // of them, in the fit (located, no fallback, finite target)
  size_t fallbackPoints = 0;  // left out: the lookup falls back there
  size_t otherSkipped = 0;    // left out: no tet, or a non-finite target
  size_t probesTouched = 0;   // probes some fitted point weights
  size_t cappedProbes = 0;    // probes whose move the maxMove cap shortened (any channel)
  size_t heldProbes = 0;      // probes the cross-validation held at their traced SH
  int iterations[3] = {0, 0, 0};
  double objectiveBefore = 0.0, objectiveAfter = 0.0;  // data term (all channels) at x0 and at the result
};

// The fitted SH, one per probe of `level` (level.sh is x0 and is not changed). probeRelError: per probe, its
// relative noise (BakeStats::probeRelError; may be empty: every probe unknownRelError). With no fitted point,
// or lambda infinite, returns level.sh unchanged. The result is finite. Deterministic for any thread count
// (`threads` only parallelises the per-point lookups). Throws std::invalid_argument for lambda < 0 or NaN, a
// probeRelError of another size than the probes (when not empty), or level.sh of another size.
std::vector<ShRgb> fitProbeSh(const Level& level, const std::vector<ShFitPoint>& points,
                              const std::vector<float>& probeRelError, const ShFitOptions& options,
                              ShFitStats* stats = nullptr, int threads = 0);

// Points where a fit or its hold-out measures: `count` area-uniform surface points (sampleSurfacePoints,
// seeded by `seed`: points a viewer could stand in front of) with referenceIrradiance at `samples` paths
// (unbounded depth, `content`). Deterministic for any thread count; `farm` as RefineOptions::farm.
std::vector<ShFitPoint> shFitPoints(const SceneTracer& tracer, int count, int samples, uint64_t seed,
                                    uint32_t content, int threads = 0, bool progress = false,
                                    const TraceFarm* farm = nullptr);

// The hold-out score of the level's `tet` lookup (ProbeQuery::irradiance, its stored occlusion and fallback
// included) at `points`, as eval scores (evaluate.h), over the points whose target is not 0 in every channel:
//   meanRelError = mean over points of the mean over channels of |x - r| / max(r, f), f = kRelFloorFraction x
//   the mean target luminance;  gross = the fraction with lum(x) > 2 lum(r) or < lum(r) / 2 (luminances
//   floored at 0.01 W/m^2). Zeros when no point counts.
struct ShFitScore {
  size_t points = 0;  // points that count
  double meanRelError = 0.0;
  double gross = 0.0;
};
ShFitScore shFitScore(const Level& level, const std::vector<ShFitPoint>& points);

// The bake's --fit auto gate on an independent hold-out: keep the fit when its mean relative error drops and
// its gross share does not rise. False when either score has no points. (A gate that let gross rise by one
// binomial standard error of the hold-out's share was measured and not kept: docs/accuracy.md#probe-guiding.)
bool shFitKept(const ShFitScore& before, const ShFitScore& after);

}  // namespace tetraprobe
