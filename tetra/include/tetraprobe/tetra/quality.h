// Shape quality of tetrahedra: what decides whether barycentric interpolation over a tet is well behaved.
// Build side; pure geometry (no CGAL).
#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include <glm/vec3.hpp>

#include "tetraprobe/tetra/tetrahedralize.h"

namespace tetraprobe {

struct TetQuality {
  double minDihedralDeg = 0.0;  // smallest of the six interior dihedral angles, degrees (regular: 70.53)
  double radiusEdge = 0.0;      // circumradius / shortest edge (regular: 0.612; slivers can stay low!)
  // Condition number of the barycentric matrix A = [P0-P3 | P1-P3 | P2-P3] in the Frobenius norm,
  // ||A|| ||A^-1|| / 3: 1 for a right-angled corner tet with equal legs at P3, sqrt(13.5) / 3 = 1.22 for a
  // regular tet; grows without bound as the tet flattens.
  // Infinity for a degenerate tet.
  double condition = 0.0;
};

// Quality of one tet given its corners (any orientation). Zero-volume tets give minDihedral 0 and
// radiusEdge / condition = +infinity.
TetQuality tetQuality(const glm::dvec3& p0, const glm::dvec3& p1, const glm::dvec3& p2, const glm::dvec3& p3);

struct MeshQuality {
  double worstMinDihedralDeg = 0.0;  // min over tets of minDihedralDeg (0 for an empty mesh)
  double meanMinDihedralDeg = 0.0;
  double worstRadiusEdge = 0.0;  // max over tets
  double worstCondition = 0.0;   // max over tets
  // histogram[b]: tets whose minimum dihedral is in [5b, 5b+5) degrees, b = 0..14 (bin 14 holds >= 70).
  std::array<uint64_t, 15> minDihedralHistogram{};
  size_t tetsBelow10Deg = 0;  // min dihedral < 10 degrees (the filler threshold)
};

MeshQuality meshQuality(const std::vector<glm::dvec3>& points, const TetMesh& mesh);

}  // namespace tetraprobe
