// Probe bake: per probe, incident radiance over the sphere by path tracing, projected onto real SH L2.
// Directions are a spherical Fibonacci set (Marques et al. 2013) under a per-probe uniformly random rotation
// (randomised QMC: unbiased, far less noise than independent directions); each direction has its own random
// stream keyed by (seed, probe, sample), so the result is bit-identical for any thread count.
// References: Ramamoorthi & Hanrahan 2001 ("An efficient representation for irradiance environment maps");
// Sloan 2008 ("Stupid spherical harmonics tricks") for the projection of deltas.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <functional>
#include <limits>
#include <memory>
#include <numbers>
#include <optional>
#include <stdexcept>
#include <string>

#include <glm/geometric.hpp>

#include "patch_guide.h"
#include "path_tracer.h"
#include "probe_bake.h"
#include "probe_guide.h"
#include "ray_tap.h"
#include "rng.h"
#include "sampling.h"
#include "tetraprobe/bake/bake.h"
#include "tetraprobe/bake/budget_shares.h"
#include "tetraprobe/common/error.h"
#include "tetraprobe/common/parallel.h"
#include "tetraprobe/common/progress.h"
#include "tracer_impl.h"

namespace tetraprobe {

using namespace bake_detail;

namespace {

constexpr float kInfinity = std::numeric_limits<float>::infinity();

glm::dmat3 probeRotation(uint64_t key) {
  Rng rng(key);
  const double u1 = rng.uniformDouble(), u2 = rng.uniformDouble(), u3 = rng.uniformDouble();
  return randomRotation(u1, u2, u3);
}

glm::vec3 sphereDirection(const glm::dmat3& rotation, int k, int n) {
  return glm::vec3(glm::normalize(rotation * sphericalFibonacci(k, n)));
}

// The unrotated n-point set, cached per thread (the same doubles sphericalFibonacci gives: saves a double
// sincos per path).
const std::vector<glm::dvec3>& fibonacciSet(int n) {
  thread_local std::vector<glm::dvec3>
      sets[2];  // a batch's (or bakeProbe's n); a guided batch's uniform half
  std::vector<glm::dvec3>& set = sets[n == kBakeBatchSize / 2 ? 1 : 0];
  if (set.size() != size_t(n)) {
    set.resize(size_t(n));
    for (int k = 0; k < n; ++k) set[size_t(k)] = sphericalFibonacci(k, n);
  }
  return set;
}

// Direct light from point, spot and directional lights at a probe, as exact SH projections of deltas.
void addPunctualSh(const SceneTracer& tracer, const glm::vec3& probe, ShRgb& sh) {
  const float eps = tracer.rayEpsilon();
  for (const Light& l : tracer.scene().lights) {
    if (l.type == LightType::kDirectional) {
      const glm::vec3 w = -glm::normalize(l.direction);
      const float through = tracer.transmittance(probe, w, 0.0f, kInfinity);
      if (through > 0.0f) addDeltaToSh(sh, w, through < 1.0f ? l.intensity * through : l.intensity);
      continue;
    }
    const glm::vec3 d = l.position - probe;
    const float r2 = glm::dot(d, d);
    if (!(r2 > 0.0f)) continue;
    const float dist = std::sqrt(r2);
    const glm::vec3 w = d / dist;
    const float spot = spotFactor(l, -w);
    if (spot <= 0.0f) continue;
    const float through = dist > eps ? tracer.transmittance(probe, w, 0.0f, dist - eps) : 1.0f;
    if (through <= 0.0f) continue;
    addDeltaToSh(sh, w, through < 1.0f ? l.intensity * (spot / r2 * through) : l.intensity * (spot / r2));
  }
}

// Emitter sampling at the probe. A small bright emitter seen directly from a probe is found by few of its
// sphere directions, so its light comes in as a few large samples (blotches between neighbouring probes).
// When the light content holds direct emission and the scene has emissive triangles, each set of N sphere
// directions is joined by N points drawn on the emitters by power, and both are weighted by the power
// heuristic (Veach 1997, ch. 9; equal counts, so the weights take the pdfs alone): a sphere ray that meets
// emission weights it by w(1 / 4 pi, p_light) (incidentRadiance's prevPdf), an emitter point by
// w(p_light, 1 / 4 pi). Unbiased either way; the variance of a small emitter's light drops by orders.
constexpr float kSpherePdf = float(0.25 * std::numbers::inv_pi);
constexpr uint64_t kEmitterSampleTag = 1ull << 61;

// The density the sphere directions of a batch are drawn with: uniform without a guide, else the even mixture
// of uniform and the guide (the emitter samples' MIS partner too).
float sphereDirectionPdf(const ProbeGuide* guide, const glm::vec3& d) {
  return guide ? 0.5f * kSpherePdf + 0.5f * guide->pdf(d) : kSpherePdf;
}

// acc += l x weight x Y(d): one sample's term of the SH projection's sum, in double.
void addProjected(double acc[kShCoeffCount][3], const glm::vec3& l, double weight, const glm::vec3& d) {
  const auto y = shBasis<double>(d.x, d.y, d.z);
  for (int i = 0; i < kShCoeffCount; ++i)
    for (int c = 0; c < 3; ++c) acc[i][c] += double(l[c]) * weight * y[size_t(i)];
}

bool samplesEmitters(const SceneTracer& tracer, const BakeOptions& options) {
  return (options.content & kContentEmissive) && !tracer.impl().emissive.empty();
}

// `count` emitter points for probe `index` (random streams keyed by (seed, probe, kEmitterSampleTag | first
// + k)), shadow-tested from the probe and MIS-weighted, added to acc in the units of the sphere sum (L Y /
// (4 pi p)): the caller's 4 pi / count scale then gives their share of the projection.
void addEmitterSamples(const SceneTracer& tracer, const glm::vec3& probe, size_t index,
                       const BakeOptions& options, uint64_t first, int count, double acc[kShCoeffCount][3],
                       const ProbeGuide* guide = nullptr) {
  for (int k = 0; k < count; ++k) {
    Rng rng(streamKey(options.seed, index, kEmitterSampleTag | (first + uint64_t(k))));
    EmitterSample e;
    if (!sampleEmitter(tracer, probe, rng, e)) continue;
    const float through = emitterTransmittance(tracer, probe, e);
    if (through <= 0.0f) continue;
    const double weight = double(through) * powerHeuristic(e.pdf, sphereDirectionPdf(guide, e.dir)) /
                          (double(e.pdf) * 4.0 * std::numbers::pi);
    addProjected(acc, e.radiance, weight, e.dir);
  }
}

// Adaptive sampling (BakeOptions::targetRelError): the running state of one probe.
struct AdaptiveProbe {
  double acc[kShCoeffCount][3] = {};  // sum over the estimated batches of the batch SH
  int batches = 0;    // batches traced (they key the random streams and count against the caps)
  int estimated = 0;  // the last `estimated` of them, which acc, mean and m2 hold (restartEstimate)
  double mean[6] = {}, m2[6] = {};            // Welford over those batches of Y(E(n)) at the six axis normals
  std::array<float, kBakeGuideBins> guide{};  // the direction guide's histogram at the end of the last pass
  int guideBatches = 0;                       // batches it holds
  std::vector<std::pair<uint64_t, double>> patches;  // the lit-patch histogram (with a fixed lit map)
  int patchBatches = 0;
};

constexpr uint64_t kBatchRotationTag = 1ull << 62;

// Y(E(n)) at the six axis normals of a batch SH: E(n) = sum_l A_l L_lm Y_lm(n) (runtime/sh.h), in double.
void axisLuminance(const double sh[kShCoeffCount][3], double out[6]) {
  static const glm::dvec3 axes[6] = {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}};
  for (int k = 0; k < 6; ++k) {
    const auto y = shBasis<double>(axes[k].x, axes[k].y, axes[k].z);
    double e[3] = {0, 0, 0};
    for (int i = 0; i < kShCoeffCount; ++i)
      for (int c = 0; c < 3; ++c) e[c] += shCosineLobe(i) * sh[i][c] * y[size_t(i)];
    out[k] = luminance(glm::dvec3(e[0], e[1], e[2]));
  }
}

constexpr uint64_t kGuideDirectionTag = 1ull << 60;

// Batches of adaptive sampling's pass 1: every probe's first samplesPerProbe paths, at least two (for an error
// estimate).
int passOneBatches(const BakeOptions& options) {
  return std::max(2, (options.samplesPerProbe + kBakeBatchSize - 1) / kBakeBatchSize);
}

// Batches of adaptive sampling's per-probe cap (maxSamplesPerProbe), at least pass 1's.
int capBatches(const BakeOptions& options) {
  return std::max(passOneBatches(options), options.maxSamplesPerProbe / kBakeBatchSize);
}

// A probe's state as the budget's shares see it.
template <class State>
BudgetProbe budgetProbe(const State& st, double error) {
  return {st.batches, st.estimated, error};
}

// A probe's guides while one pass adds its batches. The direction histogram (probe_guide.h) and the guide built
// from it go on from the probe's earlier passes (AdaptiveProbe::guide, rounded to float between passes, so a
// pass guides from its first batch wherever it runs: in the same process or in a sharded bake's merge, which
// reads it from the shard's part file). The lit-patch histogram goes on too where BakeOptions::litVoxel fixes
// the lit map for every call; else it is the pass's own (its voxels are those of the map the call builds for
// its probes, which differs between calls).
struct GuideSlot {
  GuideHistogram histogram;
  ProbeGuide guide;
  PatchHistogram patches;  // lit-patch sampling (BakeOptions::litPatches): the first hits' lit patches
  PatchGuide patchGuide;
  bool litPatches = false;  // this probe takes lit-patch sampling in this pass (needsLitPatches)
  int batches = 0;          // batches recorded in `histogram`, over every pass
  int patchBatches = 0;     // batches recorded in `patches`
  bool patchGuideBuilt = false;
};

static_assert(kGuideBins == kBakeGuideBins, "ProbeBakeState::guide holds the direction histogram");

// The slot a pass starts a probe with: the direction histogram its earlier passes learned, and its guide.
GuideSlot resumeGuide(const AdaptiveProbe& st) {
  GuideSlot slot;
  for (int k = 0; k < kGuideBins; ++k) slot.histogram.sum[size_t(k)] = double(st.guide[size_t(k)]);
  slot.batches = st.guideBatches;
  if (slot.batches >= kGuideLearnBatches) slot.guide = ProbeGuide(slot.histogram);
  for (const auto& [key, value] : st.patches) slot.patches.sum[key] = value;
  slot.patchBatches = st.patchBatches;
  return slot;
}

// What a pass leaves for the next: the direction histogram, rounded to float; with a fixed lit map
// (`carryPatches`), the lit-patch histogram by key.
void keepGuide(const GuideSlot& slot, AdaptiveProbe& st, bool carryPatches) {
  for (int k = 0; k < kGuideBins; ++k) st.guide[size_t(k)] = float(slot.histogram.sum[size_t(k)]);
  st.guideBatches = slot.batches;
  st.patches.clear();
  st.patchBatches = 0;
  if (!carryPatches) return;
  st.patches.assign(slot.patches.sum.begin(), slot.patches.sum.end());
  std::sort(st.patches.begin(), st.patches.end());
  st.patchBatches = slot.patchBatches;
}

// Whether a probe entering a pass with state st takes lit-patch sampling: only one that would stop at
// `capBatches` above the target at its present rate (batches x (error / target)^2 > capBatches), since its
// points and the bounces' points cost rays that a probe on its way to the target does not need. Its own
// state only, so the same wherever it is baked.
bool needsLitPatches(const AdaptiveProbe& st, double error, double target, int capBatches) {
  if (!(error > target)) return false;
  if (!std::isfinite(error)) return true;
  const double ratio = error / target;
  return double(st.batches) * ratio * ratio > double(capBatches);
}

constexpr uint64_t kPatchSampleTag = 1ull << 59;
// Lit-patch points a batch draws, against its kBakeBatchSize sphere directions.
constexpr int kPatchSamples = 32;

// The voxel edge of lit-patch sampling's map for a bake of `probes`: cbrt(box volume / probes), the box of
// the traced probes with each axis floored at 1e-3 of the largest (about the probe spacing); its cells are
// a quarter of that on an edge; 1 for a degenerate set.
double litVoxelEdge(const std::vector<glm::dvec3>& probes, const std::function<bool(size_t)>& skipped) {
  glm::dvec3 lo(std::numeric_limits<double>::infinity()), hi(-std::numeric_limits<double>::infinity());
  size_t count = 0;
  for (size_t i = 0; i < probes.size(); ++i) {
    if (skipped(i)) continue;
    lo = glm::min(lo, probes[i]);
    hi = glm::max(hi, probes[i]);
    ++count;
  }
  if (count == 0) return 1.0;
  const glm::dvec3 e = hi - lo;
  const double top = std::max({e.x, e.y, e.z});
  if (!(top > 0.0) || !std::isfinite(top)) return 1.0;
  const double f = 1e-3 * top;
  const double edge = std::cbrt(std::max(e.x, f) * std::max(e.y, f) * std::max(e.z, f) / double(count));
  return edge > 0.0 && std::isfinite(edge) ? edge : 1.0;
}

}  // namespace

