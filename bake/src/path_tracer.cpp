// Unidirectional path tracer for Lambertian scenes with next-event estimation: emissive triangles sampled by
// power and combined with cosine-weighted BSDF sampling by the power heuristic; point, spot and directional
// lights by shadow rays; sky reached by BSDF-sampled rays; Russian roulette after the second bounce.
// Thin transmissive surfaces (scene.h's energy model): paths pass them by a random choice with probability
// `transmission`, shadow rays are weighted by the transmittance of their segment (SceneTracer).
// References: Veach 1997 (PhD thesis, ch. 9 "Multiple importance sampling"); Pharr, Jakob & Humphreys,
// "Physically Based Rendering", 4th ed., ch. 13 (path tracing, NEE, Russian roulette); Arvo & Kirk 1990
// ("Particle transport and image synthesis", Russian roulette).
//
// The sky is not light-sampled: its best general strategy here is the cosine lobe itself, so sky radiance
// is always picked up by BSDF rays with MIS weight 1. The sun (directional light) is never hit by BSDF rays;
// it is a light-sampled-only source (like a delta), so its NEE carries weight 1 too.
#include "path_tracer.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include <glm/geometric.hpp>

#include "sampling.h"
#include "tetraprobe/runtime/level.h"
#include "tracer_impl.h"

