// Tet geometry in double precision: the barycentric face planes, Sutherland-Hodgman clipping of a triangle to
// the tet (Sutherland & Hodgman 1974), and deterministic sample points: the R3 Kronecker sequence (Roberts,
// "The unreasonable effectiveness of quasirandom sequences", 2018) folded into the tet (Rocchini & Cignoni,
// "Generating random points in a tetrahedron", JGT 2000).
#include <algorithm>
#include <cmath>

#include <glm/geometric.hpp>

#include "tet_geometry.h"

namespace tetraprobe::occlusion_detail {

TetFrame makeTetFrame(const glm::dvec3 p[4]) {
  TetFrame t;
  for (int i = 0; i < 4; ++i) t.p[i] = p[i];
  for (int i = 0; i < 4; ++i)
    for (int j = i + 1; j < 4; ++j) t.scale = std::max(t.scale, glm::length(p[i] - p[j]));
  t.valid = t.scale > 0.0 && std::isfinite(t.scale);
  for (int i = 0; i < 4 && t.valid; ++i) {
    const glm::dvec3& a = p[(i + 1) % 4];
    const glm::dvec3& b = p[(i + 2) % 4];
    const glm::dvec3& c = p[(i + 3) % 4];
    const glm::dvec3 n = glm::cross(b - a, c - a);
    const double h = glm::dot(n, p[i] - a);  // 6 x signed volume, up to sign
    if (!(std::abs(h) > 1e-12 * t.scale * t.scale * t.scale)) t.valid = false;
    t.faceN[i] = n / h;
    t.faceD[i] = -glm::dot(t.faceN[i], a);
  }
  return t;
}

std::vector<glm::dvec3> clipTriangleToTet(const TetFrame& tet, const glm::dvec3& a, const glm::dvec3& b,
                                          const glm::dvec3& c, double& area) {
  std::vector<glm::dvec3> poly = {a, b, c}, next;
  area = 0.0;
  for (int i = 0; i < 4 && !poly.empty(); ++i) {
    next.clear();
    const size_t n = poly.size();
    for (size_t k = 0; k < n; ++k) {
      const glm::dvec3& p = poly[k];
      const glm::dvec3& q = poly[(k + 1) % n];
      const double dp = glm::dot(tet.faceN[i], p) + tet.faceD[i];
      const double dq = glm::dot(tet.faceN[i], q) + tet.faceD[i];
      if (dp >= 0.0) next.push_back(p);
      if ((dp >= 0.0) != (dq >= 0.0)) next.push_back(p + (q - p) * (dp / (dp - dq)));
    }
    poly.swap(next);
  }
  if (poly.size() < 3) {
    poly.clear();
    return poly;
  }
  glm::dvec3 sum(0.0);
  for (size_t k = 1; k + 1 < poly.size(); ++k) sum += glm::cross(poly[k] - poly[0], poly[k + 1] - poly[0]);
  area = 0.5 * glm::length(sum);
  return poly;
}

glm::dvec3 kronecker3(uint32_t n) {
  constexpr double g = 1.2207440846057594754;  // the plastic-number generalisation for 3 dimensions
  constexpr double a1 = 1.0 / g, a2 = 1.0 / (g * g), a3 = 1.0 / (g * g * g);
  const double k = double(n);
  auto frac = [](double x) { return x - std::floor(x); };
  return {frac(0.5 + a1 * k), frac(0.5 + a2 * k), frac(0.5 + a3 * k)};
}

glm::dvec4 foldCubeToTet(glm::dvec3 s) {
  double x = s.x, y = s.y, z = s.z;
  if (x + y > 1.0) {  // fold the cube into a triangular prism
    x = 1.0 - x;
    y = 1.0 - y;
  }
  if (y + z > 1.0) {  // and the prism into a tet
    const double t = z;
    z = 1.0 - x - y;
    y = 1.0 - t;
  } else if (x + y + z > 1.0) {
    const double t = z;
    z = x + y + z - 1.0;
    x = 1.0 - y - t;
  }
  return {1.0 - x - y - z, x, y, z};
}

}  // namespace tetraprobe::occlusion_detail
