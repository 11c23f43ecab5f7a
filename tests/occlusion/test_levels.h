// Tiny hand-built scenes and levels for the occlusion tests.
#pragma once

#include <string>
#include <vector>

#include <glm/geometric.hpp>
#include <glm/vec2.hpp>

#include "tetraprobe/bake/tracer.h"
#include "tetraprobe/runtime/level.h"
#include "tetraprobe/scene/scene.h"
#include "tetraprobe/tetra/tetrahedralize.h"

namespace tetraprobe::test {

inline Scene emptyScene() {
  Scene s;
  Material m;
  m.name = "grey";
  m.albedo = glm::vec3(0.5f);
  s.materials.push_back(m);
  return s;
}

inline void addTriangle(Scene& s, glm::vec3 a, glm::vec3 b, glm::vec3 c) {
  const uint32_t base = uint32_t(s.positions.size());
  s.positions.insert(s.positions.end(), {a, b, c});
  s.triangles.push_back(glm::uvec3(base, base + 1, base + 2));
  s.triangleMaterial.push_back(0);
}

// Quad a-b-c-d (counter-clockwise seen from its front) as two triangles.
inline void addQuad(Scene& s, glm::vec3 a, glm::vec3 b, glm::vec3 c, glm::vec3 d) {
  addTriangle(s, a, b, c);
  addTriangle(s, a, c, d);
}

// Axis-aligned quad on plane `axis` = `at`, spanning [lo, hi] in the other two axes (front faces +axis).
inline void addAxisQuad(Scene& s, int axis, float at, glm::vec2 lo, glm::vec2 hi) {
  const int a = (axis + 1) % 3, b = (axis + 2) % 3;
  auto p = [&](float u, float v) {
    glm::vec3 q;
    q[axis] = at;
    q[a] = u;
    q[b] = v;
    return q;
  };
  addQuad(s, p(lo.x, lo.y), p(hi.x, lo.y), p(hi.x, hi.y), p(lo.x, hi.y));
}

// Closed box with outward faces.
inline void addBox(Scene& s, glm::vec3 lo, glm::vec3 hi, bool inward = false) {
  for (int axis = 0; axis < 3; ++axis) {
    const int a = (axis + 1) % 3, b = (axis + 2) % 3;
    for (int side = 0; side < 2; ++side) {
      const float at = side ? hi[axis] : lo[axis];
      auto p = [&](float u, float v) {
        glm::vec3 q;
        q[axis] = at;
        q[a] = u;
        q[b] = v;
        return q;
      };
      const bool front = (side == 1) != inward;  // front faces +axis on the hi side of an outward box
      if (front)
        addQuad(s, p(lo[a], lo[b]), p(hi[a], lo[b]), p(hi[a], hi[b]), p(lo[a], hi[b]));
      else
        addQuad(s, p(lo[a], lo[b]), p(lo[a], hi[b]), p(hi[a], hi[b]), p(hi[a], lo[b]));
    }
  }
}

// Level of world-space `probes` with its local frame at `origin` (world = origin + local).
inline Level makeLevel(const std::vector<glm::dvec3>& probes, const glm::dvec3& origin = glm::dvec3(0.0)) {
  const TetMesh mesh = tetrahedralizeDelaunay(probes);
  Level level;
  level.origin = origin;
  for (const glm::dvec3& p : probes) level.probes.push_back(glm::vec3(p - origin));
  level.sh.resize(probes.size());
  level.tets = buildTetRecords(probes, mesh, level.origin);
  return level;
}

// The regular tet used by the single-tet cases: probes 0, 1 at z = 0 and 2, 3 at z = 1.
inline std::vector<glm::dvec3> regularTet() {
  return {{0, 0, 0}, {1, 1, 0}, {1, 0, 1}, {0, 1, 1}};
}

// Ray answer: is probe position `probe` visible from `x` (on a surface with normal n, or n = 0)?
inline bool rayVisible(const SceneTracer& tracer, glm::vec3 x, glm::vec3 n, glm::vec3 probe) {
  if (glm::dot(n, n) > 0.0f) {
    if (glm::dot(probe - x, n) < 0.0f) return false;
    x += glm::normalize(n) * 1e-4f;
  }
  const glm::vec3 d = probe - x;
  const float len = glm::length(d);
  return len == 0.0f || !tracer.occluded(x, d / len, 0.0f, len);
}

}  // namespace tetraprobe::test
