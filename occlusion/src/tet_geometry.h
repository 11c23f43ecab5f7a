// Internal to the occlusion module: a uniform grid of scene triangles, clipping triangles to a tet, and the
// deterministic sample points used to check a tet's occlusion data.
#pragma once

#include <cstdint>
#include <vector>

#include <glm/vec3.hpp>
#include <glm/vec4.hpp>

#include "tetraprobe/scene/scene.h"

namespace tetraprobe::occlusion_detail {

// Scene triangles bucketed in a uniform grid over a box (level local frame, metres). Triangles outside the
// box are left out. Cells hold triangle indices in increasing order (CSR arrays).
class TriangleGrid {
 public:
  // `local[i]` = scene.positions[i] in the level's local frame.
  TriangleGrid(const Scene& scene, const std::vector<glm::dvec3>& local, const glm::dvec3& lo,
               const glm::dvec3& hi);
  // Indices of triangles whose bounding box may overlap [lo, hi], sorted, without duplicates (appended to a
  // cleared `out`).
  void query(const glm::dvec3& lo, const glm::dvec3& hi, std::vector<uint32_t>& out) const;

 private:
  glm::ivec3 cellOf(const glm::dvec3& p) const;
  glm::dvec3 lo_{0.0}, cell_{1.0};
  glm::ivec3 dims_{1};
  std::vector<uint32_t> start_;  // cells + 1
  std::vector<uint32_t> items_;
};

// A tet in double precision: w_i(X) = dot(faceN[i], X) + faceD[i] is the barycentric weight of p[i].
struct TetFrame {
  glm::dvec3 p[4];
  glm::dvec3 faceN[4];
  double faceD[4] = {0, 0, 0, 0};
  double scale = 0.0;  // longest edge, metres
  bool valid = false;  // false for a degenerate (zero-volume) tet
};
TetFrame makeTetFrame(const glm::dvec3 p[4]);

// Clips triangle abc to the tet (Sutherland-Hodgman against w_i >= 0). Returns the convex polygon (empty
// when nothing is left) and its area in `area`.
std::vector<glm::dvec3> clipTriangleToTet(const TetFrame& tet, const glm::dvec3& a, const glm::dvec3& b,
                                          const glm::dvec3& c, double& area);

// The R3 Kronecker sequence (Roberts 2018): n-th point of a low-discrepancy sequence in [0,1)^3.
glm::dvec3 kronecker3(uint32_t n);

// Uniform point in the tet from a point of the unit cube (Rocchini & Cignoni 2000, cube folding): barycentric
// weights of p[0..3].
glm::dvec4 foldCubeToTet(glm::dvec3 s);

}  // namespace tetraprobe::occlusion_detail
