// Shadow-map set-up for the full render (shadow_lights.h): per light, the layers' view-projections.
// Cube faces are plain 90-degree perspectives picked by the major axis of light-to-point (no seamless cube
// sampling); a sun gets one orthographic box around the scene (no cascades).
#include "shadow_lights.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include <glm/geometric.hpp>
#include <glm/gtc/matrix_transform.hpp>

namespace tetraprobe::render_detail {
namespace {

bool finite(const glm::vec3& v) {
  return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z);
}

}  // namespace

ShadowLights packShadowLights(const std::vector<RenderLight>& lights, const glm::dvec3& origin,
                              const glm::dvec3& lo, const glm::dvec3& hi) {
  ShadowLights out;
  const glm::dvec3 centre = (lo + hi) * 0.5 - origin;
  const double radius = std::max(glm::length(hi - lo) * 0.5, 1e-3) * 1.01;
  out.sunHalfWidth = float(radius);
  for (size_t i = 0; i < lights.size(); ++i) {
    const RenderLight& l = lights[i];
    if (!finite(l.position) || !finite(l.direction) || !finite(l.intensity) ||
        !std::isfinite(l.innerConeRad) || !std::isfinite(l.outerConeRad))
      throw std::runtime_error("render: light " + std::to_string(i) + " has a non-finite number");
    const bool sun = l.type == RenderLightType::kDirectional;
    const double dirLen = glm::length(glm::dvec3(l.direction));
    if ((sun || l.type == RenderLightType::kSpot) && !(dirLen > 0.0))
      throw std::runtime_error("render: light " + std::to_string(i) + " has a zero direction");
    const glm::dvec3 dir = dirLen > 0.0 ? glm::dvec3(l.direction) / dirLen : glm::dvec3(0, -1, 0);
    const glm::dvec3 pos = glm::dvec3(l.position) - origin;
    GpuLight g{};
    for (int a = 0; a < 3; ++a) {
      g.position[a] = float(pos[a]);
      g.direction[a] = float(dir[a]);
      g.intensity[a] = l.intensity[a];
    }
    g.position[3] = sun ? 2.0f : l.type == RenderLightType::kSpot ? 1.0f : 0.0f;
    g.direction[3] = std::cos(l.outerConeRad);
    g.intensity[3] = std::cos(l.innerConeRad);
    g.shadow[0] = int32_t(out.layers.size());
    if (sun) {
      const glm::dvec3 up = std::abs(dir.y) > 0.99 ? glm::dvec3(1, 0, 0) : glm::dvec3(0, 1, 0);
      const glm::dmat4 v = glm::lookAtRH(centre - dir * (2.0 * radius), centre, up);
      const glm::dmat4 p = glm::orthoRH_ZO(-radius, radius, -radius, radius, 0.0, 4.0 * radius);
      out.layers.push_back(glm::mat4(p * v));
    } else {
      double far = 1e-3;
      for (int c = 0; c < 8; ++c) {
        const glm::dvec3 corner((c & 1) ? hi.x : lo.x, (c & 2) ? hi.y : lo.y, (c & 4) ? hi.z : lo.z);
        far = std::max(far, glm::length(corner - origin - pos));
      }
      far *= 1.01;
      const glm::dmat4 p = glm::perspectiveRH_ZO(glm::radians(90.0), 1.0, far / 4000.0, far);
      const glm::dvec3 axes[6] = {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}};
      for (const glm::dvec3& a : axes) {
        const glm::dvec3 up = a.y != 0.0 ? glm::dvec3(0, 0, 1) : glm::dvec3(0, 1, 0);
        out.layers.push_back(glm::mat4(p * glm::lookAtRH(pos, pos + a, up)));
      }
    }
    out.lights.push_back(g);
  }
  return out;
}

}  // namespace tetraprobe::render_detail
