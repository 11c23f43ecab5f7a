// Octahedral unit-vector encoding (oct_normal.h).
#include "tetraprobe/runtime/oct_normal.h"

#include <algorithm>
#include <cmath>

#include <glm/geometric.hpp>

namespace tetraprobe {
namespace {

// GLSL's sign(): 0 at 0.
double signOf(double v) {
  return double(v > 0.0) - double(v < 0.0);
}

uint32_t pack(int x, int y) {
  return uint32_t(uint16_t(int16_t(x))) | uint32_t(uint16_t(int16_t(y))) << 16;
}

}  // namespace

glm::dvec3 decodeOctNormalRaw(uint32_t code) {
  const double x = double(int16_t(uint16_t(code & 0xffffu))) * kOctNormalUnit;
  const double y = double(int16_t(uint16_t(code >> 16))) * kOctNormalUnit;
  const double z = 1.0 - std::abs(x) - std::abs(y);
  if (z < 0.0) return {(1.0 - std::abs(y)) * signOf(x), (1.0 - std::abs(x)) * signOf(y), z};
  return {x, y, z};
}

glm::vec3 decodeOctNormal(uint32_t code) {
  const glm::dvec3 raw = decodeOctNormalRaw(code);
  return glm::vec3(raw / glm::length(raw));  // |raw| >= 1/sqrt(3): never 0
}

uint32_t encodeOctNormal(const glm::dvec3& n) {
  const double l1 = std::abs(n.x) + std::abs(n.y) + std::abs(n.z);
  if (!(l1 > 0.0) || !std::isfinite(l1)) return pack(0, 0);
  double px = n.x / l1, py = n.y / l1;
  if (n.z < 0.0) {
    const double fx = (1.0 - std::abs(py)) * (px >= 0.0 ? 1.0 : -1.0);
    const double fy = (1.0 - std::abs(px)) * (py >= 0.0 ? 1.0 : -1.0);
    px = fx;
    py = fy;
  }
  const glm::dvec3 unit = n / glm::length(n);
  const double sx = px / kOctNormalUnit, sy = py / kOctNormalUnit;
  const auto clampCode = [](double v) { return std::clamp(int(v), -kOctNormalMax, kOctNormalMax); };
  const int xs[2] = {clampCode(std::floor(sx)), clampCode(std::ceil(sx))};
  const int ys[2] = {clampCode(std::floor(sy)), clampCode(std::ceil(sy))};
  uint32_t best = pack(xs[0], ys[0]);
  double bestDot = -2.0;
  for (int x : xs)
    for (int y : ys) {
      const uint32_t code = pack(x, y);
      const glm::dvec3 raw = decodeOctNormalRaw(code);
      const double d = glm::dot(raw, unit) / glm::length(raw);
      if (d > bestDot) {
        bestDot = d;
        best = code;
      }
    }
  return best;
}

glm::vec3 quantizeOctNormal(const glm::dvec3& n) {
  return decodeOctNormal(encodeOctNormal(n));
}

}  // namespace tetraprobe
