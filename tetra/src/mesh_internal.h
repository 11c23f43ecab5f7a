// Internal to the tetra module: input validation and the deterministic extraction shared by the CGAL and
// TetGen backends (canonical even permutation per tet, Morton order of centroids, neighbour renumbering).
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include <glm/vec3.hpp>

#include "tetraprobe/tetra/tetrahedralize.h"

namespace tetraprobe::detail {

// One extracted tet: vertices and neighbours in lockstep (n[i] is across the face opposite v[i], -1 = hull).
struct RawTet {
  std::array<int32_t, 4> v;
  std::array<int32_t, 4> n;
};

std::string describe(const glm::dvec3& p);

// Throws InputError (prefixed by `who`) for fewer than 4 points, more than INT32_MAX, non-finite coordinates
// or exact duplicates, naming the offending probe indices.
void validatePoints(const std::vector<glm::dvec3>& points, const std::string& who);

// Canonicalizes each (positively oriented) raw tet, sorts by the Morton code of the centroid (ties by vertex
// tuple) and renumbers the neighbours. Raw neighbour indices refer to positions in `raw`.
TetMesh finalizeMesh(const std::vector<glm::dvec3>& points, std::vector<RawTet> raw);

}  // namespace tetraprobe::detail
