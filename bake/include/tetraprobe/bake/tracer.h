// Ray tracing of a Scene with Embree. Build side (Apache-2.0 Embree; no Embree type in this header).
#pragma once

#include <cstdint>
#include <memory>

#include <glm/vec3.hpp>

#include "tetraprobe/scene/scene.h"

namespace tetraprobe {

struct Hit {
  bool hit = false;
  float t = 0.0f;                   // distance along the (unit) ray direction, metres
  uint32_t triangle = 0;            // index into Scene::triangles
  glm::vec3 geometricNormal{0.0f};  // unit, front-face side (counter-clockwise winding)
  bool frontFace = false;           // the ray met the triangle's front face
  float u = 0.0f, v = 0.0f;  // barycentrics: point = (1-u-v) P0 + u P1 + v P2 (P = the triangle's vertices)
};

// Owns an Embree device and a committed scene built from `scene` (which must outlive the tracer).
// Thread-safe for concurrent queries after construction. Throws InputError for a scene with no triangles,
// non-finite positions, vertex indices out of range, a material table that does not match the triangles
// (triangleMaterial must hold one in-range index per triangle), or inconsistent transparency data
// (transparencyProblem). Zero-area triangles are accepted (never hit).
//
// Transparency (scene.h): where a triangle's alpha cutout has a hole there is no surface, for every query
// (an Embree filter on the cutout triangles, which live in a geometry of their own). Surfaces with
// transmission > 0 are surfaces: intersect() and occluded() report them unless `maxTransmission` says to
// step over them, and transmittance() multiplies their transmissions. Steps over a surface at distance t
// resume the same ray at max(t + rayEpsilon(), the next float), so surfaces closer than that behind it are
// skipped too. A scene without transmission traces exactly as one without these parameters.
//
// Queries take a unit `dir` and the segment [tnear, tfar] in metres. Tracing threads should hold a
// FlushDenormalsScope (every bake entry point does).
class SceneTracer {
 public:
  explicit SceneTracer(const Scene& scene);
  ~SceneTracer();
  SceneTracer(const SceneTracer&) = delete;
  SceneTracer& operator=(const SceneTracer&) = delete;

  // Closest surface on the segment whose material's transmission is at most `maxTransmission`; the default
  // (1) takes every surface, 0 only opaque ones (the geometric tests: a pane of glass is no wall that hides
  // or encloses anything). hit.t is measured from `origin`.
  Hit intersect(const glm::vec3& origin, const glm::vec3& dir, float tnear, float tfar,
                float maxTransmission = 1.0f) const;
  // Whether intersect() with the same arguments would hit (any-hit query when maxTransmission is 1).
  bool occluded(const glm::vec3& origin, const glm::vec3& dir, float tnear, float tfar,
                float maxTransmission = 1.0f) const;
  // Fraction of light crossing the segment: 0 when an opaque surface lies on it, else the product of the
  // transmissions of the surfaces on it (1 when there are none). Exactly 0 or 1, from one any-hit query,
  // when the scene has no transmission.
  float transmittance(const glm::vec3& origin, const glm::vec3& dir, float tnear, float tfar) const;
  // Material transmission of `triangle` (an index into Scene::triangles).
  float transmission(uint32_t triangle) const;
  // True when some triangle's material lets light through (transmission > 0).
  bool hasTransmission() const;
  // True when the point with barycentrics (u, v) of `triangle` lies in a hole of its alpha cutout (always
  // false for triangles without a cutout). For samplers that pick points on surfaces.
  bool isHole(uint32_t triangle, float u, float v) const;

  const Scene& scene() const;
  // Distance by which secondary rays are offset from a surface to avoid self-hits, metres:
  // 5e-6 x (bounding-box diagonal + largest absolute coordinate), at least 1e-6.
  float rayEpsilon() const;
  // Total surface area of emissive triangles, and the sampling table for them (by power). Defined in
  // bake/src/tracer_impl.h (internal to the bake module).
  struct Impl;
  const Impl& impl() const { return *impl_; }

 private:
  Hit closestHit(const glm::vec3& origin, const glm::vec3& dir, float tnear, float tfar) const;
  bool anyHit(const glm::vec3& origin, const glm::vec3& dir, float tnear, float tfar) const;

  std::unique_ptr<Impl> impl_;
};

// Sets flush-to-zero and denormals-are-zero (x86 MXCSR) on the calling thread while alive and restores the
// previous mode on destruction. Enter one in every thread that traces (Embree's recommendation); every bake
// entry point does so itself. A no-op on other architectures.
class FlushDenormalsScope {
 public:
  FlushDenormalsScope();
  ~FlushDenormalsScope();
  FlushDenormalsScope(const FlushDenormalsScope&) = delete;
  FlushDenormalsScope& operator=(const FlushDenormalsScope&) = delete;

 private:
  unsigned int saved_ = 0;
};

// Radiance of the sky seen along unit direction `dir`, W/(m^2 sr). Constant sky: scene.skyRadiance.
// Gradient sky: linear in dir.y, skyRadiance at the zenith (+Y, y = 1) to skyHorizonRadiance at the horizon
// (y = 0) and constant skyHorizonRadiance below it.
glm::vec3 skyRadiance(const Scene& scene, const glm::vec3& dir);

}  // namespace tetraprobe
