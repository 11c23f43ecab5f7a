// Ray tracing of a Scene with Embree. Build side (Apache-2.0 Embree; no Embree type in this header).
#pragma once

#include <cstdint>
#include <memory>

#include <glm/vec3.hpp>

#include "tetraprobe/scene/scene.h"

namespace tetraprobe {

struct Hit {
  bool hit = false;
  float t = 0.0f;             // distance along the (unit) ray direction, metres
  uint32_t triangle = 0;      // index into Scene::triangles
  glm::vec3 geometricNormal{0.0f};  // unit, front-face side (counter-clockwise winding)
  bool frontFace = false;     // the ray met the triangle's front face
};

// Owns an Embree device and a committed scene built from `scene` (which must outlive the tracer).
// Thread-safe for concurrent queries after construction. Throws InputError for a scene with no triangles or
// non-finite positions.
class SceneTracer {
 public:
  explicit SceneTracer(const Scene& scene);
  ~SceneTracer();
  SceneTracer(const SceneTracer&) = delete;
  SceneTracer& operator=(const SceneTracer&) = delete;

  Hit intersect(const glm::vec3& origin, const glm::vec3& dir, float tnear, float tfar) const;
  bool occluded(const glm::vec3& origin, const glm::vec3& dir, float tnear, float tfar) const;

  const Scene& scene() const;
  // Total surface area of emissive triangles, and the sampling table for them (by power).
  struct Impl;
  const Impl& impl() const { return *impl_; }

 private:
  std::unique_ptr<Impl> impl_;
};

}  // namespace tetraprobe
