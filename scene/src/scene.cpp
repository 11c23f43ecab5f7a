// Scene helpers shared by every loader.
#include "tetraprobe/scene/scene.h"

#include <algorithm>
#include <cmath>
#include <string>

#include <glm/common.hpp>
#include <glm/geometric.hpp>

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

double surfaceArea(const Scene& scene) {
  double area = 0.0;
  for (const glm::uvec3& t : scene.triangles) {
    const glm::dvec3 a(scene.positions[t.x]), b(scene.positions[t.y]), c(scene.positions[t.z]);
    area += 0.5 * glm::length(glm::cross(b - a, c - a));
  }
  return area;
}

namespace {

// Texel index along one axis of `size` texels for coordinate `c` (one unit per image).
uint32_t wrapTexel(float c, uint32_t size, TextureWrap wrap) {
  const double n = double(size);
  double x = std::floor(double(c) * n);
  switch (wrap) {
    case TextureWrap::kClampToEdge:
      x = std::clamp(x, 0.0, n - 1.0);
      break;
    case TextureWrap::kMirroredRepeat:
      x = std::fmod(x, 2.0 * n);
      if (x < 0.0) x += 2.0 * n;
      if (x >= n) x = 2.0 * n - 1.0 - x;
      break;
    case TextureWrap::kRepeat:
      x = std::fmod(x, n);
      if (x < 0.0) x += n;
      break;
  }
  return std::min(uint32_t(x), size - 1);
}

}  // namespace

float AlphaTexture::sample(glm::vec2 uv) const {
  if (!std::isfinite(uv.x) || !std::isfinite(uv.y)) return 1.0f;
  const uint32_t x = wrapTexel(uv.x, width, wrapU), y = wrapTexel(uv.y, height, wrapV);
  return float(alpha[size_t(y) * width + x]) * (1.0f / 255.0f);
}

std::string transparencyProblem(const Scene& scene) {
  for (const Material& m : scene.materials) {
    if (!(m.transmission >= 0.0f && m.transmission <= 1.0f))
      return "material '" + m.name + "' has a transmission outside [0, 1]";
    if (!std::isfinite(m.alphaCutoff)) return "material '" + m.name + "' has a non-finite alpha cutoff";
    if (m.alphaTexture < -1 || (m.alphaTexture >= 0 && size_t(m.alphaTexture) >= scene.alphaTextures.size()))
      return "material '" + m.name + "' uses alpha texture " + std::to_string(m.alphaTexture) + " of " +
             std::to_string(scene.alphaTextures.size());
  }
  for (const AlphaTexture& t : scene.alphaTextures)
    if (t.width == 0 || t.height == 0 || t.alpha.size() != size_t(t.width) * t.height)
      return "alpha texture '" + t.name + "' has " + std::to_string(t.alpha.size()) + " texels for " +
             std::to_string(t.width) + " x " + std::to_string(t.height);
  if (scene.cutoutUvs.size() != 3 * scene.cutoutTriangles.size())
    return std::to_string(scene.cutoutUvs.size()) + " cutout texture coordinates for " +
           std::to_string(scene.cutoutTriangles.size()) + " cutout triangles (need 3 each)";
  for (size_t k = 0; k < scene.cutoutTriangles.size(); ++k) {
    if (scene.cutoutTriangles[k] >= scene.triangles.size())
      return "cutout triangle " + std::to_string(scene.cutoutTriangles[k]) + " out of range";
    if (k > 0 && scene.cutoutTriangles[k] <= scene.cutoutTriangles[k - 1])
      return "cutout triangles are not in increasing order";
  }
  return {};
}

}  // namespace tetraprobe
