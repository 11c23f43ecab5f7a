// Reference (ground-truth) irradiance at a surface point: E = pi x mean incident radiance over a
// cosine-weighted hemisphere, with next-event estimation at the point itself for emissive triangles (MIS,
// power heuristic) and exact punctual irradiance. The standard error comes from the per-sample variance
// (Welford's running update). Used by the evaluation as the oracle the probes are compared against.
// References: Veach 1997 (MIS); Welford 1962 ("Note on a method for calculating corrected sums of squares").
#include <algorithm>
#include <cmath>
#include <numbers>
#include <stdexcept>
#include <string>

#include <glm/geometric.hpp>

#include "path_tracer.h"
#include "rng.h"
#include "sampling.h"
#include "tetraprobe/bake/bake.h"
#include "tetraprobe/common/error.h"
#include "tetraprobe/common/parallel.h"
#include "tetraprobe/common/progress.h"
#include "tracer_impl.h"

namespace tetraprobe {

using namespace bake_detail;

namespace {

bool finite(const glm::dvec3& v) {
  return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z);
}

// One sample of the irradiance estimator.
glm::vec3 irradianceSample(const SceneTracer& tracer, const glm::vec3& x, const glm::vec3& origin,
                           const glm::vec3& n, const TraceSettings& settings, Rng& rng) {
  glm::vec3 e(0.0f);
  const bool emissiveNee = (settings.content & kContentEmissive) != 0;
  if (emissiveNee) e += emissiveIrradiance(tracer, origin, n, rng);
  if (settings.content & kContentDirectPunctual) e += punctualIrradiance(tracer, x, origin, n, rng);
  const float u1 = rng.uniform(), u2 = rng.uniform();
  const glm::vec3 d = cosineHemisphere(n, u1, u2);
  const float pdf = std::max(glm::dot(n, d), 1e-12f) * kInvPi;
  e += kPi * incidentRadiance(tracer, origin, d, emissiveNee ? pdf : 0.0f, settings, rng);
  return e;
}

// Running estimate over samples 0, 1, 2, ... of one point (Welford per channel and for the luminance).
class PointEstimator {
 public:
  PointEstimator(const SceneTracer& tracer, const glm::dvec3& point, const glm::vec3& normal, uint64_t seed,
                 const BakeOptions& options)
      : tracer_(tracer), seed_(seed), settings_{options.bounces, options.content} {
    if (!finite(point) || !finite(glm::dvec3(normal)) || !(glm::length(normal) > 0.0f))
      throw InputError("reference: non-finite point or zero/non-finite normal");
    if (options.bounces < 0)
      throw InputError("reference: bounces must be >= 0 (got " + std::to_string(options.bounces) + ")");
    n_ = glm::normalize(normal);
    x_ = glm::vec3(point);
    origin_ = x_ + n_ * tracer.rayEpsilon();
  }

  void add(int count) {
    for (int k = 0; k < count; ++k) {
      Rng rng(streamKey(seed_, uint64_t(samples_)));
      const glm::vec3 ef = irradianceSample(tracer_, x_, origin_, n_, settings_, rng);
      const glm::dvec3 e = glm::dvec3(ef);
      ++samples_;
      const glm::dvec3 delta = e - mean_;
      mean_ += delta / double(samples_);
      m2_ += delta * (e - mean_);
      const double l = double(luminance(ef));
      const double dl = l - lumMean_;
      lumMean_ += dl / double(samples_);
      lumM2_ += dl * (l - lumMean_);
    }
  }

  int samples() const { return samples_; }
  double lumMean() const { return lumMean_; }
  double lumStderr() const {
    return samples_ > 1 ? std::sqrt(lumM2_ / double(samples_ - 1) / double(samples_)) : 0.0;
  }

  ReferenceIrradiance result() const {
    ReferenceIrradiance out;
    out.samples = samples_;
    out.irradiance = glm::vec3(mean_);
    if (samples_ > 1) out.stderror = glm::vec3(glm::sqrt(m2_ / double(samples_ - 1) / double(samples_)));
    return out;
  }

 private:
  const SceneTracer& tracer_;
  uint64_t seed_;
  TraceSettings settings_;
  glm::vec3 n_{0.0f}, x_{0.0f}, origin_{0.0f};
  int samples_ = 0;
  glm::dvec3 mean_{0.0}, m2_{0.0};
  double lumMean_ = 0.0, lumM2_ = 0.0;
};

}  // namespace

ReferenceIrradiance referenceIrradiance(const SceneTracer& tracer, const glm::dvec3& point,
                                        const glm::vec3& normal, int samples, uint64_t seed,
                                        const BakeOptions& options) {
  PointEstimator est(tracer, point, normal, seed, options);
  if (samples < 1) return ReferenceIrradiance{};
  DenormalScope denormals;
  est.add(samples);
  return est.result();
}

ReferenceIrradiance referenceIrradianceToError(const SceneTracer& tracer, const glm::dvec3& point,
                                               const glm::vec3& normal, double relError, int maxSamples,
                                               uint64_t seed, const BakeOptions& options, int minSamples) {
  if (!(relError >= 0.0) || !std::isfinite(relError))
    throw InputError("reference: relative error must be finite and >= 0 (got " + std::to_string(relError) +
                     ")");
  if (maxSamples < 1)
    throw InputError("reference: maxSamples must be >= 1 (got " + std::to_string(maxSamples) + ")");
  PointEstimator est(tracer, point, normal, seed, options);
  DenormalScope denormals;
  constexpr int kBatch = 32;
  const int first = std::clamp(minSamples, 1, maxSamples);
  est.add(first);
  while (est.samples() < maxSamples && !(est.lumStderr() <= relError * std::abs(est.lumMean())))
    est.add(std::min(kBatch, maxSamples - est.samples()));
  return est.result();
}

void traceReferences(const SceneTracer& tracer, ReferenceBatch& batch, int threads, const char* label) {
  if (batch.options.farm && batch.options.farm->references) {
    const size_t count = batch.items.size();
    const TraceFarm& farm = *batch.options.farm;
    batch.options.farm = nullptr;  // where it is traced, it is traced there
    farm.references(batch);
    if (batch.items.size() != count)
      throw std::runtime_error("references: the trace farm returned another number of points");
    return;
  }
  Progress progress(label, batch.items.size(), "points", batch.options.progress);
  parallelFor(batch.items.size(), threads, [&](size_t i) {
    ReferenceItem& item = batch.items[i];
    item.result =
        referenceIrradiance(tracer, item.position, item.normal, batch.samples, item.seed, batch.options);
    progress.advance();
  });
}

}  // namespace tetraprobe