double litMapVoxelEdge(const std::vector<glm::dvec3>& probes, const std::vector<uint8_t>* skip) {
  return litVoxelEdge(probes, [&](size_t i) { return skip != nullptr && (*skip)[i] != 0; });
}

namespace {

// Whether batch b of a probe takes part in guiding (recorded, and guided once kGuideLearnBatches are in):
// adaptive sampling asked for it and the first samplesPerProbe paths (pass 1, which every probe takes) are
// done, so pass 1 and a bake that stops there are the unguided bake's, bit for bit.
bool guidedBatch(const BakeOptions& options, int b) {
  return options.guide && options.targetRelError > 0.0 && b >= passOneBatches(options);
}

// A probe taking lit-patch sampling restarts its estimate at its first guided batch: the batches before it
// (pass 1 and the guides' learning batches, drawn without a guide) stay traced but leave the estimate, which
// from then on averages guided batches only. Those few unguided batches would otherwise hold most of the
// estimate's variance (on a room lit through its roof, such a probe's unguided batches vary by 60 %, its
// guided ones by 10 %). Unbiased: each batch is, and which batches count depends only on when the guide
// started, not on their values. (Other probes keep every batch, so levels without point, spot or sun lights
// bake as before.)
void restartEstimate(AdaptiveProbe& st) {
  for (auto& row : st.acc)
    for (double& v : row) v = 0.0;
  for (int k = 0; k < 6; ++k) st.mean[k] = st.m2[k] = 0.0;
  st.estimated = 0;
}

// Batch b's kPatchSamples lit-patch points for probe `index` (random streams keyed by (seed, probe,
// kPatchSampleTag | b x kPatchSamples + k)), each MIS-weighted against the batch's sphere directions (density
// `guide`'s mixture) and added to acc in the units of the sphere sum (L Y / (4 pi p) a direction;
// kBakeBatchSize / kPatchSamples of that a point); each lit point also goes into the probe's voxel histogram.
void addPatchPoints(const SceneTracer& tracer, const glm::vec3& probe, size_t index,
                    const BakeOptions& options, uint64_t b, const PatchGuide& patchGuide,
                    const LitMap& litMap, const ProbeGuide* guide, PatchHistogram& learned,
                    double acc[kShCoeffCount][3]) {
  for (int k = 0; k < kPatchSamples; ++k) {
    Rng rng(streamKey(options.seed, index, kPatchSampleTag | (b * kPatchSamples + uint64_t(k))));
    const double u1 = (double(k) + rng.uniformDouble()) / double(kPatchSamples);
    const double u2 = rng.uniformDouble();
    const float u3 = rng.uniform(), u4 = rng.uniform();
    const PatchPoint pt = patchGuide.sample(u1, u2, u3, u4);
    const glm::vec3 to = tracer.impl().pointOn(pt.triangle, pt.u, pt.v) - probe;
    const float dist = glm::length(to);
    if (!(dist > 0.0f) || !(pt.pdfArea > 0.0f)) continue;
    const glm::vec3 d = to / dist;
    const float cosY = std::abs(glm::dot(tracer.impl().normals[pt.triangle], d));
    if (!(cosY > 0.0f)) continue;
    const glm::vec3 l = patchPointRadiance(tracer, probe, pt.triangle, pt.u, pt.v, d, dist, rng);
    if (!(maxComponent(l) > 0.0f)) continue;
    const float pdf = solidAnglePdf(pt.pdfArea, dist, cosY);
    const float weight =
        powerHeuristic(float(kPatchSamples) * pdf, float(kBakeBatchSize) * sphereDirectionPdf(guide, d));
    addProjected(acc, l,
                 double(weight) * double(kBakeBatchSize) /
                     (double(kPatchSamples) * double(pdf) * 4.0 * std::numbers::pi),
                 d);
    learned.add(litMap.voxelAt(pt.triangle, pt.u, pt.v),
                double(luminance(l)) * weight / (double(kPatchSamples) * double(pdf)));
  }
}

void addBatch(const SceneTracer& tracer, const glm::vec3& probe, size_t index, const BakeOptions& options,
              const LitMap* litMap, AdaptiveProbe& st, GuideSlot* slot = nullptr) {
  const TraceSettings settings{options.bounces, options.content};
  const uint64_t b = uint64_t(st.batches);
  const glm::dmat3 rotation = probeRotation(streamKey(options.seed, index, kBatchRotationTag | b));
  const bool emitters = samplesEmitters(tracer, options);
  const ProbeGuide* guide = nullptr;
  const bool learn = slot && guidedBatch(options, st.batches);
  // Lit-patch sampling weighs the first hit's punctual light, which the path takes only with a bounce and
  // indirect light in the content.
  const bool patches = learn && litMap != nullptr && slot->litPatches;
  const PatchGuide* patchGuide = nullptr;
  if (learn && slot->batches >= kGuideLearnBatches) {
    if (slot->batches % kGuideLearnBatches == 0) slot->guide = ProbeGuide(slot->histogram);
    if (slot->guide.active()) guide = &slot->guide;
  }
  if (patches && slot->patchBatches >= kGuideLearnBatches) {
    if (slot->patchBatches % kGuideLearnBatches == 0 || !slot->patchGuideBuilt) {
      slot->patchGuide = PatchGuide(slot->patches, tracer, *litMap);
      slot->patchGuideBuilt = true;
    }
    if (slot->patchGuide.active()) patchGuide = &slot->patchGuide;
  }
  if (patches && (guide || patchGuide) && st.estimated == st.batches) restartEstimate(st);
  // Unguided: kBakeBatchSize uniform directions, density 1 / (4 pi). Guided: half uniform, half from the
  // guide; every direction weighted by the mixture's density (n_u / 4 pi + n_g p_g) / n, which also
  // stands for the sphere in the emitter samples' MIS.
  const int uniformCount = guide ? kBakeBatchSize / 2 : kBakeBatchSize;
  const std::vector<glm::dvec3>& fibonacci = fibonacciSet(uniformCount);
  double acc[kShCoeffCount][3] = {};
  for (int k = 0; k < kBakeBatchSize; ++k) {
    glm::vec3 d;
    if (k < uniformCount || guide == nullptr) {
      d = glm::vec3(glm::normalize(rotation * fibonacci[size_t(k)]));
    } else {
      Rng pick(streamKey(options.seed, index, kGuideDirectionTag | (b * kBakeBatchSize + uint64_t(k))));
      // Stratified over the guide's cumulative distribution: guided direction j of the batch in the j-th of
      // equal slices of it (each still drawn with density n_g p_g in its slice, so the sum is unbiased), as
      // the uniform half is stratified by its Fibonacci set.
      const double u1 =
          (double(k - uniformCount) + pick.uniformDouble()) / double(kBakeBatchSize - uniformCount);
      const double u2 = pick.uniformDouble(), u3 = pick.uniformDouble();
      d = guide->sample(u1, u2, u3);
    }
    const float pdf = sphereDirectionPdf(guide, d);
    Rng rng(streamKey(options.seed, index, b * kBakeBatchSize + uint64_t(k) + 1));
    FirstHit first;
    TraceSettings traced = settings;
    if (patches) {
      first.patches = patchGuide;
      first.sphereWeight = float(kBakeBatchSize) * pdf;
      first.patchWeight = float(kPatchSamples);
      first.bounces = options.litPatches == LitPatches::kBounces;
      traced.firstHit = &first;
    }
    const glm::vec3 l = incidentRadiance(tracer, probe, d, emitters ? pdf : 0.0f, traced, rng);
    const double w = guide ? double(kSpherePdf) / double(pdf) : 1.0;  // in units of a uniform sample
    if (learn) slot->histogram.add(d, luminance(glm::dvec3(l)) * w);
    if (patches && first.hit && maxComponent(first.radiance) > 0.0f)
      slot->patches.add(litMap->voxelAt(first.triangle, first.u, first.v),
                        double(luminance(first.radiance)) * first.weight / (double(kBakeBatchSize) * pdf));
    addProjected(acc, l, w, d);
  }
  if (emitters)
    addEmitterSamples(tracer, probe, index, options, b * kBakeBatchSize, kBakeBatchSize, acc, guide);
  if (patchGuide)
    addPatchPoints(tracer, probe, index, options, b, *patchGuide, *litMap, guide, slot->patches, acc);
  const double scale = 4.0 * std::numbers::pi / kBakeBatchSize;
  for (int i = 0; i < kShCoeffCount; ++i)
    for (int c = 0; c < 3; ++c) {
      acc[i][c] *= scale;
      st.acc[i][c] += acc[i][c];
    }
  if (learn) ++slot->batches;
  if (patches) ++slot->patchBatches;
  double q[6];
  axisLuminance(acc, q);
  ++st.batches;
  ++st.estimated;
  for (int k = 0; k < 6; ++k) {
    const double delta = q[k] - st.mean[k];
    st.mean[k] += delta / double(st.estimated);
    st.m2[k] += delta * (q[k] - st.mean[k]);
  }
}

// Mean over the axis normals of Y(E(n)).
double adaptiveMean(const AdaptiveProbe& st) {
  double m = 0.0;
  for (double v : st.mean) m += v;
  return m / 6.0;
}

// The achieved relative standard error (BakeOptions::targetRelError), against max(mean, floor).
double adaptiveRelError(const AdaptiveProbe& st, double floor) {
  if (st.estimated < 2) return std::numeric_limits<double>::infinity();
  double se = 0.0;
  for (int k = 0; k < 6; ++k)
    se = std::max(se, std::sqrt(st.m2[k] / double(st.estimated - 1) / st.estimated));
  const double denom = std::max(std::abs(adaptiveMean(st)), floor);
  return denom > 0.0 ? se / denom : (se > 0.0 ? std::numeric_limits<double>::infinity() : 0.0);
}

ShRgb adaptiveSh(const SceneTracer& tracer, const glm::vec3& probe, const BakeOptions& options,
                 const AdaptiveProbe& st) {
  ShRgb sh;
  for (int i = 0; i < kShCoeffCount; ++i)
    for (int c = 0; c < 3; ++c) sh.c[size_t(i)][c] = float(st.acc[i][c] / std::max(st.estimated, 1));
  if (options.content & kContentDirectPunctual) addPunctualSh(tracer, probe, sh);
  return sh;
}

// One probe's work in a step of the adaptive bake (TraceStep): what bakeProbesImpl's passes and TraceRunner
// both run, so a probe traced by a farm ends exactly as one traced here. `litMap` null: no lit patches.
// Returns the error it reached against `floor` (passes 2 and 3; -1 for pass 1).
double traceStep(const SceneTracer& tracer, const glm::dvec3& position, size_t index,
                 const BakeOptions& options, const LitMap* litMap, double floor, TraceStep step, int stop,
                 int capBatchesForPatches, AdaptiveProbe& st) {
  DenormalScope denormals;
  const glm::vec3 probe(position);
  if (step == TraceStep::kPass1) {
    while (st.batches < stop) addBatch(tracer, probe, index, options, nullptr, st);
    return -1.0;
  }
  GuideSlot guide = resumeGuide(st);
  const double before = adaptiveRelError(st, floor);
  // Pass 2: the probes the flat cap would stop above the target, whether pass 2 stops there or at
  // pass2MaxSamples. A budget round: a probe that restarted its estimate goes on with lit patches; one that
  // would start them here (and restart) only when its share is at least the batches it would leave out of its
  // estimate, so that a small share never leaves it an estimate of a batch or two.
  guide.litPatches =
      step == TraceStep::kPass2
          ? needsLitPatches(st, before, options.targetRelError, capBatchesForPatches)
          : st.estimated < st.batches || (stop - st.batches >= st.batches &&
                                          needsLitPatches(st, before, options.targetRelError, stop));
  while (st.batches < stop && !(adaptiveRelError(st, floor) <= options.targetRelError))
    addBatch(tracer, probe, index, options, litMap, st, &guide);
  keepGuide(guide, st, options.litVoxel > 0.0);
  return adaptiveRelError(st, floor);
}

// The lit map of lit-patch sampling for a bake call's options and voxel edge.
LitMap makeLitMap(const SceneTracer& tracer, double voxel, uint64_t seed, int threads) {
  return LitMap(tracer, voxel * voxel / 16.0, voxel, seed, threads);
}

}  // namespace

