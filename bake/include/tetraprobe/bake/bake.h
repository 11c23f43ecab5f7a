// Probe radiance baking: path-traced incident radiance projected onto SH L2 RGB, and the ground-truth
// reference oracle used by the evaluation. Build side.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <memory>
#include <utility>
#include <vector>

#include <glm/vec3.hpp>

#include "tetraprobe/bake/tracer.h"
#include "tetraprobe/runtime/level.h"
#include "tetraprobe/runtime/sh.h"

namespace tetraprobe {

// Path depth meaning "unbounded": paths end by Russian roulette only (survival probability = the largest
// throughput channel, from the third vertex on), so the estimate is unbiased. The cap only bounds a path in a
// closed box of albedo exactly 1; at albedo 0.99 a path reaches it with probability 0.99^(2^20) = 0.
inline constexpr int kUnboundedBounces = 1 << 20;

// Lit-patch sampling (BakeOptions::litPatches).
enum class LitPatches { kOff, kProbe, kBounces };

// A trace farm (BakeOptions::farm; the batches are declared with TraceRunner below): tracing done elsewhere,
// each batch in place, exactly as this process would (TraceRunner::run, traceReferences). An empty
// function: that kind of work stays here.
struct TraceBatch;
struct ReferenceBatch;
struct TraceFarm {
  std::function<void(TraceBatch& batch)> probes;          // a step of the adaptive bake's probes
  std::function<void(ReferenceBatch& batch)> references;  // reference irradiance at surface points
};

struct BakeOptions {
  int bounces = kUnboundedBounces;  // diffuse bounces after the first hit (0 = direct light only)
  int samplesPerProbe = 256;        // paths per probe (adaptive: the minimum, rounded up to batches)
  // Adaptive sampling (targetRelError > 0): a probe takes batches of kBakeBatchSize paths, each batch a
  // spherical Fibonacci set under its own random rotation (independent replicates of a randomised-QMC
  // estimate), until the standard error of its irradiance is at most targetRelError x its mean: the largest
  // over the six axis normals n of stderr(Y(E(n))) over the batches, against the mean over those normals of
  // Y(E(n)) (Y = Rec. 709 luminance), floored at kBakeErrorFloor x the median of that mean over all probes
  // after the first samplesPerProbe paths (probes that see almost nothing stop there). At most
  // maxSamplesPerProbe paths. 0 = exactly samplesPerProbe paths in one set (no error estimate).
  double targetRelError = 0.0;
  int maxSamplesPerProbe = 8192;
  // Adaptive sampling: paths the whole call may spend (0 = no more than each probe's maxSamplesPerProbe).
  // When the probes that reached their target and those stopped at maxSamplesPerProbe together used fewer, the
  // rest is shared among the probes still above the target, in rounds (each probe at most
  // kBakeBudgetCapFactor x maxSamplesPerProbe paths), the noisier a probe the larger its share (the shares
  // that minimise the mean error, from each probe's error and path count), so a small level whose light
  // arrives through a gap converges instead of stopping at the cap. The shares depend only on the probes'
  // states, never on threads.
  uint64_t pathBudget = 0;
  // Adaptive sampling: > 0, pass 2 stops a probe at this many paths (rounded down to batches, within
  // [samplesPerProbe, maxSamplesPerProbe]) and, with a path budget, the budget's pass spends at least what a
  // flat cap of maxSamplesPerProbe would have (flatCapPaths), so a level whose probes stop at the cap traces
  // about as many paths as with the flat cap, shared by the error: the probes that need fewer give paths to
  // those that need more (the bake pipeline's --share-caps). 0: pass 2 goes to maxSamplesPerProbe.
  int pass2MaxSamples = 0;
  // Lit-patch sampling: the lit map's voxel edge (0 = from the call's probes, litMapVoxelEdge). Given, every
  // call of a bake builds the same map, and a probe's lit-patch histogram goes on from pass to pass as its
  // direction guide does (ProbeBakeState::patches).
  double litVoxel = 0.0;
  // Adaptive sampling: after the first samplesPerProbe paths, each pass that adds batches to a probe records
  // where its paths find light (an equal-area histogram of first directions) and, after 4 batches, draws
  // half of each batch's directions from it (bake/src/probe_guide.h; unbiased: every direction weighted by
  // the mixture's density). false: every batch uniform.
  bool guide = true;
  // Adaptive sampling, with guide, for a probe that would stop at the cap above the target: its later
  // batches also learn in which voxels their first hit found surfaces lit by point, spot or sun lights, and
  // add 32 points drawn on those surfaces (by a map of where the lights fall), their one-bounce light
  // MIS-weighted against the sphere directions (bake/src/patch_guide.h; unbiased). kBounces: the first three
  // hits of each of its paths draw such a point too (light one or two bounces further; two rays a hit).
  LitPatches litPatches = LitPatches::kProbe;
  int threads = 0;                      // 0 = all cores; never changes the result
  uint32_t content = kContentDefault;   // which light the probes hold (ProbeContent flags)
  uint64_t seed = 0x7e77a9b0be5eedull;  // base seed; each probe/point derives its own from it and its index
  bool progress = true;                 // progress bar on a terminal
  // Adaptive sampling: when set (and its `probes`), every step that traces probes (pass 1, pass 2, each round
  // of the path budget) hands them to this farm as one TraceBatch instead of tracing them here (docs/distributed.md#the-
  // merge-farmed). Never changes the result: a farm traces each probe as runTraceBatch does. Not owned.
  const TraceFarm* farm = nullptr;
  int shOrder = 2;  // 2: L2 (9 coefficients); 1: L1, coefficients 4..8 set to exactly 0
};

// What a bake cost. Ray counts are summed per probe, so they are identical for any thread count.
inline constexpr int kBakeBatchSize = 64;
inline constexpr double kBakeErrorFloor = 1e-3;
inline constexpr int kBakeBudgetCapFactor = 16;  // BakeOptions::pathBudget: per-probe ceiling, x maxSamples

struct BakeStats {
  uint64_t intersectRays = 0;  // closest-hit queries (camera-less paths: one per path vertex)
  uint64_t occludedRays = 0;   // shadow (any-hit) queries: NEE of emissive triangles and punctual lights
                               // (in a scene with transmission, shadow rays are closest-hit steps through
                               // the glass and count as intersectRays instead)
  double seconds = 0.0;        // wall time of bakeProbes
  uint64_t paths = 0;          // paths traced over all probes
  int maxPathsPerProbe = 0;
  // Adaptive sampling only (0 otherwise): the achieved relative standard error per probe (the quantity the
  // target bounds), its mean, 95th percentile and maximum over probes, and the probes that stopped at the
  // cap above the target.
  double meanRelError = 0.0, p95RelError = 0.0, maxRelError = 0.0;
  size_t probesAtCap = 0;
  // Adaptive sampling only (empty otherwise): per probe, by index, the achieved relative standard error as
  // above (infinite when it could not be estimated), -1 for a skipped probe. The SH fit
  // (eval/sh_fit.h) weights its pull toward each probe's traced value by it.
  std::vector<float> probeRelError;
  uint64_t budgetPaths = 0;  // paths spent from BakeOptions::pathBudget beyond the per-probe caps
  uint64_t rays() const { return intersectRays + occludedRays; }
  double raysPerSecond() const { return seconds > 0.0 ? double(rays()) / seconds : 0.0; }
};

// BakeStats's figures over a set of probes' relative standard errors (`errors`, -1 entries left out): their
// count, mean (a non-finite error counts 0), 95th percentile (the element of rank ceil(0.95 count) - 1 in
// increasing order), maximum, and how many are above `target`. All 0 for no error.
struct RelErrorSummary {
  size_t count = 0;
  double mean = 0.0, p95 = 0.0, max = 0.0;
  size_t above = 0;
};
RelErrorSummary summarizeRelErrors(std::vector<double> errors, double target);

// Bakes one SH per probe (world-space positions). Deterministic for any `threads`. Adaptive sampling as
// BakeOptions::targetRelError says (in two passes: every probe's first samplesPerProbe paths, then the rest
// against the level-wide floor, so the result does not depend on the order probes are baked in).
// Per probe: options.samplesPerProbe directions (bakeSphereDirections keyed by the seed and the probe index),
// incident radiance L(d) by path tracing (options.bounces, options.content), projected with projectToSh.
// With kContentEmissive in a scene with emissive triangles, as many points drawn on the emitters by power
// join the directions, both MIS-weighted (power heuristic): emitters seen directly from a probe come in with
// far less noise than through the directions alone, and the estimate stays unbiased.
// With kContentDirectPunctual, each unshadowed point/spot light adds (I spot / r^2) Y(d) and each unshadowed
// sun E Y(d) (d towards the light, or the sun disc's centre) analytically: the delta's exact projection,
// times the transmittance of the shadow ray (SceneTracer::transmittance: glass in between scales it).
// Transmissive surfaces (scene.h) are passed by paths with probability `transmission` drawn from the path's
// own random stream, so the result stays bit-identical for any thread count.
// Probes inside geometry are baked like any other (filter them with probesInsideGeometry).
// options.shOrder 1 zeroes coefficients 4..8 after projection (0..3 are those of the L2 bake, bit for bit).
// `stats`, when given, receives the ray counts and the wall time.
// Throws InputError for samplesPerProbe < 1, bounces < 0, shOrder not 1 or 2, a negative or non-finite
// targetRelError, maxSamplesPerProbe < samplesPerProbe (adaptive), or a non-finite probe position.
// `skip` (optional, one entry per probe): probes with skip[i] != 0 are not traced and get zero SH (for probes
// whose SH is replaced anyway, e.g. shell probes behind walls that will be dilated); they take no part in the
// adaptive floor's median. std::invalid_argument when its size differs.
std::vector<ShRgb> bakeProbes(const SceneTracer& tracer, const std::vector<glm::dvec3>& probes,
                              const BakeOptions& options, BakeStats* stats = nullptr,
                              const std::vector<uint8_t>* skip = nullptr);

// ---- Sharded bake (bake/src/bake_probes.cpp; protocol in docs/distributed.md) ----
//
// bakeProbes with adaptive sampling is three passes: (1) every probe's first samplesPerProbe paths, then the
// floor (kBakeErrorFloor x the median pass-1 mean over all probes); (2) each probe alone to its target; (3)
// the path budget shared among the probes still above it. A probe's batches draw from streams keyed by (seed,
// probe index, batch), so its state after pass 2 depends only on the options, its position, its index and
// the floor, never on which process traced it. A shard runs pass 1 for every probe (the floor needs all of
// them) and pass 2 for its own; the merge takes every probe's state and runs pass 3 and the projection:
// bakeProbesMerged(shards' states) is bit-identical to bakeProbes with the same arguments.

// One probe's adaptive accumulator after pass 2 (the sums bakeProbes keeps, in double).
// Bins of the direction guide's histogram a probe carries from pass to pass (bake/src/probe_guide.h).
inline constexpr int kBakeGuideBins = 128;

struct ProbeBakeState {
  double acc[kShCoeffCount][3] = {};  // sum over the estimated batches of the batch SH (W/(m^2 sr))
  int32_t batches = 0;                // batches of kBakeBatchSize paths taken
  int32_t estimated = 0;              // the last of them that acc, mean and m2 hold (all, or from the first
                                      // guided one under lit-patch sampling)
  double mean[6] = {}, m2[6] = {};    // Welford over those of the luminance of E at the six axis normals
  double achieved = -1.0;             // relative standard error reached against the floor
  // The direction guide learned from its batches after pass 1 (light per bin, rounded to float at the end of
  // each pass) and how many batches it holds: a later pass (the path budget's) guides from its first batch.
  std::array<float, kBakeGuideBins> guide{};
  int32_t guideBatches = 0;
  // With BakeOptions::litVoxel: the lit-patch histogram learned so far (lit-map voxel key, light; by key) and
  // the batches it holds.
  std::vector<std::pair<uint64_t, double>> patches;
  int32_t patchBatches = 0;
  uint64_t intersectRays = 0, occludedRays = 0;  // rays this probe's passes 1-2 traced (BakeStats)
};

// The lit map's voxel edge for `probes` (those `skip` does not name): cbrt(box volume / count).
double litMapVoxelEdge(const std::vector<glm::dvec3>& probes, const std::vector<uint8_t>* skip);

struct ShardBake {
  double floor = 0.0;                  // kBakeErrorFloor x the level's median pass-1 mean (all probes)
  std::vector<uint32_t> probes;        // probe indices, increasing within one shard
  std::vector<ProbeBakeState> states;  // one per entry of `probes`
};

// The paths a flat cap of options.maxSamplesPerProbe would have traced on the probes of `states`: each its paths
// to options.targetRelError as its error projects them, at most the cap (budget_shares.h, cappedSpend).
uint64_t flatCapPaths(const ShardBake& states, const BakeOptions& options);

// The probes of shard `index` of `count`: the probes sorted by (x, y, z, index) cut into `count` slabs of
// equal counts (within one), slab `index` marked 1. Deterministic; every probe in exactly one shard.
// std::invalid_argument unless 0 <= index < count.
std::vector<uint8_t> shardOwnership(const std::vector<glm::dvec3>& probes, int index, int count);

// A shard: pass 1 for every probe that is not skipped, pass 2 for those with own[i] != 0; returns their
// states (and the floor). Needs options.targetRelError > 0 (InputError otherwise), else as bakeProbes.
// Cost: pass 1 of every probe (replicated in every shard) plus pass 2 of its own.
ShardBake bakeProbesShard(const SceneTracer& tracer, const std::vector<glm::dvec3>& probes,
                          const BakeOptions& options, const std::vector<uint8_t>& own,
                          const std::vector<uint8_t>* skip = nullptr);

// The same in two rounds, so no shard traces another's pass 1 (docs/distributed.md): round 1 traces pass 1
// of the own probes only and returns their states (floor NaN); the floor is bakeErrorFloor over
// probeBakeMean of every shard's round-1 states; round 2 takes the shard's round-1 states (pass1.probes:
// exactly its own traced probes) and that floor (pass1.floor) and returns what bakeProbesShard would.
// InputError when pass1 holds another set of probes or a state not fresh from pass 1.
ShardBake bakeProbesShardPass1(const SceneTracer& tracer, const std::vector<glm::dvec3>& probes,
                               const BakeOptions& options, const std::vector<uint8_t>& own,
                               const std::vector<uint8_t>* skip = nullptr);
ShardBake bakeProbesShardPass2(const SceneTracer& tracer, const std::vector<glm::dvec3>& probes,
                               const BakeOptions& options, const std::vector<uint8_t>& own,
                               const ShardBake& pass1, const std::vector<uint8_t>* skip = nullptr);
// |mean luminance of E over the six axis normals| of a probe's state: what the floor's median is over.
double probeBakeMean(const ProbeBakeState& state);
// kBakeErrorFloor x the median (the element of rank size / 2) of `means`; 0 for none. bakeProbes's floor is
// this over every traced probe's pass-1 mean.
double bakeErrorFloor(std::vector<double> means);

// The merge: `merged` holds exactly one state for every probe that is not skipped (the shards' outputs
// concatenated, any order) and the shards' floor; runs pass 3 and the SH projection. The result and `stats`
// (but its seconds) equal bakeProbes(tracer, probes, options, stats, skip). InputError when a probe's state is
// missing, repeated, out of range, for a skipped probe, or outside the batch limits the options give.
std::vector<ShRgb> bakeProbesMerged(const SceneTracer& tracer, const std::vector<glm::dvec3>& probes,
                                    const BakeOptions& options, const ShardBake& merged,
                                    BakeStats* stats = nullptr, const std::vector<uint8_t>* skip = nullptr);

// ---- Trace farm (bake/src/bake_probes.cpp; protocol in docs/distributed.md#the-merge-farmed) ----
//
// The per-probe work of one step of the adaptive bake, as data: which probes, where each stops, their states
// before the step. A probe's batches draw from streams keyed by (seed, its index, batch), so the states after
// the step depend only on the batch, never on which process traced it or how the items were split.

// The steps of bakeProbes's adaptive passes.
enum class TraceStep : uint32_t {
  kPass1 = 1,  // batches up to `stop` (pass 1's minimum), unguided
  kPass2 =
      2,  // to the target or `stop`; lit patches where a flat cap of capBatches stops it above the target
  kBudget = 3,  // a path-budget round: to the target or `stop` (the probe's share)
};

struct TraceItem {
  uint32_t index = 0;        // the probe's index in its bake call (it keys the probe's random streams)
  glm::dvec3 position{0.0};  // finite
  int32_t stop = 0;          // batches the probe may reach in this step
  ProbeBakeState state;      // in: before the step; out: after it (achieved set by passes 2 and 3)
  uint64_t intersectRays = 0, occludedRays = 0;  // out: the rays this step traced for the probe
};

struct TraceBatch {
  TraceStep step = TraceStep::kPass1;
  BakeOptions options;     // the bake call's (threads, progress and farm play no part)
  double floor = 0.0;      // the error floor (passes 2 and 3)
  double litVoxel = 0.0;   // > 0: the lit map's voxel edge, for a step that guides with one; 0: no lit map
  int32_t capBatches = 0;  // pass 2's lit-patch rule: the flat cap in batches
  std::vector<TraceItem> items;
};

// Traces a batch's items in this process, each exactly as bakeProbes's step would; keeps the last lit map it
// built (scene, voxel, seed) for the next batch. `threads` 0 = all cores; never changes the result.
// InputError for a non-finite position, a stop outside [0, 16 x the cap] or an unknown step.
class TraceRunner {
 public:
  explicit TraceRunner(const SceneTracer& tracer);
  ~TraceRunner();
  void run(TraceBatch& batch, int threads);

