// Filler probes where the Delaunay tets of the placed probes are slivers (Valient 2014). Build side.
#pragma once

#include <functional>
#include <vector>

#include <glm/vec3.hpp>

#include "tetraprobe/tetra/placement.h"
#include "tetraprobe/tetra/quality.h"
#include "tetraprobe/tetra/tetrahedralize.h"

namespace tetraprobe {

enum class TetraBackend { kCgal, kTetGen };

struct FillerOptions {
  TetraBackend backend = TetraBackend::kCgal;
  double minDihedralDeg = 10.0;   // tets below this are slivers to fix
  int rounds = 3;                 // CGAL: re-tetrahedralizations at most
  double tetgenRadiusEdge = 1.4;  // TetGen: radius-edge bound of the refinement (slivers pass any bound;
                                  // a tight one adds points where they would form)
  bool snapToLattice = true;      // move each candidate to the nearest point of the lattice
                                  // (local spacing) * Z^3 when that stays near the tet (voxel placement)
  double minDistance = 0.5;       // a candidate closer than this x its spacing to a probe (or an earlier
                                  // candidate) is skipped
};

struct FillerResult {
  TetMesh mesh;               // final mesh over probes.positions (after fillers were appended)
  MeshQuality before, after;  // before: the mesh of the probes as given
  size_t added = 0;           // filler probes appended (kind kFiller)
  size_t rejected = 0;        // candidates dropped by the inside test or as near-coincident
  int rounds = 0;
};

// CGAL: tetrahedralize; for every interior tet (no hull face: hull slivers cover concavities of the probe
// cloud, and a point inside them only makes more) with min dihedral < minDihedralDeg take its circumcentre,
// or its centroid when the circumcentre lies farther than the tet's longest edge from the centroid; skip
// candidates within minDistance x max(local spacings) of a probe or an earlier candidate (mergeProbes' rule);
// `inside` (may be empty) rejects the rest that are in geometry; append and re-tetrahedralize, for at most
// `rounds` rounds or until a round adds nothing; a round that makes the worst min dihedral worse (or leaves
// it and does not reduce the sliver count) is undone and ends the loop, so `after` is never worse than
// `before`. The candidate's spacing is the mean spacing of the tet's corners. TetGen: one TetGen Delaunay +
// quality refinement (q with tetgenRadiusEdge / minDihedralDeg, hull kept); the Steiner points are the
// candidates (same inside/near filtering); the final mesh is TetGen's refinement of all kept probes without
// Steiner points (flips only: valid, positively oriented, not necessarily Delaunay); when its worst min
// dihedral is below that of the plain Delaunay mesh, the fillers are dropped again. Deterministic. Throws
// what the tetrahedralizers throw.
FillerResult addSliverFillers(
    PlacedProbes& probes, const FillerOptions& options,
    const std::function<std::vector<uint8_t>(const std::vector<glm::dvec3>&)>& inside);

}  // namespace tetraprobe
