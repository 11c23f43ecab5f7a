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

namespace {

// One light's term of punctualIrradiance (the same random numbers, in the same order).
glm::vec3 lightIrradiance(const SceneTracer& tracer, const Light& l, const glm::vec3& x,
                          const glm::vec3& origin, const glm::vec3& n, Rng& rng) {
  const float eps = tracer.rayEpsilon();
  if (l.type == LightType::kDirectional) {
    const glm::vec3 axis = -glm::normalize(l.direction);
    glm::vec3 w = axis;
    if (l.angularRadiusRad > 0.0f) {
      const float u1 = rng.uniform(), u2 = rng.uniform();
      w = uniformCone(axis, std::cos(l.angularRadiusRad), u1, u2);
    }
    const float c = glm::dot(n, w);
    if (c <= 0.0f) return glm::vec3(0.0f);
    const float through = tracer.transmittance(origin, w, 0.0f, kInfinity);
    if (through <= 0.0f) return glm::vec3(0.0f);
    return through < 1.0f ? l.intensity * (c * through) : l.intensity * c;
  }
  const glm::vec3 d = l.position - x;
  const float r2 = glm::dot(d, d);
  if (!(r2 > 0.0f)) return glm::vec3(0.0f);
  const glm::vec3 w = d / std::sqrt(r2);
  const float c = glm::dot(n, w);
  if (c <= 0.0f) return glm::vec3(0.0f);
  const float spot = spotFactor(l, -w);
  if (spot <= 0.0f) return glm::vec3(0.0f);
  glm::vec3 target = l.position;
  if (l.radius > 0.0f) {
    const float u1 = rng.uniform(), u2 = rng.uniform();
    target += uniformSphere(u1, u2) * l.radius;
  }
  const glm::vec3 s = target - origin;
  const float dist = glm::length(s);
  const float through = dist > eps ? tracer.transmittance(origin, s / dist, 0.0f, dist - eps) : 1.0f;
  if (through <= 0.0f) return glm::vec3(0.0f);
  return through < 1.0f ? l.intensity * (spot * c / r2 * through) : l.intensity * (spot * c / r2);
}

// A light's weight in punctualIrradianceOneLight: the luminance of its unshadowed irradiance at x (normal n),
// positive wherever the light can reach x: a point or spot light's cosine, falloff and cone do not depend on
// its radius' jitter; a sun's cosine is taken as cos(axis) + sin(disc radius), positive wherever a direction
// in its disc is above the surface.
float lightBound(const Light& l, const glm::vec3& x, const glm::vec3& n) {
  const float y = luminance(l.intensity);
  if (!(y > 0.0f)) return 0.0f;
  if (l.type == LightType::kDirectional) {
    const float c = glm::dot(n, -glm::normalize(l.direction)) + std::sin(std::max(l.angularRadiusRad, 0.0f));
    return c > 0.0f ? y * std::min(c, 1.0f) : 0.0f;
  }
  const glm::vec3 d = l.position - x;
  const float r2 = glm::dot(d, d);
  if (!(r2 > 0.0f)) return 0.0f;
  const glm::vec3 w = d / std::sqrt(r2);
  const float c = glm::dot(n, w);
  if (c <= 0.0f) return 0.0f;
  return y * spotFactor(l, -w) * c / r2;
}

}  // namespace

glm::vec3 punctualIrradiance(const SceneTracer& tracer, const glm::vec3& x, const glm::vec3& origin,
                             const glm::vec3& n, Rng& rng) {
  glm::vec3 e(0.0f);
  for (const Light& l : tracer.scene().lights) e += lightIrradiance(tracer, l, x, origin, n, rng);
  return e;
}