ShRgb bake_detail::bakeProbe(const SceneTracer& tracer, const glm::vec3& probe, size_t index,
                             const BakeOptions& options) {
  DenormalScope denormals;
  const TraceSettings settings{options.bounces, options.content};
  const int n = options.samplesPerProbe;
  const glm::dmat3 rotation = probeRotation(streamKey(options.seed, index));
  const std::vector<glm::dvec3>& fibonacci = fibonacciSet(n);
  const bool emitters = samplesEmitters(tracer, options);
  double acc[kShCoeffCount][3] = {};
  for (int k = 0; k < n; ++k) {
    const glm::vec3 d = glm::vec3(glm::normalize(rotation * fibonacci[size_t(k)]));
    Rng rng(streamKey(options.seed, index, uint64_t(k) + 1));
    const glm::vec3 l = incidentRadiance(tracer, probe, d, emitters ? kSpherePdf : 0.0f, settings, rng);
    addProjected(acc, l, 1.0, d);
  }
  if (emitters) addEmitterSamples(tracer, probe, index, options, 0, n, acc);
  ShRgb sh;
  const double scale = 4.0 * std::numbers::pi / n;
  for (int i = 0; i < kShCoeffCount; ++i)
    for (int c = 0; c < 3; ++c) sh.c[i][c] = float(acc[i][c] * scale);
  if (options.content & kContentDirectPunctual) addPunctualSh(tracer, probe, sh);
  return sh;
}

