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
// non-finite positions, vertex indices out of range, or a material table that does not match the triangles
// (triangleMaterial must hold one in-range index per triangle). Zero-area triangles are accepted (never hit).
//
// Queries take a unit `dir` and the segment [tnear, tfar] in metres. Tracing threads should hold a
// FlushDenormalsScope (every bake entry point does).
class SceneTracer {
 public:
  explicit SceneTracer(const Scene& scene);
  ~SceneTracer();
  SceneTracer(const SceneTracer&) = delete;
  SceneTracer& operator=(const SceneTracer&) = delete;

  Hit intersect(const glm::vec3& origin, const glm::vec3& dir, float tnear, float tfar) const;
  bool occluded(const glm::vec3& origin, const glm::vec3& dir, float tnear, float tfar) const;

  const Scene& scene() const;
  // Distance by which secondary rays are offset from a surface to avoid self-hits, metres:
  // 5e-6 x (bounding-box diagonal + largest absolute coordinate), at least 1e-6.
  float rayEpsilon() const;
  // Total surface area of emissive triangles, and the sampling table for them (by power). Defined in
  // bake/src/tracer_impl.h (internal to the bake module).
  struct Impl;
  const Impl& impl() const { return *impl_; }

 private:
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
