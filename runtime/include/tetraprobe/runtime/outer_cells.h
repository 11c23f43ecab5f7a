// Outer cells: a continuous answer outside the probe hull (Cupisz, GDC 2012; docs/level_format.md 'OUTC').
// Each hull triangle P0P1P2 is extruded along unit vertex normals N0, N1, N2; a point X outside the hull lies
// on the extruded triangle Q_i(t) = P_i + t N_i for the smallest t >= 0 solving
//   det[A + tA', B + tB', (X - P2) - tN2] = 0,   A = P0-P2, A' = N0-N2, B = P1-P2, B' = N1-N2,
// and is interpolated with the triangle barycentrics of X in Q0Q1Q2. At t = 0 those are the hull tet's
// barycentrics (weight 0 on the tet's fourth probe), so the field is continuous across the hull boundary, and
// neighbouring cells share their extruded edges, so it is continuous across outer cells.
// Permissive: standard library and GLM only.
#pragma once

#include <cstdint>
#include <vector>

#include <glm/vec3.hpp>

#include "tetraprobe/runtime/level.h"

namespace tetraprobe {

// Builds one outer cell per hull face (tet face with neighbour -1) of `tets` over `probes` (local frame):
// outward winding, angle-weighted unit vertex normals (the same vector for a probe in every cell naming it),
// links across hull edges (-1 where a hull edge does not have exactly two hull faces), sorted by (tet, face).
// Deterministic (a pure function of its input). O(tets log tets); allocates the result.
std::vector<OuterCell> buildOuterCells(const std::vector<glm::vec3>& probes, const std::vector<Tet>& tets);

// Index of the outer cell on face `face` (0..3, the face opposite tet.v[face]) of hull tet `tet`, or -1.
// Binary search over the (tet, face) order buildOuterCells produces.
int32_t findOuterCell(const std::vector<OuterCell>& cells, int32_t tet, int32_t face);

// Coefficients (c[3] t^3 + c[2] t^2 + c[1] t + c[0]) of det[A + tA', B + tB', (X - P2) - tN2] for cell
// `cell`, local point x (metres), evaluated in double. c[0] > 0 when x is outside the hull face.
void outerCellCubic(const OuterCell& cell, const std::vector<glm::vec3>& probes, const glm::dvec3& x,
                    double c[4]);

// Smallest root t >= 0 of c[3] t^3 + c[2] t^2 + c[1] t + c[0] (roots within -1e-12 * scale of 0 count as
// 0), where `scale` > 0 is the problem's length scale (|X - P| + edge length): it decides which coefficients
// are negligible. The degree is reduced explicitly (cubic -> quadratic -> linear -> constant) when the
// leading term is below 1e-13 of the others at t = scale; the cubic's roots are isolated between the
// critical points and refined by safeguarded Newton-bisection; the quadratic uses the cancellation-free
// formula. Returns false (and leaves *t alone) when there is no such root in [0, 1e4 * scale]. Never NaN.
// Solved in tau = t / scale (coefficients c[k] / scale^(3-k)), so no power of a far point's t overflows.
bool smallestNonNegativeRoot(const double c[4], double scale, double* t);

struct OuterWeights {
  bool valid = false;  // a root t >= 0 exists and the extruded triangle is not degenerate
  double t = 0.0;      // extrusion parameter (metres along the unit normals)
  double b[3] = {};    // barycentrics of x in the extruded triangle, for cell.v[0..2]; sum to 1
};

// The extrusion parameter and raw barycentrics of local point x in `cell` (may be negative outside the
// cell). When there is no root (`valid` false), b holds the barycentrics of x's projection onto the hull
// face's plane, to steer a walk.
OuterWeights outerCellWeights(const OuterCell& cell, const std::vector<glm::vec3>& probes,
                              const glm::dvec3& x);

}  // namespace tetraprobe