void bake_detail::validateBakeOptions(const BakeOptions& options) {
  if (options.samplesPerProbe < 1)
    throw InputError("bake: samplesPerProbe must be >= 1 (got " + std::to_string(options.samplesPerProbe) +
                     ")");
  if (options.bounces < 0)
    throw InputError("bake: bounces must be >= 0 (got " + std::to_string(options.bounces) + ")");
  if (options.shOrder != 1 && options.shOrder != 2)
    throw InputError("bake: SH order must be 1 or 2 (got " + std::to_string(options.shOrder) + ")");
  if (!(options.targetRelError >= 0.0) || !std::isfinite(options.targetRelError))
    throw InputError("bake: target relative error must be finite and >= 0 (got " +
                     std::to_string(options.targetRelError) + ")");
  if (options.targetRelError > 0.0 && options.maxSamplesPerProbe < options.samplesPerProbe)
    throw InputError("bake: maxSamplesPerProbe (" + std::to_string(options.maxSamplesPerProbe) +
                     ") is below samplesPerProbe (" + std::to_string(options.samplesPerProbe) + ")");
}

void truncateShOrder(std::vector<ShRgb>& sh, int order) {
  if (order != 1) return;
  for (ShRgb& p : sh)
    for (int i = 4; i < kShCoeffCount; ++i) p.c[size_t(i)] = glm::vec3(0.0f);
}

