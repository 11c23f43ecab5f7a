// Tet shape measures: minimum dihedral angle (from outward face normals), radius-edge ratio (circumradius
// over shortest edge; Shewchuk 2002, "What is a good linear element?") and the Frobenius condition number
// of the barycentric matrix [P0-P3 | P1-P3 | P2-P3] that the runtime inverts (Cupisz 2012).
#include "tetraprobe/tetra/quality.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>

#include <glm/geometric.hpp>
#include <glm/mat3x3.hpp>
#include <glm/matrix.hpp>

namespace tetraprobe {
namespace {

double frobenius(const glm::dmat3& m) {
  double s = 0.0;
  for (int c = 0; c < 3; ++c)
    for (int r = 0; r < 3; ++r) s += m[c][r] * m[c][r];
  return std::sqrt(s);
}

}  // namespace

TetQuality tetQuality(const glm::dvec3& p0, const glm::dvec3& p1, const glm::dvec3& p2,
                      const glm::dvec3& p3) {
  const glm::dvec3 p[4] = {p0, p1, p2, p3};
  constexpr double kInf = std::numeric_limits<double>::infinity();
  TetQuality q;
  const glm::dvec3 a = p1 - p0, b = p2 - p0, c = p3 - p0;
  const double det = glm::dot(a, glm::cross(b, c));  // 6 x signed volume
  double shortest = kInf;
  for (int i = 0; i < 4; ++i)
    for (int j = i + 1; j < 4; ++j) shortest = std::min(shortest, glm::length(p[j] - p[i]));
  if (!(std::abs(det) > 0.0) || !std::isfinite(det)) {
    q.minDihedralDeg = 0.0;
    q.radiusEdge = kInf;
    q.condition = kInf;
    return q;
  }
  // Outward unit normal of the face opposite vertex k.
  glm::dvec3 n[4];
  for (int k = 0; k < 4; ++k) {
    const glm::dvec3 &u = p[(k + 1) % 4], &v = p[(k + 2) % 4], &w = p[(k + 3) % 4];
    glm::dvec3 m = glm::cross(v - u, w - u);
    if (glm::dot(m, p[k] - u) > 0.0) m = -m;
    n[k] = glm::normalize(m);
  }
  double minAngle = std::numbers::pi;
  for (int k = 0; k < 4; ++k)
    for (int l = k + 1; l < 4; ++l) {
      // Interior dihedral at the edge shared by faces k and l: pi minus the angle between outward normals.
      const double cosine = std::clamp(glm::dot(n[k], n[l]), -1.0, 1.0);
      minAngle = std::min(minAngle, std::numbers::pi - std::acos(cosine));
    }
  q.minDihedralDeg = minAngle * 180.0 / std::numbers::pi;
  const glm::dvec3 centre = (glm::dot(a, a) * glm::cross(b, c) + glm::dot(b, b) * glm::cross(c, a) +
                             glm::dot(c, c) * glm::cross(a, b)) /
                            (2.0 * det);
  q.radiusEdge = glm::length(centre) / shortest;
  const glm::dmat3 m(p0 - p3, p1 - p3, p2 - p3);
  q.condition = frobenius(m) * frobenius(glm::inverse(m)) / 3.0;
  if (!std::isfinite(q.condition)) q.condition = kInf;
  return q;
}

MeshQuality meshQuality(const std::vector<glm::dvec3>& points, const TetMesh& mesh) {
  MeshQuality mq;
  if (mesh.tets.empty()) return mq;
  mq.worstMinDihedralDeg = 180.0;
  double sum = 0.0;
  for (const auto& t : mesh.tets) {
    const TetQuality q =
        tetQuality(points[size_t(t[0])], points[size_t(t[1])], points[size_t(t[2])], points[size_t(t[3])]);
    mq.worstMinDihedralDeg = std::min(mq.worstMinDihedralDeg, q.minDihedralDeg);
    mq.worstRadiusEdge = std::max(mq.worstRadiusEdge, q.radiusEdge);
    mq.worstCondition = std::max(mq.worstCondition, q.condition);
    sum += q.minDihedralDeg;
    const size_t bin = std::min<size_t>(size_t(q.minDihedralDeg / 5.0), mq.minDihedralHistogram.size() - 1);
    ++mq.minDihedralHistogram[bin];
    if (q.minDihedralDeg < 10.0) ++mq.tetsBelow10Deg;
  }
  mq.meanMinDihedralDeg = sum / double(mesh.tets.size());
  return mq;
}

}  // namespace tetraprobe
