// The bake's unidirectional path tracer (Lambertian surfaces, next-event estimation with MIS), shared by the
// probe bake and the reference oracle. Internal to the bake module.
//
// Light content (runtime/level.h ProbeContent), seen from the receiver (a probe or a reference point):
// the first surface a receiver's ray meets, or the sky it escapes to, is *direct* light (kContentEmissive,
// kContentSky); everything reflected at that surface or later is kContentIndirect, whatever lit it (punctual
// lights included). Point/spot/directional light reaching the receiver without a bounce is
// kContentDirectPunctual and is added by the callers (analytically for probes, by NEE at reference points).
#pragma once

#include <algorithm>
#include <cstdint>

#include <glm/vec3.hpp>

#include "patch_guide.h"
#include "rng.h"
#include "tetraprobe/bake/tracer.h"

namespace tetraprobe::bake_detail {

// A probe's sphere direction in lit-patch sampling (patch_guide.h): in, the patches and the two techniques'
// weights; out, what the direction's first hit found.
struct FirstHit {
  const PatchGuide* patches = nullptr;  // null: the first hit's punctual light counts fully
  float sphereWeight = 0.0f;            // directions a batch x the density this one was drawn with
  float patchWeight = 0.0f;             // patch points a batch (x their density at the hit: the MIS partner)
  bool bounces = false;                 // the path's first kLitPatchVertices hits draw a patch point each
  // Out: the first surface hit (triangle, barycentrics) and its one-bounce light, albedo / pi x the punctual
  // lights' irradiance, before the MIS weight (0 when nothing was hit or lit); `weight` is that weight.
  bool hit = false;
  uint32_t triangle = 0;
  float u = 0.0f, v = 0.0f;
  glm::vec3 radiance{0.0f};
  float weight = 1.0f;
};

struct TraceSettings {
  int bounces = 2;       // diffuse reflections after the first hit
  uint32_t content = 0;  // ProbeContent flags
  // Set for a probe's direction under lit-patch sampling: the first surface hit's punctual light is
  // MIS-weighted against the patch points (power heuristic), and the hit is reported.
  FirstHit* firstHit = nullptr;
};

// The share of the light meeting a surface that a path reflects there (scene.h's thin-glass model: it passes a
// transmissive surface with probability `transmission`, else reflects): 1 - transmission, 0 from 1 on.
inline float reflectedShare(const Material& m) {
  return 1.0f - std::min(m.transmission, 1.0f);
}

// The one-bounce light a patch point sends to a probe (lit-patch sampling): albedo / pi x the punctual
// lights' irradiance at barycentrics (u, v) of `triangle`, on the side facing the probe, times the
// transmittance of the segment from the probe. `dir` and `dist` are from the probe to the point; 0 when the
// point sits in an alpha-cutout hole or the segment is blocked.
glm::vec3 patchPointRadiance(const SceneTracer& tracer, const glm::vec3& probe, uint32_t triangle, float u,
                             float v, const glm::vec3& dir, float dist, Rng& rng);

// Radiance in W/(m^2 sr) arriving at `origin` from unit direction `dir` (the ray starts at origin, tnear 0).
// `prevPdf` > 0: `dir` was drawn with this solid-angle pdf (a cosine lobe, or a probe's uniform sphere) at a
// point that also sampled the emissive triangles as often (emissiveIrradiance, sampleEmitter), so emission
// met by this ray is MIS-weighted against that; 0: no light sampling was done at origin and emission counts fully. At a transmissive surface the path
// continues straight on with probability `transmission` (the path's rng; no bounce counted), else
// reflects diffusely with the albedo; opaque surfaces draw no extra random number.
glm::vec3 incidentRadiance(const SceneTracer& tracer, const glm::vec3& origin, const glm::vec3& dir,
                           float prevPdf, const TraceSettings& settings, Rng& rng);

// A point drawn on the emissive triangles by power (area-uniform within a triangle), seen from `origin`.
struct EmitterSample {
  glm::vec3 dir{0.0f};  // unit direction from origin to the point
  float dist = 0.0f;    // distance from origin to the point
  float pdf = 0.0f;     // solid-angle pdf of drawing dir (power share / area * dist^2 / cos at the light)
  glm::vec3 radiance{0.0f};  // the emission leaving the point towards origin (not shadow-tested)
};

// Draws one EmitterSample (three random numbers whatever the outcome). False when the scene has no
// emissive triangles, the point lies in an alpha-cutout hole, coincides with origin, or faces away from it
// (emission is front-face only): such a draw contributes 0, as a BSDF or sphere ray would find no emission.
bool sampleEmitter(const SceneTracer& tracer, const glm::vec3& origin, Rng& rng, EmitterSample& out);

// The transmittance of the segment from `origin` to sample `s`'s point (stopping a ray epsilon short of it;
// 1 when it is closer than that): 0 when an opaque surface blocks it.
float emitterTransmittance(const SceneTracer& tracer, const glm::vec3& origin, const EmitterSample& s);

// One-sample estimate of the irradiance (W/m^2) at `origin` (already offset from its surface) with unit
// normal n from emissive triangles, sampled by power and MIS-weighted (power heuristic) against cosine
// sampling of the hemisphere about n. Shadow-tested: weighted by the segment's transmittance. Points that
// fall in an alpha-cutout hole of the chosen emitter contribute 0 (BSDF rays miss them too).
glm::vec3 emissiveIrradiance(const SceneTracer& tracer, const glm::vec3& origin, const glm::vec3& n,
                             Rng& rng);

// Irradiance (W/m^2) at point x with unit normal n from every point, spot and directional light; shadow rays
// start at `origin` (x offset off its surface, or x itself in free space). Point/spot: I cos / r^2 with
// r = |light - x|, spot cone smoothstep(cos outer, cos inner, cos angle); a light radius > 0 jitters the
// shadow ray's end on that sphere (soft shadows). Directional: E cos(w) for w uniform in the sun disc's cone
// (the disc's perpendicular irradiance is E). Each is weighted by its shadow ray's transmittance (0 when an
// opaque surface blocks it). Exact (no randomness) for zero radii.
glm::vec3 punctualIrradiance(const SceneTracer& tracer, const glm::vec3& x, const glm::vec3& origin,
                             const glm::vec3& n, Rng& rng);

// An unbiased one-sample estimate of punctualIrradiance: one light drawn in proportion to a weight of its
// unshadowed irradiance at x (its luminance x cosine x falloff x cone; a sun's cosine widened by its disc),
// its term over the probability of drawing it. One shadow ray whatever the number of lights; exactly
// punctualIrradiance's when the scene has one light.
glm::vec3 punctualIrradianceOneLight(const SceneTracer& tracer, const glm::vec3& x, const glm::vec3& origin,
                                     const glm::vec3& n, Rng& rng);

// Spot cone attenuation for light `l` towards unit direction `toPoint` (from the light to the receiver).
float spotFactor(const Light& l, const glm::vec3& toPoint);

}  // namespace tetraprobe::bake_detail