std::vector<glm::vec3> bakeSphereDirections(int count, uint64_t key) {
  std::vector<glm::vec3> dirs(size_t(std::max(count, 0)));
  const glm::dmat3 rotation = probeRotation(key);
  for (int k = 0; k < count; ++k) dirs[size_t(k)] = sphereDirection(rotation, k, count);
  return dirs;
}

ShRgb projectToSh(const std::vector<glm::vec3>& dirs, const std::vector<glm::vec3>& radiance) {
  ShRgb sh;
  if (dirs.empty()) return sh;
  double acc[kShCoeffCount][3] = {};
  for (size_t k = 0; k < dirs.size() && k < radiance.size(); ++k) {
    const glm::vec3 d = dirs[k];
    const auto y = shBasis<double>(d.x, d.y, d.z);
    for (int i = 0; i < kShCoeffCount; ++i)
      for (int c = 0; c < 3; ++c) acc[i][c] += double(radiance[k][c]) * y[i];
  }
  const double scale = 4.0 * std::numbers::pi / double(dirs.size());
  for (int i = 0; i < kShCoeffCount; ++i)
    for (int c = 0; c < 3; ++c) sh.c[i][c] = float(acc[i][c] * scale);
  return sh;
}

void addDeltaToSh(ShRgb& sh, const glm::vec3& dir, const glm::vec3& irradiance) {
  const auto y = shBasis<double>(dir.x, dir.y, dir.z);
  for (int i = 0; i < kShCoeffCount; ++i)
    for (int c = 0; c < 3; ++c) sh.c[i][c] = float(double(sh.c[i][c]) + double(irradiance[c]) * y[i]);
}

