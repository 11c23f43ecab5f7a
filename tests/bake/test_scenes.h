// Tiny hand-built scenes for the bake tests (the scene loaders are tested elsewhere).
#pragma once

#include <cmath>
#include <numbers>
#include <string>

#include <glm/geometric.hpp>

#include "tetraprobe/scene/scene.h"

namespace tetraprobe::test {

inline uint32_t addMaterial(Scene& s, glm::vec3 albedo, glm::vec3 emission = glm::vec3(0.0f)) {
  Material m;
  m.name = "m";
  m.name += std::to_string(s.materials.size());  // (operator+ trips a GCC 12 -Wrestrict false positive)
  m.albedo = albedo;
  m.emission = emission;
  s.materials.push_back(m);
  return uint32_t(s.materials.size() - 1);
}

inline void addTriangle(Scene& s, glm::vec3 a, glm::vec3 b, glm::vec3 c, uint32_t material) {
  const uint32_t base = uint32_t(s.positions.size());
  s.positions.insert(s.positions.end(), {a, b, c});
  s.triangles.push_back(glm::uvec3(base, base + 1, base + 2));
  s.triangleMaterial.push_back(material);
}

// Quad a-b-c-d, counter-clockwise seen from its front, split into n x n cells (2 triangles each).
inline void addQuad(Scene& s, glm::vec3 a, glm::vec3 b, glm::vec3 c, glm::vec3 d, uint32_t material,
                    int n = 1) {
  auto at = [&](int i, int j) {
    const float u = float(i) / n, v = float(j) / n;
    return a * (1 - u) * (1 - v) + b * u * (1 - v) + c * u * v + d * (1 - u) * v;
  };
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      addTriangle(s, at(i, j), at(i + 1, j), at(i + 1, j + 1), material);
      addTriangle(s, at(i, j), at(i + 1, j + 1), at(i, j + 1), material);
    }
}

// Axis-aligned box [lo, hi]; faces point inward (a room) or outward (a solid crate).
inline void addBox(Scene& s, glm::vec3 lo, glm::vec3 hi, bool inward, uint32_t material, int n = 1) {
  const glm::vec3 p[8] = {{lo.x, lo.y, lo.z}, {hi.x, lo.y, lo.z}, {hi.x, hi.y, lo.z}, {lo.x, hi.y, lo.z},
                          {lo.x, lo.y, hi.z}, {hi.x, lo.y, hi.z}, {hi.x, hi.y, hi.z}, {lo.x, hi.y, hi.z}};
  // Outward-facing (counter-clockwise seen from outside) faces.
  const int f[6][4] = {{0, 3, 2, 1}, {4, 5, 6, 7}, {0, 1, 5, 4}, {3, 7, 6, 2}, {0, 4, 7, 3}, {1, 2, 6, 5}};
  for (const auto& q : f) {
    if (inward)
      addQuad(s, p[q[3]], p[q[2]], p[q[1]], p[q[0]], material, n);
    else
      addQuad(s, p[q[0]], p[q[1]], p[q[2]], p[q[3]], material, n);
  }
}

// UV sphere, front faces toward the centre (inward) or away from it.
inline void addSphere(Scene& s, glm::vec3 centre, float radius, bool inward, uint32_t material,
                      int rings = 24, int segments = 48) {
  auto at = [&](int i, int j) {
    const double th = std::numbers::pi * i / rings, ph = 2.0 * std::numbers::pi * j / segments;
    return centre +
           radius * glm::vec3(std::sin(th) * std::cos(ph), std::cos(th), std::sin(th) * std::sin(ph));
  };
  auto tri = [&](glm::vec3 a, glm::vec3 b, glm::vec3 c) {
    const glm::vec3 n = glm::cross(b - a, c - a);
    if (glm::length(n) < 1e-9f) return;
    const bool facesIn = glm::dot(n, centre - (a + b + c) / 3.0f) > 0.0f;
    if (facesIn == inward)
      addTriangle(s, a, b, c, material);
    else
      addTriangle(s, a, c, b, material);
  };
  for (int i = 0; i < rings; ++i)
    for (int j = 0; j < segments; ++j) {
      tri(at(i, j), at(i + 1, j), at(i + 1, j + 1));
      tri(at(i, j), at(i + 1, j + 1), at(i, j + 1));
    }
}

// Square ground plane at height y, facing +Y, half-size h.
inline void addGround(Scene& s, float y, float h, uint32_t material) {
  addQuad(s, {-h, y, h}, {h, y, h}, {h, y, -h}, {-h, y, -h}, material);
}

}  // namespace tetraprobe::test
