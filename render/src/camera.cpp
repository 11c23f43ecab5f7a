// The renderer's pinhole camera as a ray generator: the direction through an image point, for CPU tracers
// that must see exactly the pixels renderLevel rasterizes (same look-at frame, vertical field of view,
// Vulkan's y-down framebuffer after the projection's y flip, pixel centres at half-integers).
#include <cmath>

#include <glm/geometric.hpp>
#include <glm/gtc/matrix_transform.hpp>
#include <glm/mat3x3.hpp>
#include <glm/mat4x4.hpp>

#include "tetraprobe/render/render.h"

namespace tetraprobe {

glm::dvec3 pixelRayDirection(const RenderView& view, double x, double y) {
  // renderer.cpp: clip = perspectiveRH_ZO(fovY, w / h) with [1][1] negated, times lookAtRH(eye, target, up).
  // A view-space point (xv, yv, zv) lands at NDC x = f / aspect * xv / -zv and y = -f * yv / -zv (f = 1 /
  // tan(fovY / 2)), and the viewport maps NDC [-1, 1] to [0, width] x [0, height] with y down. Inverting:
  const double tanHalf = std::tan(glm::radians(double(view.fovYDeg)) * 0.5);
  const double aspect = double(view.width) / double(view.height);
  const double ndcX = 2.0 * x / double(view.width) - 1.0;
  const double ndcY = 2.0 * y / double(view.height) - 1.0;
  const glm::dvec3 dirView(ndcX * tanHalf * aspect, -ndcY * tanHalf, -1.0);
  const glm::dmat4 lookAt = glm::lookAtRH(glm::dvec3(view.eye), glm::dvec3(view.target), glm::dvec3(view.up));
  // The look-at rotation is orthonormal: its inverse is its transpose.
  return glm::normalize(glm::transpose(glm::dmat3(lookAt)) * dirView);
}

}  // namespace tetraprobe