namespace {

// A sharded bake's role in bakeProbesImpl: a shard (passes 1-2 for the probes `own` names, states out), or
// the merge (every probe's state after pass 2 in, passes 3 and the SH out). Null: the whole bake.
struct ShardRole {
  const std::vector<uint8_t>* own = nullptr;  // shard: the probes it takes to pass 2
  ShardBake* out = nullptr;                   // shard: their states
  const ShardBake* resume = nullptr;          // merge: every traced probe's state
  bool pass1Only = false;                     // round 1: pass 1 of the own probes only, states out
  const ShardBake* pass1 = nullptr;           // round 2: the own probes' pass-1 states and the floor
};

// The running sums both records share (AdaptiveProbe <-> ProbeBakeState, either way): acc, batches, mean, m2.
template <class From, class To>
void copySums(const From& from, To& to) {
  for (int i = 0; i < kShCoeffCount; ++i)
    for (int c = 0; c < 3; ++c) to.acc[i][c] = from.acc[i][c];
  to.batches = from.batches;
  to.estimated = from.estimated;
  to.guide = from.guide;
  to.guideBatches = from.guideBatches;
  to.patches = from.patches;
  to.patchBatches = from.patchBatches;
  for (int k = 0; k < 6; ++k) {
    to.mean[k] = from.mean[k];
    to.m2[k] = from.m2[k];
  }
}

std::vector<ShRgb> bakeProbesImpl(const SceneTracer& tracer, const std::vector<glm::dvec3>& probes,
                                  const BakeOptions& options, BakeStats* stats,
                                  const std::vector<uint8_t>* skip, const ShardRole& role) {
  validateBakeOptions(options);
  const bool sharded = role.own != nullptr || role.resume != nullptr;
  const auto own = [&](size_t i) { return role.own == nullptr || (*role.own)[i] != 0; };
  if (sharded && !(options.targetRelError > 0.0))
    throw InputError("bake: a sharded bake needs adaptive sampling (a target error > 0)");
  if (role.own && role.own->size() != probes.size())
    throw std::invalid_argument("bakeProbesShard: ownership mask size differs from the probe count");
  if (skip && skip->size() != probes.size())
    throw std::invalid_argument("bakeProbes: skip mask size differs from the probe count");
  auto skipped = [&](size_t i) { return skip != nullptr && (*skip)[i] != 0; };
  // Progress counts the probes a pass traces (skipped ones cost nothing and would make the ETA wrong).
  auto traced = [&](bool ownOnly) {
    uint64_t n = 0;
    for (size_t i = 0; i < probes.size(); ++i) n += !skipped(i) && (!ownOnly || own(i));
    return n;
  };
  for (size_t i = 0; i < probes.size(); ++i)
    if (!std::isfinite(probes[i].x) || !std::isfinite(probes[i].y) || !std::isfinite(probes[i].z))
      throw InputError("bake: probe " + std::to_string(i) + " has a non-finite position");
  const auto t0 = std::chrono::steady_clock::now();
  std::vector<ShRgb> out(probes.size());
  // Per probe: sums independent of the threads (a shard always counts: its part file carries them).
  std::vector<RayTap> taps(stats || sharded ? probes.size() : 0);
  std::unique_ptr<Progress> progress;
  const bool adaptive = options.targetRelError > 0.0;
  std::vector<int> paths(probes.size(), options.samplesPerProbe);
  std::vector<double> achieved;
  uint64_t budgetPaths = 0;
  if (!adaptive) {
    if (options.progress) progress = std::make_unique<Progress>("bake", traced(false), "probes");
    parallelFor(probes.size(), options.threads, [&](size_t i) {
      if (skipped(i)) {
        paths[i] = 0;
        return;
      }
      if (stats) {
        RayTapScope scope(taps[i]);
        out[i] = bakeProbe(tracer, glm::vec3(probes[i]), i, options);
      } else {
        out[i] = bakeProbe(tracer, glm::vec3(probes[i]), i, options);
      }
      if (progress) progress->advance();
    });
  } else {
    const int minBatches = passOneBatches(options);
    const int maxBatches = capBatches(options);
    const int pass2Batches =
        options.pass2MaxSamples > 0
            ? std::clamp(options.pass2MaxSamples / kBakeBatchSize, minBatches, maxBatches)
            : maxBatches;
    std::vector<AdaptiveProbe> state(probes.size());
    auto run = [&](size_t i, auto&& body) {
      if (!taps.empty()) {
        RayTapScope scope(taps[i]);
        body();
      } else {
        body();
      }
    };
    // The lit map of lit-patch sampling, built on first use (a merge whose probes all reached their target
    // traces none); the same in every process of a sharded bake (a pure function of the scene, the probes
    // and the seed). A farmed step sends its voxel edge instead, and the map is built where it is traced.
    std::optional<LitMap> lit;
    const bool usesLitMap = options.guide && options.litPatches != LitPatches::kOff && options.bounces >= 1 &&
                            (options.content & kContentIndirect) && !tracer.scene().lights.empty();
    const bool farmed = options.farm != nullptr && options.farm->probes;
    double litVoxelUsed = 0.0;           // set (serially) before each pass that guides
    const LitMap* litMapUsed = nullptr;  // the same, when this process traces
    auto buildLitMap = [&] {
      if (usesLitMap && !(litVoxelUsed > 0.0))
        litVoxelUsed = options.litVoxel > 0.0 ? options.litVoxel : litVoxelEdge(probes, skipped);
      if (usesLitMap && !farmed && !lit)
        lit.emplace(makeLitMap(tracer, litVoxelUsed, options.seed, options.threads));
      if (lit) litMapUsed = &*lit;
    };
    double floor = 0.0;
    // One step for the probes `which` (each to stopOf(its index)): traced here, or handed to the farm as one
    // batch; either way each probe's state, error, rays and paths end the same.
    auto runStep = [&](TraceStep step, const std::vector<size_t>& which, auto&& stopOf, const char* label) {
      if (farmed) {
        TraceBatch batch;
        batch.step = step;
        batch.options = options;
        batch.options.farm = nullptr;
        batch.floor = floor;
        batch.litVoxel = step == TraceStep::kPass1 ? 0.0 : litVoxelUsed;
        batch.capBatches = maxBatches;
        batch.items.resize(which.size());
        for (size_t k = 0; k < which.size(); ++k) {
          TraceItem& item = batch.items[k];
          item.index = uint32_t(which[k]);
          item.position = probes[which[k]];
          item.stop = int32_t(stopOf(which[k]));
          copySums(state[which[k]], item.state);
          item.state.achieved = achieved[which[k]];
        }
        options.farm->probes(batch);
        if (batch.items.size() != which.size())
          throw std::runtime_error("bake: the trace farm returned another number of probes");
        for (size_t k = 0; k < which.size(); ++k) {
          const size_t i = which[k];
          const TraceItem& item = batch.items[k];
          if (item.index != i) throw std::runtime_error("bake: the trace farm returned probes out of order");
          copySums(item.state, state[i]);
          if (step != TraceStep::kPass1) achieved[i] = item.state.achieved;
          if (!taps.empty()) {
            taps[i].intersects += item.intersectRays;
            taps[i].occludeds += item.occludedRays;
          }
        }
        return;
      }
      if (options.progress) progress = std::make_unique<Progress>(label, which.size(), "probes");
      parallelFor(which.size(), options.threads, [&](size_t k) {
        const size_t i = which[k];
        run(i, [&] {
          const double reached = traceStep(tracer, probes[i], i, options, litMapUsed, floor, step,
                                           int(stopOf(i)), maxBatches, state[i]);
          if (step != TraceStep::kPass1) achieved[i] = reached;
        });
        if (progress) progress->advance();
      });
      if (progress) progress->finish();
    };
    achieved.assign(probes.size(), -1.0);
    if (role.resume) {
      // The merge: every traced probe's state after pass 2 comes from the shards, exactly once.
      const ShardBake& r = *role.resume;
      if (r.probes.size() != r.states.size())
        throw std::invalid_argument("bakeProbesMerged: probe and state counts differ");
      std::vector<uint8_t> seen(probes.size(), 0);
      for (size_t k = 0; k < r.probes.size(); ++k) {
        const uint32_t i = r.probes[k];
        if (i >= probes.size() || skipped(i) || seen[i])
          throw InputError("bake merge: shard state for probe " + std::to_string(i) +
                           (i >= probes.size() ? " is out of range"
                            : skipped(i)       ? " that is not traced"
                                               : " given twice"));
        const ProbeBakeState& s = r.states[k];
        if (s.batches < minBatches || s.batches > maxBatches || s.estimated < 0 || s.estimated > s.batches)
          throw InputError("bake merge: shard state for probe " + std::to_string(i) + " is inconsistent");
        seen[i] = 1;
        copySums(s, state[i]);
        achieved[i] = s.achieved;
        taps[i].intersects = s.intersectRays;
        taps[i].occludeds = s.occludedRays;
      }
      for (size_t i = 0; i < probes.size(); ++i) {
        if (!skipped(i) && !seen[i])
          throw InputError("bake merge: no shard holds probe " + std::to_string(i));
        paths[i] = skipped(i) ? 0 : state[i].batches * kBakeBatchSize;
      }
      floor = r.floor;
    } else {
      // Pass 1: every probe's minimum; then the floor from the level's median; pass 2: each probe to its target.
      // A shard runs pass 1 for every probe (the floor is the median over all of them), pass 2 for its own;
      // in two rounds, round 1 runs pass 1 of its own probes and round 2 takes those and the floor.
      if (role.pass1) {
        const ShardBake& r = *role.pass1;
        std::vector<uint8_t> seen(probes.size(), 0);
        for (size_t k = 0; k < r.probes.size() && k < r.states.size(); ++k) {
          const uint32_t i = r.probes[k];
          if (i >= probes.size() || skipped(i) || !own(i) || seen[i] || r.states[k].batches != minBatches ||
              r.states[k].estimated != minBatches)
            throw InputError("bake: round-1 state for probe " + std::to_string(i) +
                             " does not belong to this shard");
          seen[i] = 1;
          copySums(r.states[k], state[i]);
          taps[i].intersects = r.states[k].intersectRays;
          taps[i].occludeds = r.states[k].occludedRays;
        }
        for (size_t i = 0; i < probes.size(); ++i)
          if (!skipped(i) && own(i) && !seen[i])
            throw InputError("bake: no round-1 state for probe " + std::to_string(i));
        floor = r.floor;
      } else {
        std::vector<size_t> first;
        for (size_t i = 0; i < probes.size(); ++i)
          if (!skipped(i) && !(role.pass1Only && !own(i))) first.push_back(i);
        runStep(
            TraceStep::kPass1, first, [&](size_t) { return minBatches; }, "bake (pass 1)");
        std::vector<double> means;
        for (size_t i = 0; i < probes.size(); ++i)
          if (!skipped(i)) means.push_back(std::abs(adaptiveMean(state[i])));
        floor = bakeErrorFloor(std::move(means));
      }
      if (role.pass1Only) {
        floor = std::numeric_limits<double>::quiet_NaN();  // not known until every shard's pass 1 is
        std::fill(achieved.begin(), achieved.end(), -1.0);
      }
      if (!role.pass1Only) {
        buildLitMap();
        std::vector<size_t> second;
        for (size_t i = 0; i < probes.size(); ++i) {
          if (skipped(i) || !own(i))
            paths[i] = 0;
          else
            second.push_back(i);
        }
        runStep(
            TraceStep::kPass2, second, [&](size_t) { return pass2Batches; }, "bake (to target)");
        for (size_t i : second) paths[i] = state[i].batches * kBakeBatchSize;
      }
      if (role.out) {
        ShardBake& out = *role.out;
        out = ShardBake{};
        out.floor = floor;
        for (size_t i = 0; i < probes.size(); ++i) {
          if (skipped(i) || !own(i)) continue;
          ProbeBakeState s;
          copySums(state[i], s);
          s.achieved = achieved[i];
          s.intersectRays = taps[i].intersects;
          s.occludedRays = taps[i].occludeds;
          out.probes.push_back(uint32_t(i));
          out.states.push_back(s);
        }
        return {};
      }
    }
    // Pass 3 (BakeOptions::pathBudget): the unspent budget shared among the probes above the target
    // (budgetShares), in rounds, each round sharing what the last left.
    auto batchesUsed = [&] {
      uint64_t n = 0;
      for (size_t i = 0; i < probes.size(); ++i) n += skipped(i) ? 0 : uint64_t(state[i].batches);
      return n;
    };
    uint64_t used = batchesUsed();
    uint64_t budgetBatches = options.pathBudget / kBakeBatchSize;
    if (options.pass2MaxSamples > 0 && budgetBatches > 0) {
      std::vector<BudgetProbe> all;
      for (size_t i = 0; i < probes.size(); ++i)
        if (!skipped(i)) all.push_back(budgetProbe(state[i], achieved[i]));
      budgetBatches = std::max(budgetBatches, cappedSpend(all, options.targetRelError, maxBatches));
    }
    const int ceilingBatches = maxBatches * kBakeBudgetCapFactor;
    const uint64_t usedBefore = used;
    for (int round = 0; round < 8 && used < budgetBatches; ++round) {
      std::vector<size_t> open;
      for (size_t i = 0; i < probes.size(); ++i)
        if (!skipped(i) && achieved[i] > options.targetRelError && state[i].batches < ceilingBatches)
          open.push_back(i);
      if (open.empty()) break;
      std::vector<BudgetProbe> asked(open.size());
      for (size_t k = 0; k < open.size(); ++k) asked[k] = budgetProbe(state[open[k]], achieved[open[k]]);
      const std::vector<int> stops =
          budgetShares(asked, budgetBatches - used, options.targetRelError, ceilingBatches);
      if (stops.empty()) break;
      buildLitMap();
      std::vector<int> stopOf(probes.size(), 0);
      for (size_t k = 0; k < open.size(); ++k) stopOf[open[k]] = stops[k];
      runStep(
          TraceStep::kBudget, open, [&](size_t i) { return stopOf[i]; }, "bake (path budget)");
      for (size_t i : open) paths[i] = state[i].batches * kBakeBatchSize;
      used = batchesUsed();
    }
    budgetPaths = (used - usedBefore) * kBakeBatchSize;
    parallelFor(probes.size(), options.threads, [&](size_t i) {
      if (!skipped(i)) run(i, [&] { out[i] = adaptiveSh(tracer, glm::vec3(probes[i]), options, state[i]); });
    });
  }
  if (progress) progress->finish();
  truncateShOrder(out, options.shOrder);
  if (stats) {
    *stats = BakeStats{};
    stats->budgetPaths = budgetPaths;
    for (const RayTap& t : taps) {
      stats->intersectRays += t.intersects;
      stats->occludedRays += t.occludeds;
    }
    for (int n : paths) {
      stats->paths += uint64_t(n);
      stats->maxPathsPerProbe = std::max(stats->maxPathsPerProbe, n);
    }
    stats->probeRelError.assign(achieved.begin(), achieved.end());
    const RelErrorSummary summary = summarizeRelErrors(std::move(achieved), options.targetRelError);
    stats->meanRelError = summary.mean;
    stats->p95RelError = summary.p95;
    stats->maxRelError = summary.max;
    stats->probesAtCap = summary.above;
    stats->seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  }
  return out;
}

}  // namespace

