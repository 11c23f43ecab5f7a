// Build side of per-tet probe occlusion (issue #6, light leaking): chooses per tet nothing, up to three
// splitting planes, or four 16-texel shadow maps, checked against visibility rays. Links Embree through
// SceneTracer (no Embree type here). Runtime data and evaluation: tetraprobe/runtime/occlusion.h;
// data layout and selection rule: docs/occlusion.md.
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "tetraprobe/bake/tracer.h"
#include "tetraprobe/runtime/level.h"
#include "tetraprobe/runtime/occlusion.h"

namespace tetraprobe {

enum class OcclusionMode {
  kAuto,        // per tet, the cheapest representation that agrees with the rays (see buildOcclusion)
  kNone,        // no occlusion data at all (empty LevelOcclusion)
  kPlanes,      // every tet with geometry gets planes (the best-agreeing count of 1..3)
  kShadowMaps,  // every tet with geometry gets shadow maps
};

// "auto", "none", "planes", "shadow-maps" -> mode; false for anything else.
bool parseOcclusionMode(const std::string& text, OcclusionMode& mode);
const char* occlusionModeName(OcclusionMode mode);

// Which surfaces are walls: those whose material transmission is at most this (scene.h). Visibility rays and
// shadow-map depths step over the others (a window pane lets its light through, which is no leak; its
// probes on both sides may interpolate across it), and they do not count as geometry cutting a tet. Alpha
// cutout holes are never walls.
inline constexpr float kOcclusionWallTransmission = 0.5f;

struct OcclusionOptions {
  OcclusionMode mode = OcclusionMode::kAuto;
  double minAgreement = 0.95;  // auto: a representation is good enough when it answers at least this
      // fraction of the tet's sampled (point, probe) visibility questions like the rays
  int volumeSamples = 32;   // stratified points inside each tet with geometry (no normal, no bias)
  int surfaceSamples = 32;  // points on the geometry inside each tet, each tested from both sides
  // Per level probe, the probe whose SH it carries (empty: each its own). A dilated probe (bake/bake.h,
  // dilateInvalidProbes: a shell probe behind the level's walls with its nearest valid probe's SH) counts as
  // visible from a point when that source probe is, so the lookup keeps interpolating towards it rather
  // than dropping it at every surface it lies behind. Must hold level.probes.size() valid indices.
  std::vector<uint32_t> visibilitySource;
  int threads = 0;       // 0 = all cores; never changes the result
  bool progress = true;  // progress bar on a terminal
};

struct OcclusionStats {
  size_t tets = 0;
  size_t tetsWithGeometry = 0;                // tets that some triangle cuts (with positive area inside)
  size_t none = 0;                            // tets storing nothing (includes every tet without geometry)
  size_t planeTets = 0;                       // tets storing planes
  size_t planeTetsByCount[4] = {0, 0, 0, 0};  // [1..3]: tets with that many planes
  size_t shadowMapTets = 0;
  size_t planes = 0;             // OcclusionPlane records
  size_t bytes = 0;              // LevelOcclusion::bytes() of the result
  size_t belowMinAgreement = 0;  // tets with geometry whose stored data misses options.minAgreement
  uint64_t answers = 0;          // sampled (point, probe) visibility answers checked, over tets with geometry
  uint64_t agreeing = 0;         // of those, answered like the rays by the stored data (visibility > 0.5)
  uint64_t leaking = 0;          // of those, rays say occluded but the stored data says visible
  uint64_t blackouts = 0;        // samples that see a probe by rays but are sent to the fallback by the data
  uint64_t rays = 0;             // rays traced
  uint64_t surfaceAnswers = 0;   // the part of `answers` asked at points on the geometry (normal-biased)
  uint64_t surfaceAgreeing = 0;  // of those, answered like the rays
  double agreement = 1.0;        // agreeing / answers (1 when nothing was checked)
  double surfaceAgreement = 1.0;  // surfaceAgreeing / surfaceAnswers (1 when nothing was checked)
  double seconds = 0.0;
};

// Builds the occlusion data of `level` against the geometry of `tracer` (world frame; level positions are
// local, world = level.origin + local). Deterministic for any options.threads.
//
// Per tet: the triangles cutting it are clipped to it (the segment from a point in the tet to one of its
// probes stays inside the convex tet, so only geometry inside can occlude: a tet without any stores nothing,
// exactly). Otherwise options.volumeSamples points inside and options.surfaceSamples points on the clipped
// geometry (each from both sides, normal-biased as at run time) are answered by rays to the four probes, and
// in auto mode the first candidate that answers at least options.minAgreement of them like the rays wins, in
// order of cost: none (8 bytes), 1, 2, 3 planes (8 + 16 per plane), shadow maps (8 + 64). When none
// reaches it, the best-agreeing one wins (ties: the cheaper). Planes come from the clipped triangles
// clustered by plane, added greedily (among the 8 largest clusters, the one agreeing most); each cell's
// visible-probe mask is the majority answer of the samples in it. Shadow maps trace the 15 lattice vertices
// of each probe's opposite face (4x4 split). The figures in docs/occlusion.md suggest minAgreement 0.98.
//
// The result is empty (nothing stored) when no tet needs data or mode is kNone. Throws InputError for an
// invalid level (validateLevel), minAgreement outside [0, 1], negative sample counts, or more data than the
// 28-bit offsets address.
//
// `cache` (optional, see OcclusionCache): per-tet results of the previous call with the same cache, reused for
// the tets that call had; the result and stats are then the same, bit for bit, as without a cache.
class OcclusionCache;
LevelOcclusion buildOcclusion(const SceneTracer& tracer, const Level& level, const OcclusionOptions& options,
                              OcclusionStats* stats = nullptr, OcclusionCache* cache = nullptr);

// What buildOcclusion worked out per tet, kept for the next call on a grown level (the bake's hole and
// refinement rounds append probes and tetrahedralize again; most tets come back unchanged, with the same four
// probes in the same canonical order). A tet's result depends only on its four probes' positions and
// visibility sources, the geometry and the options, so a tet whose four probe indices match a tet of the
// previous call is not worked out again. The cache checks that it may: it is cleared when the level's
// probes are not the previous call's with probes appended (a position or a visibility source changed), or
// when the tracer, the level's origin or the options that decide a tet's data differ. After each call it
// holds that call's tets only (memory: the level's tets with geometry, about 150 bytes each).
class OcclusionCache {
 public:
  OcclusionCache();
  ~OcclusionCache();
  OcclusionCache(const OcclusionCache&) = delete;
  OcclusionCache& operator=(const OcclusionCache&) = delete;
  size_t reused() const;    // tets the last call took from the cache
  size_t computed() const;  // tets the last call worked out

 private:
  friend LevelOcclusion buildOcclusion(const SceneTracer&, const Level&, const OcclusionOptions&,
                                       OcclusionStats*, OcclusionCache*);
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace tetraprobe
