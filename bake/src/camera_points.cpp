// Evaluation points where a viewer looks: uniformly random positions on each camera's image plane, the first
// surface the primary ray meets, with the normal facing the camera. Scores what a player sees (the surfaces a
// level's cameras frame), where area-uniform points weight hidden backs, undersides and far walls by area.
// The camera frame is the renderer's (glm::lookAtRH with the camera's up, vertical field of view).
#include <cmath>
#include <limits>

#include <glm/geometric.hpp>
#include <glm/trigonometric.hpp>

#include "rng.h"
#include "tetraprobe/bake/bake.h"
#include "tracer_impl.h"

namespace tetraprobe {

using namespace bake_detail;

namespace {

constexpr int kMaxDrawsPerPoint = 20;
constexpr int kMaxBackFaceLayers = 64;

struct CameraFrame {
  glm::vec3 eye, forward, right, up;
  float tanHalfY = 0.0f;
  bool valid = false;
};

CameraFrame cameraFrame(const Camera& c, float aspect) {
  CameraFrame f;
  const glm::vec3 view = c.target - c.eye;
  if (!(glm::length(view) > 0.0f) || !(c.fovYDeg > 0.0f && c.fovYDeg < 180.0f)) return f;
  f.eye = c.eye;
  f.forward = glm::normalize(view);
  const glm::vec3 side = glm::cross(f.forward, c.up);
  if (!(glm::length(side) > 0.0f)) return f;
  f.right = glm::normalize(side) * aspect;
  f.up = glm::cross(glm::normalize(side), f.forward);
  f.tanHalfY = std::tan(glm::radians(c.fovYDeg) * 0.5f);
  f.valid = std::isfinite(f.tanHalfY);
  return f;
}

}  // namespace

std::vector<SurfacePoint> sampleCameraPoints(const SceneTracer& tracer, const std::vector<Camera>& cameras,
                                             int count, uint64_t seed, float aspect) {
  std::vector<SurfacePoint> points;
  if (count < 1 || cameras.empty() || !(aspect > 0.0f)) return points;
  std::vector<CameraFrame> frames;
  for (const Camera& c : cameras) frames.push_back(cameraFrame(c, aspect));
  DenormalScope denormals;
  const SceneTracer::Impl& impl = tracer.impl();
  points.reserve(size_t(count));
  const int64_t maxDraws = int64_t(kMaxDrawsPerPoint) * count;
  for (int64_t draw = 0; draw < maxDraws && int(points.size()) < count; ++draw) {
    const CameraFrame& f = frames[size_t(draw % int64_t(frames.size()))];
    if (!f.valid) continue;
    Rng rng(streamKey(seed, uint64_t(draw)));
    const float sx = 2.0f * rng.uniform() - 1.0f, sy = 2.0f * rng.uniform() - 1.0f;
    const glm::vec3 dir = glm::normalize(f.forward + f.tanHalfY * (sx * f.right + sy * f.up));
    // Back faces are culled, as the renderer does (single-sided walls are seen through from outside).
    Hit hit;
    float tnear = 0.0f;
    for (int layer = 0; layer < kMaxBackFaceLayers; ++layer) {
      hit = tracer.intersect(f.eye, dir, tnear, std::numeric_limits<float>::infinity());
      if (!hit.hit || hit.frontFace) break;
      tnear = hit.t + impl.rayEpsilon;
      hit.hit = false;
    }
    if (!hit.hit) continue;
    SurfacePoint sp;
    sp.position = glm::dvec3(impl.pointOn(hit.triangle, hit.u, hit.v));
    sp.normal = hit.geometricNormal;
    sp.albedo = impl.material(hit.triangle).albedo;
    sp.triangle = hit.triangle;
    points.push_back(sp);
  }
  return points;
}

}  // namespace tetraprobe