std::vector<ShRgb> bakeProbes(const SceneTracer& tracer, const std::vector<glm::dvec3>& probes,
                              const BakeOptions& options, BakeStats* stats,
                              const std::vector<uint8_t>* skip) {
  return bakeProbesImpl(tracer, probes, options, stats, skip, ShardRole{});
}

ShardBake bakeProbesShard(const SceneTracer& tracer, const std::vector<glm::dvec3>& probes,
                          const BakeOptions& options, const std::vector<uint8_t>& own,
                          const std::vector<uint8_t>* skip) {
  ShardBake out;
  ShardRole role;
  role.own = &own;
  role.out = &out;
  bakeProbesImpl(tracer, probes, options, nullptr, skip, role);
  return out;
}

ShardBake bakeProbesShardPass1(const SceneTracer& tracer, const std::vector<glm::dvec3>& probes,
                               const BakeOptions& options, const std::vector<uint8_t>& own,
                               const std::vector<uint8_t>* skip) {
  ShardBake out;
  ShardRole role;
  role.own = &own;
  role.out = &out;
  role.pass1Only = true;
  bakeProbesImpl(tracer, probes, options, nullptr, skip, role);
  return out;
}

ShardBake bakeProbesShardPass2(const SceneTracer& tracer, const std::vector<glm::dvec3>& probes,
                               const BakeOptions& options, const std::vector<uint8_t>& own,
                               const ShardBake& pass1, const std::vector<uint8_t>* skip) {
  ShardBake out;
  ShardRole role;
  role.own = &own;
  role.out = &out;
  role.pass1 = &pass1;
  bakeProbesImpl(tracer, probes, options, nullptr, skip, role);
  return out;
}