namespace tetraprobe::bake_detail {

namespace {

constexpr float kInfinity = std::numeric_limits<float>::infinity();

float smoothstep(float e0, float e1, float x) {
  if (e1 <= e0) return x >= e1 ? 1.0f : 0.0f;
  const float t = std::clamp((x - e0) / (e1 - e0), 0.0f, 1.0f);
  return t * t * (3.0f - 2.0f * t);
}

// Index of the first CDF entry >= u (u in [0, 1)).
size_t sampleCdf(const std::vector<double>& cdf, double u) {
  const auto it = std::upper_bound(cdf.begin(), cdf.end(), u);
  return std::min(size_t(it - cdf.begin()), cdf.size() - 1);
}

}  // namespace

float spotFactor(const Light& l, const glm::vec3& toPoint) {
  if (l.type != LightType::kSpot) return 1.0f;
  const float c = glm::dot(toPoint, l.direction);
  return smoothstep(std::cos(l.outerConeRad), std::cos(l.innerConeRad), c);
}

glm::vec3 punctualIrradiance(const SceneTracer& tracer, const glm::vec3& x, const glm::vec3& origin,
                             const glm::vec3& n, Rng& rng) {
  const Scene& scene = tracer.scene();
  const float eps = tracer.rayEpsilon();
  glm::vec3 e(0.0f);
  for (const Light& l : scene.lights) {
    if (l.type == LightType::kDirectional) {
      const glm::vec3 axis = -glm::normalize(l.direction);
      glm::vec3 w = axis;
      if (l.angularRadiusRad > 0.0f) {
        const float u1 = rng.uniform(), u2 = rng.uniform();
        w = uniformCone(axis, std::cos(l.angularRadiusRad), u1, u2);
      }
      const float c = glm::dot(n, w);
      if (c <= 0.0f) continue;
      const float through = tracer.transmittance(origin, w, 0.0f, kInfinity);
      if (through <= 0.0f) continue;
      e += through < 1.0f ? l.intensity * (c * through) : l.intensity * c;
      continue;
    }
    const glm::vec3 d = l.position - x;
    const float r2 = glm::dot(d, d);
    if (!(r2 > 0.0f)) continue;
    const glm::vec3 w = d / std::sqrt(r2);
    const float c = glm::dot(n, w);
    if (c <= 0.0f) continue;
    const float spot = spotFactor(l, -w);
    if (spot <= 0.0f) continue;
    glm::vec3 target = l.position;
    if (l.radius > 0.0f) {
      const float u1 = rng.uniform(), u2 = rng.uniform();
      target += uniformSphere(u1, u2) * l.radius;
    }
    const glm::vec3 s = target - origin;
    const float dist = glm::length(s);
    const float through = dist > eps ? tracer.transmittance(origin, s / dist, 0.0f, dist - eps) : 1.0f;
    if (through <= 0.0f) continue;
    e += through < 1.0f ? l.intensity * (spot * c / r2 * through) : l.intensity * (spot * c / r2);
  }
  return e;
}

bool sampleEmitter(const SceneTracer& tracer, const glm::vec3& origin, Rng& rng, EmitterSample& out) {
  const SceneTracer::Impl& impl = tracer.impl();
  if (impl.emissive.empty()) return false;
  const double uLight = rng.uniformDouble();
  const float u1 = rng.uniform(), u2 = rng.uniform();
  const uint32_t tri = impl.emissive[sampleCdf(impl.emissiveCdf, uLight)];
  const glm::vec2 b = uniformTriangle(u1, u2);
  if (tracer.isHole(tri, b.x, b.y)) return false;  // no emitter there (BSDF rays miss it too)
  const glm::vec3 d = impl.pointOn(tri, b.x, b.y) - origin;
  const float dist2 = glm::dot(d, d);
  if (!(dist2 > 0.0f)) return false;
  const float dist = std::sqrt(dist2);
  const glm::vec3 w = d / dist;
  const float cosLight = -glm::dot(impl.normals[tri], w);
  if (cosLight <= 0.0f) return false;  // emission is front-face only
  out.dir = w;
  out.dist = dist;
  out.pdf = impl.emissivePdfArea[tri] * dist2 / cosLight;
  out.radiance = impl.material(tri).emission;
  return true;
}

float emitterTransmittance(const SceneTracer& tracer, const glm::vec3& origin, const EmitterSample& s) {
  const float eps = tracer.rayEpsilon();
  return s.dist > eps ? tracer.transmittance(origin, s.dir, 0.0f, s.dist - eps) : 1.0f;
}

glm::vec3 emissiveIrradiance(const SceneTracer& tracer, const glm::vec3& origin, const glm::vec3& n,
                             Rng& rng) {
  EmitterSample s;
  if (!sampleEmitter(tracer, origin, rng, s)) return glm::vec3(0.0f);
  const float cosReceiver = glm::dot(n, s.dir);
  if (cosReceiver <= 0.0f) return glm::vec3(0.0f);
  const float through = emitterTransmittance(tracer, origin, s);
  if (through <= 0.0f) return glm::vec3(0.0f);
  const float weight = powerHeuristic(s.pdf, cosReceiver * kInvPi);
  const glm::vec3 e = s.radiance * (cosReceiver * weight / s.pdf);
  return through < 1.0f ? e * through : e;
}

glm::vec3 incidentRadiance(const SceneTracer& tracer, const glm::vec3& origin, const glm::vec3& dir,
                           float prevPdf, const TraceSettings& settings, Rng& rng) {
  const SceneTracer::Impl& impl = tracer.impl();
  const Scene& scene = *impl.scene;
  const float eps = impl.rayEpsilon;
  glm::vec3 radiance(0.0f), throughput(1.0f);
  glm::vec3 o = origin, d = dir;
  float tnear = 0.0f;  // > 0 after stepping through transmissive surfaces: the ray resumes past them
  for (int vertex = 0;; ++vertex) {
    const bool direct = vertex == 0;
    const Hit hit = tracer.intersect(o, d, tnear, kInfinity);
    if (!hit.hit) {
      if (!direct || (settings.content & kContentSky)) radiance += throughput * skyRadiance(scene, d);
      break;
    }
    const Material& m = impl.material(hit.triangle);
    if (hit.frontFace && maxComponent(m.emission) > 0.0f &&
        (!direct || (settings.content & kContentEmissive))) {
      float weight = 1.0f;
      if (prevPdf > 0.0f) {
        const float cosLight = -glm::dot(hit.geometricNormal, d);
        const float pdfLight = impl.emissivePdfArea[hit.triangle] * hit.t * hit.t / cosLight;
        weight = powerHeuristic(prevPdf, pdfLight);
      }
      radiance += throughput * m.emission * weight;
    }
    // A transmissive surface lets the ray through with probability `transmission` (unbiased for the thin-glass
    // model: the surface passes that fraction unchanged and reflects the rest with its albedo, so the
    // reflection below needs no extra weight). Passing is no bounce: same vertex, same origin (hit.t stays
    // the distance from the last scattering point, as the MIS weight above needs). Opaque surfaces draw no
    // random number, so scenes without transmission trace as before, bit for bit.
    if (m.transmission > 0.0f && (m.transmission >= 1.0f || rng.uniform() < m.transmission)) {
      tnear = std::max(hit.t + eps, std::nextafter(hit.t, kInfinity));
      --vertex;
      continue;
    }
    if (vertex >= settings.bounces) break;
    if (direct && !(settings.content & kContentIndirect)) break;
    if (maxComponent(m.albedo) <= 0.0f) break;
    if (vertex >= 2) {  // Russian roulette from the third bounce on
      const float survive = std::min(1.0f, maxComponent(throughput));
      if (rng.uniform() >= survive) break;
      throughput /= survive;
    }
    const glm::vec3 n = hit.frontFace ? hit.geometricNormal : -hit.geometricNormal;
    const glm::vec3 p = impl.pointOn(hit.triangle, hit.u, hit.v) + n * eps;
    const glm::vec3 irradiance =
        emissiveIrradiance(tracer, p, n, rng) + punctualIrradiance(tracer, p, p, n, rng);
    radiance += throughput * m.albedo * kInvPi * irradiance;
    const float u1 = rng.uniform(), u2 = rng.uniform();
    d = cosineHemisphere(n, u1, u2);
    prevPdf = std::max(glm::dot(n, d), 1e-12f) * kInvPi;
    o = p;
    tnear = 0.0f;
    throughput *= m.albedo;
  }
  return radiance;
}

}  // namespace tetraprobe::bake_detail
