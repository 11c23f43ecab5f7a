// Accuracy evaluation: compares probe lookups with path-traced ground truth at random surface points and
// reports error against run time and memory. Build side (uses the Embree reference oracle).
//
// Points no path leaves: a point whose reference is exactly 0 in every channel (every path and every NEE
// sample returned 0: a closed cavity, the inside of a wall). Such points have no scale to be relative to;
// they are left out of every per-point mean below and reported apart (EvalReport::closedPoints and each
// method's mean answer there, MethodResult::closedMean).
//
// Error measures over the other points ("open" points; per point p, channel c, lookup x, reference r,
// irradiance in W/m^2), with the level-relative floor f = kRelFloorFraction x mean over open points of
// luminance(r) (EvalReport::relFloor; 5 % of the level's mean brightness; 0.01 W/m^2 when no point is open
// or none is lit):
//   relmse         = mean over p,c of (x - r)^2 / max(r, f)^2
//   rel error(p)   = mean over c of |x - r| / max(r, f)
//   mean_rel_error = mean over p of rel error(p);  p95_rel_error = its 95th percentile
//   leak           = mean over p of max(0, lum(x) - lum(r)) / max(lum(r), 0.01)   (light that should not be
//   there)
//   leak_indirect  = the same mean over the points lit only indirectly (direct light below 1 % of r: the
//   surfaces that see the light only through a door, where a leak shows)
//   gross_error    = fraction of points with lum(x) > 2 lum(r) or lum(x) < lum(r) / 2 (off by more than 2x
//   either way), luminances floored at 0.01 W/m^2 so two near-black values agree
//   dark_holes     = fraction of points with lum(x) < 0.25 lum(r) (the same floor): black and dim polygons
//   fallback       = fraction of the open points where the method's answer uses the all-occluded fallback
//   (ShadeRecord::fallback > 0); n/a (< 0) for a method without one. The points no path leaves that fall
//   back are counted apart (closedFallbackPoints): no viewer sees their answer
// The former definition, kept for comparison (the *AbsFloor fields, over all points, closed ones included):
//   relmse = mean over p,c of (x - r)^2 / (r^2 + 0.01), rel error(p) = mean over c of |x - r| / sqrt(r^2 +
//   0.01). Its fixed 0.01 W/m^2 floor lets one closed point with an answer of 27.9 W/m^2 add 279 / n to
//   mean_rel; the measures above leave such points out and scale the floor with the level's brightness.
#pragma once

#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include <glm/vec3.hpp>

#include "tetraprobe/bake/bake.h"
#include "tetraprobe/eval/grid_volume.h"
#include "tetraprobe/runtime/level.h"
#include "tetraprobe/runtime/occlusion.h"
#include "tetraprobe/runtime/query.h"
#include "tetraprobe/scene/scene.h"

