// Shared helpers for the tetra tests: tiny hand-built scenes and a brute-force ray caster standing in for the
// bake's SceneTracer (the tetra module links no ray tracer).
#pragma once

#include <cmath>
#include <vector>

#include <glm/geometric.hpp>

#include "tetraprobe/scene/scene.h"
#include "tetraprobe/tetra/placement.h"

namespace tetraprobe::test {

inline void addQuad(Scene& s, glm::vec3 a, glm::vec3 b, glm::vec3 c, glm::vec3 d) {  // CCW front face
  const uint32_t base = uint32_t(s.positions.size());
  s.positions.insert(s.positions.end(), {a, b, c, d});
  s.triangles.push_back({base, base + 1, base + 2});
  s.triangles.push_back({base, base + 2, base + 3});
  s.triangleMaterial.insert(s.triangleMaterial.end(), {0u, 0u});
}

// Axis-aligned box with faces pointing out (solid) or in (a room).
inline void addBox(Scene& s, glm::vec3 lo, glm::vec3 hi, bool outward) {
  const glm::vec3 c[8] = {{lo.x, lo.y, lo.z}, {hi.x, lo.y, lo.z}, {hi.x, hi.y, lo.z}, {lo.x, hi.y, lo.z},
                          {lo.x, lo.y, hi.z}, {hi.x, lo.y, hi.z}, {hi.x, hi.y, hi.z}, {lo.x, hi.y, hi.z}};
  const int f[6][4] = {{0, 3, 2, 1}, {4, 5, 6, 7}, {0, 1, 5, 4}, {2, 3, 7, 6}, {1, 2, 6, 5}, {0, 4, 7, 3}};
  for (const auto& q : f) {
    if (outward)
      addQuad(s, c[q[0]], c[q[1]], c[q[2]], c[q[3]]);
    else
      addQuad(s, c[q[0]], c[q[3]], c[q[2]], c[q[1]]);
  }
  if (s.materials.empty()) s.materials.push_back({});
}

struct RayHit {
  bool hit = false;
  double t = 0.0;
  bool front = false;
  glm::dvec3 normal{0.0};  // front-face unit normal
};

inline RayHit castRay(const Scene& s, const glm::dvec3& o, const glm::dvec3& d, double tmax) {
  RayHit best;
  best.t = tmax;
  for (const auto& tri : s.triangles) {
    const glm::dvec3 a(s.positions[tri.x]), b(s.positions[tri.y]), c(s.positions[tri.z]);
    const glm::dvec3 e1 = b - a, e2 = c - a, pv = glm::cross(d, e2);
    const double det = glm::dot(e1, pv);
    if (std::abs(det) < 1e-14) continue;
    const glm::dvec3 tv = o - a;
    const double u = glm::dot(tv, pv) / det;
    if (u < 0.0 || u > 1.0) continue;
    const glm::dvec3 qv = glm::cross(tv, e1);
    const double v = glm::dot(d, qv) / det;
    if (v < 0.0 || u + v > 1.0) continue;
    const double t = glm::dot(e2, qv) / det;
    if (t <= 1e-9 || t >= best.t) continue;
    best.hit = true;
    best.t = t;
    best.normal = glm::normalize(glm::cross(e1, e2));
    best.front = glm::dot(best.normal, d) < 0.0;
  }
  return best;
}

inline std::vector<glm::dvec3> fibonacciSphere(int n) {
  std::vector<glm::dvec3> dirs;
  const double golden = 3.14159265358979323846 * (3.0 - std::sqrt(5.0));
  for (int i = 0; i < n; ++i) {
    const double z = 1.0 - (i + 0.5) * 2.0 / n, r = std::sqrt(1.0 - z * z);
    dirs.emplace_back(r * std::cos(golden * i), r * std::sin(golden * i), z);
  }
  return dirs;
}

// The pipeline's clearance query, by brute force: 64 rays, insideByRays().
inline ClearanceQuery bruteForceClearance(const Scene& s) {
  return [&s](const std::vector<glm::dvec3>& pts, const std::vector<double>& reach) {
    const auto dirs = fibonacciSphere(64);
    std::vector<Clearance> out(pts.size());
    for (size_t i = 0; i < pts.size(); ++i) {
      int back = 0, hits = 0;
      glm::dvec3 escape(0.0);
      Clearance& c = out[i];
      for (const auto& d : dirs) {
        const RayHit h = castRay(s, pts[i], d, 1e30);
        if (h.hit && !h.front) ++back;
        hits += h.hit;
        if (!h.hit || (h.front && h.t > reach[i])) escape += d;
        if (h.hit && h.t < c.nearest) {
          c.nearest = h.t;
          c.away = h.front ? h.normal : -h.normal;
        }
      }
      c.inside = insideByRays(64, hits, back);
      if (glm::length(escape) > 0.0) c.escape = glm::normalize(escape);
    }
    return out;
  };
}

inline bool insideBox(const glm::dvec3& p, glm::vec3 lo, glm::vec3 hi) {
  return p.x > lo.x && p.y > lo.y && p.z > lo.z && p.x < hi.x && p.y < hi.y && p.z < hi.z;
}

}  // namespace tetraprobe::test