glm::vec3 punctualIrradianceOneLight(const SceneTracer& tracer, const glm::vec3& x, const glm::vec3& origin,
                                     const glm::vec3& n, Rng& rng) {
  const std::vector<Light>& lights = tracer.scene().lights;
  if (lights.size() == 1) return lightIrradiance(tracer, lights[0], x, origin, n, rng);
  double total = 0.0;
  for (const Light& l : lights) total += double(lightBound(l, x, n));
  if (!(total > 0.0)) return glm::vec3(0.0f);
  double pick = rng.uniformDouble() * total;
  for (size_t k = 0; k < lights.size(); ++k) {
    const double b = double(lightBound(lights[k], x, n));
    if (!(b > 0.0)) continue;
    if (pick < b || k + 1 == lights.size()) {
      return lightIrradiance(tracer, lights[k], x, origin, n, rng) * float(total / b);
    }
    pick -= b;
  }
  return glm::vec3(0.0f);  // rounding past the last light with a bound: none is lit there
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

glm::vec3 patchPointRadiance(const SceneTracer& tracer, const glm::vec3& probe, uint32_t triangle, float u,
                             float v, const glm::vec3& dir, float dist, Rng& rng) {
  const SceneTracer::Impl& impl = tracer.impl();
  if (tracer.isHole(triangle, u, v)) return glm::vec3(0.0f);
  const Material& m = impl.material(triangle);
  const float reflect = reflectedShare(m);
  if (maxComponent(m.albedo) <= 0.0f || !(reflect > 0.0f)) return glm::vec3(0.0f);
  const glm::vec3 nt = impl.normals[triangle];
  const float side = glm::dot(nt, dir);
  if (side == 0.0f || !std::isfinite(side)) return glm::vec3(0.0f);
  const glm::vec3 n = side < 0.0f ? nt : -nt;  // the side the probe sees
  const float eps = impl.rayEpsilon;
  const glm::vec3 y = impl.pointOn(triangle, u, v);
  const float through = dist > eps ? tracer.transmittance(probe, dir, 0.0f, dist - eps) : 1.0f;
  if (through <= 0.0f) return glm::vec3(0.0f);
  const glm::vec3 p = y + n * eps;
  const glm::vec3 e = punctualIrradianceOneLight(tracer, p, p, n, rng);
  return m.albedo * (kInvPi * reflect * through) * e;
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

// Hits of a probe's path that draw a lit-patch point (the first three: the light of further bounces is a
// small share, not worth two rays a hit).
constexpr int kLitPatchVertices = 3;

glm::vec3 incidentRadiance(const SceneTracer& tracer, const glm::vec3& origin, const glm::vec3& dir,
                           float prevPdf, const TraceSettings& settings, Rng& rng) {
  const SceneTracer::Impl& impl = tracer.impl();
  const Scene& scene = *impl.scene;
  const float eps = impl.rayEpsilon;
  glm::vec3 radiance(0.0f), throughput(1.0f);
  glm::vec3 o = origin, d = dir;
  const PatchGuide* bouncePatches = nullptr;  // set at the first hit when it drew a lit-patch point
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
        const float pdfLight = solidAnglePdf(impl.emissivePdfArea[hit.triangle], hit.t, cosLight);
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
    glm::vec3 punctual = punctualIrradiance(tracer, p, p, n, rng);
    if (direct && settings.firstHit) {
      FirstHit& f = *settings.firstHit;
      f.hit = true;
      f.triangle = hit.triangle;
      f.u = hit.u;
      f.v = hit.v;
      f.radiance = throughput * m.albedo * kInvPi * punctual;
      f.weight = 1.0f;
      if (f.patches && maxComponent(f.radiance) > 0.0f) {
        const float pdfArea = f.patches->pdfArea(hit.triangle, hit.u, hit.v);
        const float cosY = std::abs(glm::dot(hit.geometricNormal, d));
        if (pdfArea > 0.0f && cosY > 0.0f)
          f.weight = powerHeuristic(f.sphereWeight, solidAnglePdf(f.patchWeight * pdfArea, hit.t, cosY));
      }
      punctual *= f.weight;
    } else if (bouncePatches) {
      // A later hit, reached by a cosine direction from a hit that drew a lit-patch point: its punctual light
      // against that point (one each, power heuristic).
      const float pdfArea = bouncePatches->pdfArea(hit.triangle, hit.u, hit.v);
      const float cosY = std::abs(glm::dot(hit.geometricNormal, d));
      if (pdfArea > 0.0f && cosY > 0.0f && maxComponent(punctual) > 0.0f)
        punctual *= powerHeuristic(prevPdf, solidAnglePdf(pdfArea, hit.t, cosY));
    }
    const glm::vec3 irradiance = emissiveIrradiance(tracer, p, n, rng) + punctual;
    radiance += throughput * m.albedo * kInvPi * irradiance;
    bouncePatches = nullptr;
    if (settings.firstHit && settings.firstHit->patches && settings.firstHit->bounces &&
        vertex < kLitPatchVertices && vertex + 1 < settings.bounces) {
      // Light through a lit patch one bounce more: a point drawn by the probe's guide (the lit surfaces the
      // probe sees, which the first hits around it mostly see too), its one-bounce light reflected here,
      // MIS-weighted against the cosine direction that follows.
      bouncePatches = settings.firstHit->patches;
      const double g1 = rng.uniformDouble(), g2 = rng.uniformDouble();
      const float g3 = rng.uniform(), g4 = rng.uniform();
      const PatchPoint pt = bouncePatches->sample(g1, g2, g3, g4);
      const glm::vec3 to = impl.pointOn(pt.triangle, pt.u, pt.v) - p;
      const float dist = glm::length(to);
      if (dist > 0.0f && pt.pdfArea > 0.0f) {
        const glm::vec3 w = to / dist;
        const float cosX = glm::dot(n, w), cosZ = std::abs(glm::dot(impl.normals[pt.triangle], w));
        if (cosX > 0.0f && cosZ > 0.0f) {
          const glm::vec3 l = patchPointRadiance(tracer, p, pt.triangle, pt.u, pt.v, w, dist, rng);
          const float pdf = solidAnglePdf(pt.pdfArea, dist, cosZ);
          if (maxComponent(l) > 0.0f)
            radiance +=
                throughput * m.albedo * l * (kInvPi * cosX * powerHeuristic(pdf, cosX * kInvPi) / pdf);
        }
      }
    }
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