 private:
  struct Cache;
  const SceneTracer& tracer_;
  std::unique_ptr<Cache> cache_;
};

// Sets coefficients 4..8 to exactly zero (an L1 probe, runtime/sh.h) when order == 1; no-op for order 2.
void truncateShOrder(std::vector<ShRgb>& sh, int order);

// The bake's direction set over the unit sphere: an n-point spherical Fibonacci set under a uniformly random
// rotation derived from `key` (the probe bake uses key = hash(seed, probe index)). Each direction is
// marginally uniform, so projectToSh of it is an unbiased randomised-QMC estimate.
std::vector<glm::vec3> bakeSphereDirections(int count, uint64_t key);

// Monte Carlo SH projection over the sphere: L_lm = 4 pi / N sum_k radiance[k] Y_lm(dirs[k]) (N =
// dirs.size(), accumulated in double). `radiance` has one entry per direction, W/(m^2 sr). Empty input gives
// zeros.
ShRgb projectToSh(const std::vector<glm::vec3>& dirs, const std::vector<glm::vec3>& radiance);

// Adds the exact projection of a delta of irradiance `irradiance` (W/m^2, perpendicular) arriving from unit
// direction `dir`: sh[i] += irradiance * Y_i(dir).
void addDeltaToSh(ShRgb& sh, const glm::vec3& dir, const glm::vec3& irradiance);

// For each point, true when it is inside geometry: more than `backFaceFraction` of `rays` uniformly
// distributed rays hit back faces of opaque surfaces (the Unity APV rule, 25 %; transmissive surfaces and
// cutout holes are seen through: a glass case encloses nothing). Deterministic.
std::vector<uint8_t> probesInsideGeometry(const SceneTracer& tracer, const std::vector<glm::dvec3>& points,
                                          int rays = 64, double backFaceFraction = 0.25, int threads = 0);

struct ReferenceIrradiance {
  glm::vec3 irradiance{0.0f};  // W/m^2, same light content as the probes (options.content)
  glm::vec3 stderror{0.0f};    // standard error of the estimate, per channel
  int samples = 0;
};

// Ground-truth irradiance at a surface point with unit normal `normal` (the point is offset along the
// normal by a small epsilon internally). `seed` makes it reproducible. Uses options.bounces/content.
// Each of `samples` samples: NEE of the emissive triangles (MIS, power heuristic) + exact punctual
// irradiance (I cos / r^2 x shadow-ray transmittance, sampled only for sun discs and light radii) + pi x the
// radiance of one cosine-sampled path. Rays start at point + normal x tracer.rayEpsilon(); punctual
// distances and cosines use the exact point. stderror = sample standard deviation / sqrt(samples) (per-sample variance).
// Single-threaded (callers parallelise over points). samples < 1 gives zeros with samples = 0. Throws
// InputError for a non-finite point, a zero or non-finite normal, or bounces < 0.
ReferenceIrradiance referenceIrradiance(const SceneTracer& tracer, const glm::dvec3& point,
                                        const glm::vec3& normal, int samples, uint64_t seed,
                                        const BakeOptions& options);

// referenceIrradiance run until the luminance estimate is precise enough: samples are drawn in batches of
// 32 (sample s uses the same random stream as in referenceIrradiance, so a run that stops at N samples
// equals referenceIrradiance(..., N, ...)) until, after at least `minSamples`, the standard error of the
// luminance (Rec. 709 weights) is at most relError x |mean luminance|, or `maxSamples` are reached.
// A point that receives no light stops at minSamples (zero mean, zero error). Throws InputError as
// referenceIrradiance, and for relError < 0 or maxSamples < 1.
ReferenceIrradiance referenceIrradianceToError(const SceneTracer& tracer, const glm::dvec3& point,
                                               const glm::vec3& normal, double relError, int maxSamples,
                                               uint64_t seed, const BakeOptions& options,
                                               int minSamples = 64);

// Reference irradiance at surface points, as data (a farm's other kind of work): per point its position,
// unit normal and seed; out, referenceIrradiance(tracer, position, normal, samples, seed, options).
struct ReferenceItem {
  glm::dvec3 position{0.0};
  glm::vec3 normal{0.0f, 0.0f, 1.0f};
  uint64_t seed = 0;
  ReferenceIrradiance result;  // out
};

struct ReferenceBatch {
  BakeOptions options;  // bounces and content are what the reference reads; farm and progress as above
  int32_t samples = 0;  // paths a point
  std::vector<ReferenceItem> items;
};

// Fills every item's result: on batch.options.farm when it takes reference points (BakeOptions::farm), else
// here, parallel over items (`threads` 0 = all cores, never changes the result; with options.progress, a
// progress line named `label`). Throws InputError as referenceIrradiance does.
void traceReferences(const SceneTracer& tracer, ReferenceBatch& batch, int threads,
                     const char* label = "references");

struct SurfacePoint {
  glm::dvec3 position{0.0};
  glm::vec3 normal{0.0f};  // unit, pointing into open space (the side a viewer could see)
  glm::vec3 albedo{0.0f};
  uint32_t triangle = 0;
};

// Up to `count` points where a viewer looks: for each of `cameras` in turn (round robin), a uniformly random
// position on its image plane (vertical field of view fovYDeg, width/height = `aspect`, the renderer's
// lookAt/perspective frame), the primary ray's first front-face hit (back faces are culled, as the
// renderer culls them) with its geometric normal. Misses (sky) are redrawn, at most 20 x count draws in all. Deterministic for a
// given seed. Empty when `cameras` is empty.
std::vector<SurfacePoint> sampleCameraPoints(const SceneTracer& tracer, const std::vector<Camera>& cameras,
                                             int count, uint64_t seed, float aspect = 16.0f / 9.0f);

// `count` random points on the scene's surfaces, area-weighted, each on a side that faces open space
// (points whose both sides are enclosed are skipped and redrawn). Deterministic for a given seed.
// Points in alpha-cutout holes are redrawn (there is no surface there); the side test counts opaque
// surfaces only. A side is open when at most 25 % of 32 uniform-hemisphere rays from the point (offset by
// tracer.rayEpsilon() along that side's normal) hit back faces or escape into the void: when the sky is
// black, any escaping ray (the level is an interior and the void is its outside); under a sky, a ray escaping
// below the horizon (direction y < 0: the underside of a ground plane, or a wall facing the void around a
// level, which no viewer on the ground sees).
// The front side wins when both are open.
// At most 20 x count draws: may return fewer than `count` points when most surface is enclosed.
std::vector<SurfacePoint> sampleSurfacePoints(const SceneTracer& tracer, int count, uint64_t seed);

// ---- Dilation (bake/src/dilate.cpp) ----

// Replaces the SH of every probe with invalid[i] != 0 by the SH of its nearest valid probe (Euclidean
// distance in double; ties: the lower index), as Unity's Adaptive Probe Volumes dilate probes that see
// mostly back faces. Used for shell probes outside a closed level (tetra/placement.h, placeShellProbes):
// they are tet vertices the per-tet occlusion hides from the level's surfaces, and when it does not, they
// repeat a nearby valid probe instead of the backs of walls. Exact nearest through a uniform grid searched
// in growing rings; O(probes) expected. Returns the number replaced (0 when no probe is valid: nothing to
// copy). Throws std::invalid_argument when the sizes differ.
// `source` (optional) gets, per probe, the index of the probe whose SH it now holds (itself when valid or
// when no probe is valid).
size_t dilateInvalidProbes(const std::vector<glm::dvec3>& positions, const std::vector<uint8_t>& invalid,
                           std::vector<ShRgb>& sh, std::vector<uint32_t>* source = nullptr);

// ---- Deringing (bake/src/dering.cpp) ----
//
// An SH L2 probe reconstructs irradiance E(n) = sum A_l L_lm Y_lm(n) (runtime/sh.h). Bright, small sources
// make that ring: E goes negative on the side facing away (-0.04 x the mean near 122 degrees for a single
// directional light). Deringing multiplies band l by a window factor w_l(s) with strength s in [0, 2]:
//   w_0 = 1 (the mean, L00, is never changed),  w_l(s) = (1 + cos(pi min(1, s l / 2))) / 2,
// a Hann window whose half-width shrinks from infinity (s = 0: no change) to 2 bands (s = 1: w_1 = 1/2,
// w_2 = 0, the cosine-convolved kernel (1 + cos)/4 >= 0, so any non-negative radiance gives non-negative E)
// and then to 1 band (s = 2: only L00 left).
// The window lifts E everywhere it shrinks a band: where a probe sees a bright region on one side and nothing
// on the other, its dark side gets a share of the bright side's light (a probe in the Cornell box's open front,
// facing out: 0 W/m^2 traced, -0.018 as projected, 0.108 windowed). kAuto instead takes, per channel, the
// nearest field (L2 over the sphere) that is non-negative with the same mean (nearestNonNegativeSh), which
// leaves the dark side near zero and the bright side nearly as projected.

enum class DeringMode {
  kNone,    // leave the SH bit-identical
  kAuto,    // per probe and channel, the nearest non-negative irradiance with L00 held (nearestNonNegativeSh)
  kWindow,  // per probe, the smallest window strength (on a 1/256 grid) that makes E non-negative
  kFixed,   // one window strength for every probe
};

struct DeringOptions {
  DeringMode mode = DeringMode::kAuto;
  double strength = 0.0;  // kFixed only, in [0, 2]
  int threads = 0;        // 0 = all cores; never changes the result
};

struct DeringStats {
  size_t probes = 0;
  size_t deringedProbes = 0;         // probes whose SH the deringing changed
  size_t unfixableProbes = 0;        // negative even at strength 2 / with bands 1-2 gone (a negative L00;
                                     // only imported SH)
  double maxStrength = 0.0;          // largest window strength applied (kAuto: only where float rounding left
                                     // the projection below the tolerance)
  float minIrradianceBefore = 0.0f;  // min over probes, normals and channels of E, W/m^2 (0 with no probes)
  float minIrradianceAfter = 0.0f;
};

inline constexpr double kDeringMaxStrength = 2.0;
inline constexpr int kDeringStepsPerUnit = 256;  // kAuto's strength grid: multiples of 1/256
// E counts as non-negative when its minimum is >= -kDeringTolerance x the probe's largest mean irradiance
// (pi Y00 L00 over channels): float rounding of a field whose exact minimum is 0 (a single delta at
// strength 1) must not push the strength up a step.
inline constexpr double kDeringTolerance = 1e-5;
// Normals of the dense check: a spherical Fibonacci set. E is a polynomial of degree 2 on the sphere, so on
// any great circle a trigonometric polynomial of degree 2 and |E''| <= M = sum_l l^2 max|band l| (Bernstein);
// with every direction within 0.05 rad of a check normal (measured covering radius of 4096 points: 0.0414
// rad) the true minimum is at most M 0.05^2 / 2 = 0.125 % of M below the best sample, and a local search
// (compass search in the tangent plane, from that sample's covering radius down to 1e-5 rad) finds it.
// Questions the bound already settles (a negative sample; a best sample above the margin) take no search,
// and a 512-normal coarse set (covering radius 0.12 rad) answers most of them before the dense one is
// needed.
inline constexpr int kDeringCheckNormals = 4096;

// The window factors {w_0, w_1, w_2} at strength s (clamped to [0, 2]).
std::array<double, 3> deringWindow(double strength);

// Multiplies band 1 by w_1(s) and band 2 by w_2(s) in place; L00 is untouched. s = 0 leaves sh bit-identical.
void applyDeringWindow(ShRgb& sh, double strength);

// Minimum over unit normals and the three channels of E(n) of `sh` windowed at `strength` (sh itself is not
// changed), W/m^2: dense check plus local refinement (kDeringCheckNormals).
float minShIrradiance(const ShRgb& sh, double strength = 0.0);

// kAuto for one probe: per channel whose E dips below -kDeringTolerance / 10 x the probe's largest mean
// irradiance, bands 1-2 replaced by those of the nearest field in the L2 norm over the sphere (with L00 held,
// the Euclidean distance of the coefficients A_l L_lm, Parseval) whose E is at least that bound at every normal
// (E's exact minimum over the sphere, bake/src/dering_nearest.cpp). A probe without band
// 2 (all nine of its band-2 coefficients zero) keeps none. Channels already non-negative keep every bit; a
// channel with a non-positive mean gets its constant (`fixable` false). Returns whether it changed sh.
// Never farther from the input than the smallest window (the window is one member of the same set).
bool nearestNonNegativeSh(ShRgb& sh, bool* fixable = nullptr);

// kWindow's choice for one probe: 0 when E >= -tolerance already; else the smallest multiple s of
// 1/kDeringStepsPerUnit such that windowed E >= -tolerance, found by bisection so that s - 1/256 is verified
// to fail; kDeringMaxStrength when even that fails (`fixable` set to false).
double autoDeringStrength(const ShRgb& sh, bool* fixable = nullptr);

// Derings every probe as options say and returns the statistics. kNone changes nothing (stats still
// computed). Throws InputError for a kFixed strength outside [0, 2] or non-finite. Deterministic for any
// thread count.
DeringStats deringProbes(std::vector<ShRgb>& sh, const DeringOptions& options);

}  // namespace tetraprobe