namespace tetraprobe {

// A point is "lit only indirectly" when less than this fraction of its reference comes directly.
inline constexpr double kIndirectOnlyFraction = 0.01;

// The relative errors' floor as a fraction of the open points' mean reference luminance (header comment).
inline constexpr double kRelFloorFraction = 0.05;

// Where the points are drawn.
enum class EvalSampling {
  kArea,     // area-uniform on the surfaces, each on its open side (sampleSurfacePoints)
  kCameras,  // where the scene's cameras look (sampleCameraPoints): the surfaces a viewer sees
};

struct EvalOptions {
  int points = 512;                          // surface points
  int samplesPerPoint = 4096;                // reference paths per point
  int referenceBounces = kUnboundedBounces;  // reference depth: unbounded (Russian roulette only, unbiased)
  EvalSampling sampling = EvalSampling::kArea;
  std::vector<Camera> cameras;  // kCameras: the views to draw points from (must not be empty)
  uint64_t seed = 0x5eed0e7a1ull;
  int threads = 0;
  bool progress = true;
};

// One part of a method's run-time data, bytes.
struct ByteSection {
  std::string name;
  uint64_t bytes = 0;
};

struct MethodResult {
  std::string name;
  double relmse = 0.0;
  double meanRelError = 0.0;
  double p95RelError = 0.0;
  double leak = 0.0;
  double leakIndirect = 0.0;  // leak over the points lit only indirectly (EvalPoint::indirectOnly)
  double grossError = 0.0;    // fraction of points off by more than 2x either way (luminance)
  double darkHoles = 0.0;     // fraction of points below 0.25x the reference (luminance)
  double fallback = -1.0;  // fraction of the open points where the answer falls back; < 0: n/a (no fallback)
  size_t closedFallbackPoints = 0;  // points no path leaves where the answer falls back (not in `fallback`)
  // The former definition (fixed floor sqrt(r^2 + 0.01), over all points, closed ones included).
  double relmseAbsFloor = 0.0, meanRelAbsFloor = 0.0, p95RelAbsFloor = 0.0;
  glm::vec3 closedMean{0.0f};  // mean answer over the points no path leaves, W/m^2 (0 when there are none)
  double cpuNsPerQuery = 0.0;  // single thread, fastest of repeated timed passes over the points
  // timeLookup (below), filled by the caller: wall time per query of a pass over all timing points on
  // `threads` threads, median over the passes; in a camera's pixel order and in random order. 0 = not timed.
  double cpuNsCoherent = 0.0, cpuNsRandom = 0.0;
  int threads = 0;
  double gpuMs = -1.0;  // full-screen lookup pass, ms (the caller's; < 0 = not measured)
  uint64_t bytes = 0;   // data the method's lookup touches at run time (sum of `sections`)
  std::vector<ByteSection> sections;
  uint64_t probes = 0;            // probes or grid nodes (for bytes per probe)
  std::vector<glm::vec3> values;  // per-point lookups (same order as EvalReport::points)
};

struct EvalPoint {
  SurfacePoint surface;
  ReferenceIrradiance reference;
  glm::vec3 direct{0.0f};     // direct part of the reference (0 bounces: emitters and sky seen directly)
  bool indirectOnly = false;  // luminance(direct) < kIndirectOnlyFraction x luminance(reference)
};

// Whether no path leaves the point: its reference is exactly 0 in every channel (see the header comment;
// the estimator's samples are never negative, so a zero mean means every sample was 0).
bool noPathLeaves(const EvalPoint& point);
bool noPathLeaves(const ReferenceIrradiance& reference);  // the same rule for a reference alone

struct EvalReport {
  EvalSampling sampling = EvalSampling::kArea;
  int samplesPerPoint = 0;
  int referenceBounces = 0;
  double meanRelStderr = 0.0;
  size_t indirectOnlyPoints = 0;  // points lit only indirectly (EvalPoint::indirectOnly)
  size_t closedPoints = 0;        // points no path leaves (noPathLeaves), set by scoreMethod
  double relFloor = 0.0;          // f of the header, W/m^2, set by scoreMethod
  double referenceSeconds = 0.0;
  std::vector<EvalPoint> points;
  std::vector<MethodResult> methods;
};

// A lookup method under test: irradiance at (world position, unit normal).
struct LookupMethod {
  std::string name;
  uint64_t bytes = 0;                 // sum of `sections` when they are given
  std::vector<ByteSection> sections;  // optional breakdown of `bytes`
  uint64_t probes = 0;                // probes or grid nodes
  std::function<glm::vec3(const glm::dvec3&, const glm::vec3&)> lookup;
  // Optional: out[i] = lookup(world[i], normal[i]) for i < count, on the calling thread, the way an engine
  // would call the method for consecutive pixels (the tet lookup passes each query's tet to the next).
  // Timing uses it when set.
  std::function<void(const glm::dvec3* world, const glm::vec3* normal, glm::vec3* out, size_t count)> batch;
  // Optional: the all-occluded fallback's share in lookup's answer at (world, normal), in [0, 1]
  // (ShadeRecord::fallback of the one shading function, runtime/shade.h). Unset: the method has none (n/a).
  std::function<float(const glm::dvec3& world, const glm::vec3& normal)> fallback;
};

// What the tet lookup (ProbeQuery::irradiance and shaders/tetraprobe.glsl) reads, section by section, in the
// GPU layout: probe positions (12 bytes each), SH (56, half precision as uploaded), tets (packed: gpuTetBytes,
// gpu_tets.h), the cell grid's hash slots and start bricks (startBricksBytes, start_bricks.h: the GPU's
// start; the CPU descends the cell grid's BSP instead), outer cells (48: GpuOuterCell, normals as
// octahedral codes), the coarse start grid (4 bytes a cell) and, when `occlusion`, the level's occlusion data as the GPU packs it (gpuOcclusionBytes,
// gpu_layout.h). The query's structures are counted (those the level stores, or those it built on load).
std::vector<ByteSection> tetLookupBytes(const ProbeQuery& query, bool occlusion);
uint64_t totalBytes(const std::vector<ByteSection>& sections);

// Points to time lookups at: positions and unit normals in the order they are queried.
struct TimingPoints {
  std::vector<glm::dvec3> position;  // world metres
  std::vector<glm::vec3> normal;
  std::string order;  // how they are ordered, for the report ("pixels of camera NAME WxH", "random")
};

// The hit pixels of `camera`'s view at width x height (traceReferenceGBuffer: the renderer's camera), in
// pixel order (row by row): the order a full-screen pass queries. Normals face the camera.
TimingPoints cameraTimingPoints(const SceneTracer& tracer, const Camera& camera, int width, int height,
                                int threads = 0);
// The report's points along a Morton (Z-order) curve over their bounds: a coherent order for scenes
// without cameras.
TimingPoints mortonTimingPoints(const EvalReport& report);
// The same points in a random order (Fisher-Yates with `seed`).
TimingPoints shuffledTimingPoints(const TimingPoints& points, uint64_t seed);

// Wall time per query, ns: `runs` passes over all `points` (each of `threads` threads takes a contiguous
// share, through method.batch when set), the median pass divided by the number of points (so with T
// threads it is the throughput cost, about 1/T of one thread's latency). One untimed warm-up pass first.
// 0 for no points.
double timeLookup(const LookupMethod& method, const TimingPoints& points, int threads, int runs = 7);

// "area" or "cameras".
const char* evalSamplingName(EvalSampling sampling);

// Draws the points (options.sampling) and their references (content = the level's content) once.
// meanRelStderr = mean over points of stderror / sqrt(r^2 + 0.01), luminance. Throws InputError for
// kCameras without cameras.
EvalReport computeReference(const SceneTracer& tracer, uint32_t content, const EvalOptions& options);

// One point's reference as `eval --points-out` wrote it (to score new levels without re-tracing).
struct StoredReference {
  glm::dvec3 position{0.0};
  glm::vec3 normal{0.0f}, irradiance{0.0f}, stderror{0.0f}, direct{0.0f};
};

// As computeReference, but the references come from `stored` (the rows of one point set, in order) instead
// of being traced: the points are drawn again with options' seed and sampling, and each must match its row
// (position within 1e-4 m + 1e-6 relative, normal within 1e-4: the CSV keeps 7 digits), so a file from
// another scene, seed, point count or sampling is refused with InputError naming the first mismatch.
// samplesPerPoint is reported as given (the caller states the count the file was traced with).
EvalReport reuseReference(const SceneTracer& tracer, const EvalOptions& options,
                          const std::vector<StoredReference>& stored);

// Scores one method against the report's references and appends it to report.methods (name, bytes,
// sections, probes, the error measures of the header, fallback, closedMean and cpuNsPerQuery; the other
// timings stay 0). Sets report.closedPoints and report.relFloor (from the points alone: the same for every
// method).
void scoreMethod(EvalReport& report, const LookupMethod& method);

// The standard methods for a level: `tet` (ProbeQuery, with the level's stored occlusion when it has some),
// `tet (no occlusion)` (only for a level storing occlusion: ProbeQuery with it disabled) and `nearest`
// (nearest probe's SH). The tet methods report their fallback (ProbeQuery::explain); `nearest` has none. Bytes: tetLookupBytes for the tet methods; positions, SH and the bucket grid for
// `nearest`.
std::vector<LookupMethod> standardMethods(const Level& level);

// `name` (e.g. "grid (equal bytes)"): the grid's trilinear lookup (grid_volume.h); bytes = grid->bytes()
// (header + nodes), probes = its nodes.
LookupMethod gridMethod(std::shared_ptr<const GridVolume> grid, const std::string& name);

// Per point of `report`, the share of the all-occluded fallback in the `tet` answer (applyOcclusion's
// `fallback`, occlusion.h): 0 where the point sees some of its tet's probes, 1 where it sees none. All zero for
// a level without occlusion. For diagnosing dark polygons.
std::vector<float> fallbackShares(const Level& level, const EvalReport& report);

// `tet+occlusion`: the tet lookup with per-tet occlusion data (runtime/occlusion.h) dropping occluded probes,
// with its fallback reported. Points outside the tets (outer cells, empty level) take the plain tet answer.
LookupMethod occlusionMethod(const Level& level, std::shared_ptr<const LevelOcclusion> occlusion);

}  // namespace tetraprobe
