// CPU queries against a loaded level: which tet holds a point, its barycentric weights, and the
// interpolated irradiance. Permissive: standard library and GLM only. Thread-safe for concurrent const use.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include <glm/vec4.hpp>
#include <glm/vec3.hpp>

#include "tetraprobe/runtime/level.h"

namespace tetraprobe {

// A coarse uniform grid over the probe bounds (local frame) naming, per cell, a tet near the cell centre to
// start a walk from, so walks stay short. Shared by the CPU query and the GPU upload (same layout as
// shaders/tetraprobe_layout.glsl). Cell (x,y,z) is at index x + dims.x * (y + dims.y * z).
struct StartGrid {
  glm::vec3 min{0.0f};       // local frame, metres
  glm::vec3 cellSize{1.0f};  // metres
  glm::ivec3 dims{0};
  std::vector<int32_t> startTet;
};

struct Location {
  int32_t tet = -1;          // containing tet, or the hull tet the answer was taken from; -1 for an empty level
  glm::vec4 weights{0.0f};   // weights of tet.v[0..3]: non-negative, sum to 1
  bool inside = false;       // true when the point lies in the tet (within 1e-6 on each weight)
};

class ProbeQuery {
 public:
  // Keeps a reference to `level` (which must outlive the query) and builds its acceleration data.
  explicit ProbeQuery(const Level& level);

  // Locates a world-space point. `hint` is a tet to start from (for example the tet of the same object
  // last frame), or -1. Outside the probe hull the answer is defined and finite: the nearest hull tet with
  // its weights clamped to be non-negative and renormalized.
  Location locate(const glm::dvec3& world, int32_t hint = -1) const;

  // Reference answer for tests and the walk's fallback: scans every tet (O(tets)) and returns the one whose
  // smallest weight is largest (ties: lowest index), clamped and renormalized as locate() does. Inside the
  // hull it agrees with locate() (up to which of two tets sharing a face is named for a point on it); the
  // hint never changes locate()'s answer inside the hull, while outside it may pick another hull tet.
  Location bruteForceLocate(const glm::dvec3& world) const;

  // Irradiance E in W/m^2 at a world-space point on a surface with unit normal `normal`. When `tetCache` is
  // given it is read as the walk's starting hint and updated with the tet found (per-object caching).
  glm::vec3 irradiance(const glm::dvec3& world, const glm::vec3& normal, int32_t* tetCache = nullptr) const;

  // Batch form: out[i] = irradiance(world[i], normal[i]). Runs on up to `threads` threads (0 = all cores).
  void irradianceBatch(const glm::dvec3* world, const glm::vec3* normal, glm::vec3* out, size_t count,
                       int threads = 0) const;

  const Level& level() const { return level_; }
  const StartGrid& startGrid() const { return grid_; }

 private:
  const Level& level_;
  StartGrid grid_;
};

}  // namespace tetraprobe
