// Reference (ground-truth) irradiance at a surface point: E = pi x mean incident radiance over a
// cosine-weighted hemisphere, with next-event estimation at the point itself for emissive triangles (MIS,
// power heuristic) and exact punctual irradiance. The standard error comes from the per-sample variance
// (Welford's running update). Used by the evaluation as the oracle the probes are compared against.
// References: Veach 1997 (MIS); Welford 1962 ("Note on a method for calculating corrected sums of squares").
#include <cmath>
#include <numbers>
#include <string>

#include <glm/geometric.hpp>

#include "path_tracer.h"
#include "rng.h"
#include "sampling.h"
#include "tetraprobe/bake/bake.h"
#include "tetraprobe/common/error.h"
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

}  // namespace

ReferenceIrradiance referenceIrradiance(const SceneTracer& tracer, const glm::dvec3& point,
                                        const glm::vec3& normal, int samples, uint64_t seed,
                                        const BakeOptions& options) {
  if (!finite(point) || !finite(glm::dvec3(normal)) || !(glm::length(normal) > 0.0f))
    throw InputError("reference: non-finite point or zero/non-finite normal");
  if (options.bounces < 0)
    throw InputError("reference: bounces must be >= 0 (got " + std::to_string(options.bounces) + ")");
  ReferenceIrradiance out;
  if (samples < 1) return out;
  DenormalScope denormals;
  const TraceSettings settings{options.bounces, options.content};
  const glm::vec3 n = glm::normalize(normal);
  const glm::vec3 x = glm::vec3(point);
  const glm::vec3 origin = x + n * tracer.rayEpsilon();
  glm::dvec3 mean(0.0), m2(0.0);
  for (int s = 0; s < samples; ++s) {
    Rng rng(streamKey(seed, uint64_t(s)));
    const glm::dvec3 e = glm::dvec3(irradianceSample(tracer, x, origin, n, settings, rng));
    const glm::dvec3 delta = e - mean;
    mean += delta / double(s + 1);
    m2 += delta * (e - mean);
  }
  out.samples = samples;
  out.irradiance = glm::vec3(mean);
  if (samples > 1) out.stderror = glm::vec3(glm::sqrt(m2 / double(samples - 1) / double(samples)));
  return out;
}

}  // namespace tetraprobe
