// The last sliver pass of a bake: after occlusion-hole and refinement probes were appended to a mesh whose
// worst tet the filler already bounded, bring the worst tet back to that bound. Build side.
#pragma once

#include <cstddef>
#include <cstdint>
#include <functional>
#include <utility>
#include <vector>

#include <glm/vec3.hpp>

#include "tetraprobe/tetra/filler.h"
#include "tetraprobe/tetra/quality.h"
#include "tetraprobe/tetra/tetrahedralize.h"

namespace tetraprobe {

struct FinalSliverOptions {
  TetraBackend backend = TetraBackend::kCgal;  // Delaunay of either backend (no TetGen refinement)
  double targetDeg = 0.0;    // tets whose min dihedral is below this are slivers (degrees): the worst tet of
                             // the mesh before the late probes were appended
  size_t firstLate = 0;      // points [firstLate, n) are the late probes; only they (and the pass's own
                             // fillers) are ever removed
  size_t maxFillers = 0;     // filler probes the pass may add in all (each one costs a probe bake)
  int fillerRounds = 2;      // re-tetrahedralizations spent on fillers at most
  double minDistance = 0.5;  // a filler closer than this x its spacing to a probe is skipped (mergeProbes)
  int nudgeRounds = 0;       // re-tetrahedralizations spent moving late corners off their slivers (step 1b)
  double nudgeFraction = 0.15;  // a move's length: this x the mean edge of the corner's slivers ...
  double maxNudge = 0.125;      // ... at most this x the corner's spacing
};

struct FinalSliverResult {
  MeshQuality before, after;      // before: Delaunay of the points as given; after: of the result
  std::vector<size_t> removed;    // indices into the given points, ascending (all >= firstLate)
  std::vector<glm::dvec3> added;  // fillers, appended after the kept points in this order
  std::vector<std::pair<size_t, glm::dvec3>> moved;  // kept late points that step 1b moved: (index into the
                                                     // given points, new position), ascending by index
  TetMesh mesh;                                      // Delaunay of kept points (given order) then `added`
  size_t rejected = 0;    // filler candidates dropped (inside geometry, near a probe, budget)
  int fillerRounds = 0;   // filler rounds kept
  int removalRounds = 0;  // re-tetrahedralizations spent on removals
  int nudgeRounds = 0;    // move rounds kept (step 1b)
};

// Tetrahedralizes `points` (Delaunay, options.backend). When its worst min dihedral is below targetDeg:
// (1) up to fillerRounds rounds of fillers: the circumcentre (centroid when the circumcentre is farther than
// the longest edge from the centroid) of each interior tet (no hull face) below targetDeg, with the tet's
// mean corner spacing (`spacing`, one per point, metres), filtered as addSliverFillers does (merge tolerance
// minDistance x spacing, then `inside`, which may be empty), at most maxFillers in all, in tet order; a round
// is kept only when it lowers the number of tets below targetDeg, else undone and the loop ends. (1b) Up to
// nudgeRounds rounds of moves: the removable corners step 2 would pick (its greedy cover) are moved instead,
// each away from the faces opposite it in its slivers (the sum of those faces' unit normals towards it, so the
// slivers gain height) by nudgeFraction x the slivers' mean edge, at most maxNudge x its spacing; moves that
// `inside` vetoes are skipped; a round is kept only when it lowers the number of tets below targetDeg, else
// undone and the loop ends. A moved probe must be traced again at its new position (the caller's). (2) While a
// tet is below targetDeg: removable corners (late probes and fillers of step 1) of those tets are removed, a
// greedy cover (the corner of the most such tets first, ties to the highest index, until each such tet with
// a removable corner lost one), and the points tetrahedralized again; ends when no tet is below targetDeg
// or none of them has a removable corner. With CGAL's Delaunay (symbolic perturbation) every tet whose corners
// are all earlier points is a tet of the earlier points' own Delaunay mesh, so when targetDeg is that
// mesh's worst min dihedral, step 2 always reaches it: after.worstMinDihedralDeg >= targetDeg. Deterministic
// (sequential, the same input gives the same result). Throws what the tetrahedralizers throw.
FinalSliverResult fixFinalSlivers(
    const std::vector<glm::dvec3>& points, const std::vector<double>& spacing,
    const FinalSliverOptions& options,
    const std::function<std::vector<uint8_t>(const std::vector<glm::dvec3>&)>& inside);

}  // namespace tetraprobe
