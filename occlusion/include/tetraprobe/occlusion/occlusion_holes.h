// Occlusion holes: surface points whose tet's occlusion data hides all four of its probes, so the lookup can
// only fall back (runtime/occlusion.h, occludedIrradiance) and draws a dark, hard-edged polygon. Each such
// point gets a new probe in front of it, on its own side of the geometry, so that once the level is
// tetrahedralized again the point lies in a tet with a probe it sees. Build side.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include <memory>

#include <glm/vec3.hpp>

#include "tetraprobe/bake/bake.h"
#include "tetraprobe/bake/tracer.h"
#include "tetraprobe/runtime/level.h"
#include "tetraprobe/runtime/query.h"

namespace tetraprobe {

struct OcclusionHoleOptions {
  double spacing = 1.0;  // probe spacing near geometry, metres: new probes sit at most spacing / 2 in
                         // front of their point, one per spacing / 2 cell
  double pointsPerSquareMetre = 4.0;  // surface points checked, per m^2 of surface x (1 m / spacing)^2
  // Bounds on that count. maxPoints 0: none (a level twice the surface is checked at twice the points, so
  // a town gains from the rounds as a room does), up to kMaxHolePoints, which keeps the draw in memory.
  int minPoints = 4096, maxPoints = 0;
  uint64_t seed = 0x401e5ull;  // surface points (sampleSurfacePoints)
  // Propose only for hole points whose fallback does not already answer with a probe they see: skipped are
  // points whose fallback probe (the one occludedIrradiance leans on: the largest u_i max(front_i,
  // kOcclusionBehindShare)) lies in front, is reached by a ray, and is in no channel brighter than the
  // unoccluded blend that caps the fallback (the bake's --hole-rule unseen; docs/accuracy.md has the trade).
  bool onlyUnseen = false;
  bool propose = true;  // false: count the hole points only (the bake's check of the finished level)
  // Judge a hole by the lookup's answer (ShadeRecord::fallback: the visibility after the blend over the
  // probes' stars hides every probe) instead of the tet's own data (ownFallback): the bake's last round,
  // after refinement, aimed at what a viewer would see fall back.
  bool lookupOnly = false;
  bool keepLookupFallbacks = false;  // fill OcclusionHoles::lookupFallbacks (the bake's final check)
  // Proposals sit at most this far in front of their point (ProbesInFront's maxOffset; 0: spacing / 2).
  double maxOffset = 0.0;
};

inline constexpr int kMaxHolePoints = 1 << 25;  // 33.5 M points, about 1.3 GB of SurfacePoint

struct OcclusionHoles {
  size_t pointsChecked = 0;  // surface points drawn (on their open side)
  size_t holePoints = 0;     // of those, points that see none of their tet's probes (fallback share > 0;
                             // with lookupOnly, by the lookup's answer)
  size_t seenPoints = 0;     // of those, with onlyUnseen: points left alone, their fallback probe seen
  size_t lookupFallbackPoints = 0;  // of pointsChecked, points whose run-time answer falls back: the
                                    // visibility after the face blend (lookupVisibility, face_blend.h) hides
                                    // every probe; fewer than holePoints, which judge the tet's data alone
  std::vector<glm::dvec3> probes;   // new probe positions, world metres, deterministic order
  std::vector<SurfacePoint> lookupFallbacks;  // with keepLookupFallbacks: those points, in draw order
};

// New probes in front of surface points, shared by hole filling and error-driven refinement (eval/refine.h):
// a proposal for point p with unit normal n sits at p + n x d, d = min(maxOffset, half the free distance
// along n) (maxOffset <= 0: spacing / 2, hole filling's), so it stays on the point's side of nearby geometry; refused when d < spacing / 50 (no room), when
// an earlier proposal took its spacing / 2 grid cell, or when a probe of `level` or an earlier proposal lies
// within spacing / 10 (the placement's merge distance). Deterministic: proposals are judged in call order.
class ProbesInFront {
 public:
  ProbesInFront(const SceneTracer& tracer, const Level& level, double spacing, double maxOffset = 0.0);
  ~ProbesInFront();
  // True (and the position appended to probes()) when the proposal for the point is taken.
  bool propose(const glm::dvec3& point, const glm::vec3& normal);
  const std::vector<glm::dvec3>& probes() const { return probes_; }

 private:
  struct Grids;
  const SceneTracer& tracer_;
  double spacing_;
  double maxOffset_;
  std::vector<glm::dvec3> probes_;
  std::unique_ptr<Grids> grids_;
};

// The share of the all-occluded fallback at a world point with normal `normal` by its tet's own occlusion
// data (ShadeRecord::ownFallback of query.explain, runtime/shade.h; before the face blend): 0 where the point
// sees some of its tet's probes. 0 for a level without occlusion, a point with no tet, or a `query` (of
// `level`) with occlusion off.
float occlusionFallbackShare(const Level& level, const ProbeQuery& query, const glm::dvec3& point,
                             const glm::vec3& normal);

// Finds the holes of `level` (which must store occlusion; none: an empty result) at area-uniform surface
// points and proposes a probe in front of each hole point (ProbesInFront, in draw order). Deterministic. Throws InputError for a
// non-positive or non-finite spacing.
OcclusionHoles findOcclusionHoles(const SceneTracer& tracer, const Level& level,
                                  const OcclusionHoleOptions& options);

}  // namespace tetraprobe
