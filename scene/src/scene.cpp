// Scene helpers shared by every loader.
#include "tetraprobe/scene/scene.h"

#include <glm/common.hpp>

namespace tetraprobe {

void sceneBounds(const Scene& scene, glm::vec3& lo, glm::vec3& hi) {
  lo = glm::vec3(0.0f);
  hi = glm::vec3(0.0f);
  if (scene.positions.empty()) return;
  lo = hi = scene.positions[0];
  for (const auto& p : scene.positions) {
    lo = glm::min(lo, p);
    hi = glm::max(hi, p);
  }
}

}  // namespace tetraprobe
