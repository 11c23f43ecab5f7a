// Delaunay tetrahedralization of probe positions, and the per-tet records the runtime reads.
// Build side (links CGAL, GPL): no CGAL type appears in this header.
#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include <glm/vec3.hpp>

#include "tetraprobe/runtime/level.h"

namespace tetraprobe {

struct TetMesh {
  // Vertex indices into the input points, positively oriented (orient3d(v0,v1,v2,v3) > 0), where
  // orient3d = det[v1-v0 | v2-v0 | v3-v0]: right-handed, positive signed volume, CGAL::orientation ==
  // POSITIVE (the opposite sign of Shewchuk's orient3d; det[P0-P3 | P1-P3 | P2-P3] of level.h's Tet is
  // negative). Canonical: each tet is the even permutation with its smallest index first and its
  // second-smallest second. Tets are in Morton order of their centroids (spatially coherent walks on the CPU
  // and GPU), ties in order of those tuples.
  std::vector<std::array<int32_t, 4>> tets;
  // neighbours[t][i]: the tet sharing the face opposite tets[t][i], or -1 on the convex hull.
  std::vector<std::array<int32_t, 4>> neighbours;
};

// Delaunay tetrahedralization with exact predicates (CGAL, EPICK). Deterministic: the same points in the same
// order give the same mesh. Throws InputError naming the problem for fewer than 4 points, non-finite
// coordinates, exact duplicates, or points that are all coplanar/collinear.
TetMesh tetrahedralizeDelaunay(const std::vector<glm::dvec3>& points);

// TetGen 1.5 backend (AGPL, build side). Stage 1: Delaunay of `points` (switches "Qn"). Stage 2, only when
// `refine` is true: quality refinement of that mesh ("rYq<radiusEdge>/<minDihedralDeg>Qn", hull faces kept
// unsplit, at most `maxSteiner` new points, -1 = no limit, 0 = none: TetGen then only improves the mesh by
// flips, and the result is a valid but no longer Delaunay mesh), whose Steiner points are appended after the
// input points. (TetGen's `q` on a bare point set returns an empty mesh, hence the two stages.) The mesh is
// in the same convention as tetrahedralizeDelaunay() (positively oriented, canonical, Morton order,
// neighbours) over `points` + steiner. Deterministic. Throws InputError for the same degenerate inputs as
// tetrahedralizeDelaunay() (same messages, prefix "tetrahedralize (tetgen)"); TetGen's own failures (its int
// error codes; TETLIBRARY is defined so it never calls exit()) become InputError naming the code.
struct TetGenOptions {
  bool refine = false;
  double radiusEdge = 2.0;       // q: maximum radius-edge ratio
  double minDihedralDeg = 10.0;  // q: minimum dihedral angle, degrees
  int maxSteiner = -1;
};
struct TetGenResult {
  TetMesh mesh;
  std::vector<glm::dvec3> steiner;  // added points; mesh index points.size() + i is steiner[i]
};
TetGenResult tetrahedralizeTetGen(const std::vector<glm::dvec3>& points, const TetGenOptions& options = {});

// Runtime tet records (tetraprobe::Tet: probes and neighbours; the runtime derives weights from the probe
// positions) with positions taken relative to `origin`. One record per mesh tet, same order. Throws
// InputError naming the tet and its probes when its volume is zero or not finite in double, or when two of its probes collapse to one float position once taken
// relative to `origin` (glm::vec3(point - origin), as Level::probes stores them): near-duplicates such as
// 1e-9 m apart at 1 m from `origin` or 1 cm apart at 1000 km. The runtime's exact weights come from those
// float positions, so such a tet would get equal weights (query.h). Tets flat or inverted in float without a
// collapse (a lattice face's four probes, coplanar but for double rounding) are kept; slivers that stay
// positive in float are kept however thin.
std::vector<Tet> buildTetRecords(const std::vector<glm::dvec3>& points, const TetMesh& mesh,
                                 const glm::dvec3& origin);

}  // namespace tetraprobe
