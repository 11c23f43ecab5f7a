// The lights of RenderMode::kFull as direct.comp reads them, and the view-projection of every shadow-map
// layer: six 90-degree cube faces per point or spot light, one orthographic box per sun. Internal to the
// render module.
#pragma once

#include <cstdint>
#include <vector>

#include <glm/mat4x4.hpp>
#include <glm/vec3.hpp>

#include "tetraprobe/render/render.h"

namespace tetraprobe::render_detail {

// One light, std430 (direct.comp's `Light`, 64 bytes).
struct GpuLight {
  float position[4];   // xyz local frame, metres; w: type 0 point, 1 spot, 2 directional
  float direction[4];  // xyz unit travel direction; w: cos(outer cone)
  float intensity[4];  // rgb W/sr or W/m^2; w: cos(inner cone)
  int32_t shadow[4];   // x: first shadow-map layer, -1 none
};
static_assert(sizeof(GpuLight) == 64, "direct.comp Light is 64 bytes in std430");

struct ShadowLights {
  std::vector<GpuLight> lights;
  std::vector<glm::mat4> layers;  // local frame -> the layer's clip space (depth 0..1, no y flip)
  float sunHalfWidth = 0.0f;      // half the side of every sun's orthographic box, metres
};

// Packs `lights` (world frame) for the level local frame whose origin is `origin`, with shadow-map layers
// covering the scene bounds [lo, hi] (world metres, lo <= hi): cube faces +X -X +Y -Y +Z -Z (direct.comp's
// cubeFace order) reaching the farthest bound corner, and for a sun a box holding the bounds' sphere.
// Throws std::runtime_error for a light whose numbers are not finite or whose direction is zero.
ShadowLights packShadowLights(const std::vector<RenderLight>& lights, const glm::dvec3& origin,
                              const glm::dvec3& lo, const glm::dvec3& hi);

}  // namespace tetraprobe::render_detail