RelErrorSummary summarizeRelErrors(std::vector<double> errors, double target) {
  errors.erase(std::remove(errors.begin(), errors.end(), -1.0), errors.end());
  RelErrorSummary out;
  if (errors.empty()) return out;
  std::sort(errors.begin(), errors.end());
  double sum = 0.0;
  for (double e : errors) {
    sum += std::isfinite(e) ? e : 0.0;
    out.above += e > target ? 1 : 0;
  }
  out.count = errors.size();
  out.mean = sum / double(errors.size());
  out.p95 = errors[std::min(errors.size() - 1, size_t(std::ceil(0.95 * double(errors.size()))) - 1)];
  out.max = errors.back();
  return out;
}

uint64_t flatCapPaths(const ShardBake& states, const BakeOptions& options) {
  std::vector<BudgetProbe> probes;
  for (const ProbeBakeState& s : states.states) probes.push_back(budgetProbe(s, s.achieved));
  return cappedSpend(probes, options.targetRelError, capBatches(options)) * uint64_t(kBakeBatchSize);
}

double probeBakeMean(const ProbeBakeState& state) {
  AdaptiveProbe a;
  copySums(state, a);
  return std::abs(adaptiveMean(a));
}

double bakeErrorFloor(std::vector<double> means) {
  double median = 0.0;
  if (!means.empty()) {
    std::nth_element(means.begin(), means.begin() + long(means.size() / 2), means.end());
    median = means[means.size() / 2];
  }
  return kBakeErrorFloor * median;
}

std::vector<ShRgb> bakeProbesMerged(const SceneTracer& tracer, const std::vector<glm::dvec3>& probes,
                                    const BakeOptions& options, const ShardBake& merged, BakeStats* stats,
                                    const std::vector<uint8_t>* skip) {
  ShardRole role;
  role.resume = &merged;
  return bakeProbesImpl(tracer, probes, options, stats, skip, role);
}

std::vector<uint8_t> shardOwnership(const std::vector<glm::dvec3>& probes, int index, int count) {
  if (count < 1 || index < 0 || index >= count)
    throw std::invalid_argument("shardOwnership: shard " + std::to_string(index) + " of " +
                                std::to_string(count));
  std::vector<uint32_t> order(probes.size());
  for (size_t i = 0; i < order.size(); ++i) order[i] = uint32_t(i);
  std::sort(order.begin(), order.end(), [&](uint32_t a, uint32_t b) {
    const glm::dvec3 &pa = probes[a], &pb = probes[b];
    if (pa.x != pb.x) return pa.x < pb.x;
    if (pa.y != pb.y) return pa.y < pb.y;
    if (pa.z != pb.z) return pa.z < pb.z;
    return a < b;
  });
  const size_t n = probes.size(), c = size_t(count), k = size_t(index);
  std::vector<uint8_t> own(n, 0);
  for (size_t r = k * n / c; r < (k + 1) * n / c; ++r) own[order[r]] = 1;
  return own;
}

struct TraceRunner::Cache {
  double voxel = 0.0;
  uint64_t seed = 0;
  std::optional<LitMap> lit;
};

TraceRunner::TraceRunner(const SceneTracer& tracer) : tracer_(tracer), cache_(std::make_unique<Cache>()) {}
TraceRunner::~TraceRunner() = default;

void TraceRunner::run(TraceBatch& batch, int threads) {
  const BakeOptions& options = batch.options;
  validateBakeOptions(options);
  if (batch.step != TraceStep::kPass1 && batch.step != TraceStep::kPass2 && batch.step != TraceStep::kBudget)
    throw InputError("trace batch: unknown step " + std::to_string(uint32_t(batch.step)));
  const int64_t ceiling = int64_t(capBatches(options)) * kBakeBudgetCapFactor;
  for (const TraceItem& item : batch.items) {
    if (!std::isfinite(item.position.x) || !std::isfinite(item.position.y) || !std::isfinite(item.position.z))
      throw InputError("trace batch: probe " + std::to_string(item.index) + " has a non-finite position");
    if (item.stop < 0 || item.stop > ceiling || item.state.batches < 0 || item.state.batches > ceiling)
      throw InputError("trace batch: probe " + std::to_string(item.index) +
                       " has a stop or state out of range");
  }
  const LitMap* litMap = nullptr;
  if (batch.litVoxel > 0.0) {
    if (!std::isfinite(batch.litVoxel)) throw InputError("trace batch: non-finite lit map voxel");
    Cache& c = *cache_;
    if (!c.lit || c.voxel != batch.litVoxel || c.seed != options.seed) {
      c.lit.reset();
      c.lit.emplace(makeLitMap(tracer_, batch.litVoxel, options.seed, threads));
      c.voxel = batch.litVoxel;
      c.seed = options.seed;
    }
    litMap = &*c.lit;
  }
  parallelFor(batch.items.size(), threads, [&](size_t k) {
    TraceItem& item = batch.items[k];
    AdaptiveProbe st;
    copySums(item.state, st);
    RayTap tap;
    double reached;
    {
      RayTapScope scope(tap);
      reached = traceStep(tracer_, item.position, item.index, options, litMap, batch.floor, batch.step,
                          item.stop, batch.capBatches, st);
    }
    copySums(st, item.state);
    if (batch.step != TraceStep::kPass1) item.state.achieved = reached;
    item.intersectRays = tap.intersects;
    item.occludedRays = tap.occludeds;
  });
}

}  // namespace tetraprobe
