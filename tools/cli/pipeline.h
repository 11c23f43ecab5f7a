// The bake pipeline: scene -> probe placement -> SH bake -> tetrahedralization -> Level. Shared by
// `tetraprobe bake` and the end-to-end tests.
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "tetraprobe/bake/bake.h"
#include "tetraprobe/eval/evaluate.h"
#include "tetraprobe/eval/refine.h"
#include "tetraprobe/eval/sh_fit.h"
#include "tetraprobe/occlusion/build_occlusion.h"
#include "tetraprobe/runtime/level.h"
#include "tetraprobe/scene/scene.h"

namespace tetraprobe::cli {

// Every option of a bake. The default member values are `tetraprobe bake`'s defaults, stated here only: the
// CLI's option table and --help (pipeline_options.h), `eval --sweep` and the level's generator string all
// start from a default-constructed PipelineOptions. (The library structs inside keep their own defaults for
// their other callers; those the bake changes are set below.)
struct PipelineOptions {
  double spacing = 0.0;     // finest voxel / grid spacing, metres; <= 0: auto (autoSpacing(scene))
  std::string probesCsv;    // user probes (kept exactly; never moved or merged away)
  std::string importShCsv;  // probes and their SH from another baker (bake/sh_csv.h); no path tracing
  // bake.shOrder 1 also truncates imported SH. Adaptive sampling to 2 % noise (at least 256, at most 8192
  // paths a probe, unbounded bounces), a 16M-path budget for the whole bake, default content, L2, seed 1.
  BakeOptions bake = [] {
    BakeOptions b;
    b.bounces = kUnboundedBounces;
    b.samplesPerProbe = 256;
    b.targetRelError = 0.02;
    b.maxSamplesPerProbe = 8192;
    b.pathBudget = 16000000;
    b.content = kContentDefault;
    b.seed = 1;
    b.shOrder = 2;
    b.threads = 0;
    return b;
  }();
  // With adaptive sampling and a path budget, true (the default): pass 2 stops each probe at half of
  // maxSamplesPerProbe, and the budget's pass, over the finished level, spends at least what the flat cap
  // would have, shared by the error (BakeOptions::pass2MaxSamples), with one lit map for every call of the
  // bake so that lit-patch histograms go on from pass to pass (BakeOptions::litVoxel); both set by
  // buildLevel. false: the flat cap first, then the budget beyond it.
  bool shareCaps = true;
  DeringOptions dering;  // auto; applied to baked and imported SH alike

  // Placement (tetra/placement.h): "voxel" (adaptive voxels + push-out + merge + fillers; the default),
  // "grid" (regular grid, inside probes rejected; for comparison), "none" (user probes only).
  std::string placement = "voxel";
  double maxSpacing = 10.0;    // voxel: coarsest open-space cell, metres
  double fillerSpacing = 4.0;  // voxel: open-space filler lattice, metres (0 = none)
  // voxel: shell probes (tetra/placement.h, placeShellProbes) on the level's bounds grown outward, at this
  // step in metres within two steps of a surface, maxSpacing elsewhere; < 0 = auto (the spacing), 0 = none.
  // Shell probes that fail the inside rule are dilated.
  double shellSpacing = -1.0;
  std::string tetra = "cgal";  // "cgal" | "tetgen"

  // Per-tet occlusion against light leaking, built after the SH bake and stored in the level
  // (occlusion/build_occlusion.h). occlusion.mode kNone stores nothing; threads and progress follow `bake`.
  // Auto, and auto takes the cheapest representation that answers 98 % of the sampled rays alike.
  OcclusionOptions occlusion = [] {
    OcclusionOptions o;
    o.mode = OcclusionMode::kAuto;
    o.minAgreement = 0.98;
    return o;
  }();
  // Rounds of occlusion-hole filling (occlusion/occlusion_holes.h) after the occlusion stage: surface points
  // that see none of their tet's probes get a probe in front of them, then the level is tetrahedralized,
  // baked (new probes only) and occluded again; stops early when none are left. 0 = none; needs occlusion.
  // Not for imported SH. With user probes alone (placement "none") the CLI makes it 0 unless given
  // (pipeline_options.h).
  int holeRounds = 3;
  bool holesOnlyUnseen = false;  // OcclusionHoleOptions::onlyUnseen (--hole-rule unseen)
  // Rounds after the hole rounds and refinement (whose probes re-tetrahedralize the level and open holes of
  // their own) that add probes where the lookup's answer, after the blend over the probes' stars, still falls
  // back (OcclusionHoleOptions::lookupOnly). 0 = none; needs occlusion and hole filling (holeRounds > 0).
  // Their proposals sit at most kLookupHoleOffset x spacing in front of their point (hole rounds: half a
  // spacing), so that the new probe more often becomes a vertex of the point's tet.
  int lookupHoleRounds = 6;
  // Error-driven refinement (eval/refine.h): at most this many probes added where the lookup's error
  // against the oracle is largest, measured at refinePoints area-uniform surface points. 0 = none, < 0 =
  // auto: a quarter of the probes that are not shell probes, at least 1024. With user probes alone
  // (placement "none") the CLI makes it 0 unless given (pipeline_options.h).
  int probeBudget = -1;
  // Surface points refinement measures at (each twice: select, check); < 0 = auto (autoRefinePoints).
  int refinePoints = -1;
  // The late sliver pass (tetra/final_slivers.h) after hole and refinement probes: brings the worst tet of the
  // final mesh back to the worst before those probes (or lateMinDihedral when lower), with at most lateFillers filler probes (baked like the
  // other added probes) and then by removing the late probe of each sliver left. Off: the late probes' slivers
  // stay (the default: dropping refinement probes cost the Cornell box accuracy at its cameras, gross 0.033 ->
  // 0.039 at the 2 deg bound; docs/occlusion.md).
  bool lateSlivers = false;
  int lateFillers = 0;
  int lateNudgeRounds = 4;  // FinalSliverOptions::nudgeRounds: move late probes off slivers before dropping
  // The pass's bound, degrees: the smaller of this and the worst tet's before those probes; < 0 = auto (the
  // worst before those probes, whatever it is). 2 by default: on Veach Ajar (14.6 deg before) and the Cornell
  // box (7.2) the auto bound drops most hole and refinement probes and their accuracy with them.
  double lateMinDihedral = 2.0;
  // How far in front of its surface point a refinement probe sits at most, metres; <= 0: auto, spacing x
  // kRefineOffsetFraction (refine.h).
  double refineOffset = 0.0;

  // Probe SH fitted to the surfaces they light (eval/sh_fit.h), after the last probe is added and traced:
  // "off", "on" (kept whatever the hold-out says) or "auto" (kept only when the hold-out points' mean
  // relative error drops and their gross error does not rise). fitPoints area-uniform surface points at fitSamples reference paths each (< 0:
  // auto, kFitPointsPerProbe per probe that is not a shell probe, within [kFitPointsMin, kFitPointsMax]);
  // fitHoldout independent points score the level before and after. Not for imported SH.
  std::string fit = "auto";
  double fitLambda = 0.3;   // ShFitOptions::lambda
  double fitMaxMove = 0.3;  // ShFitOptions::maxMove
  bool fitValidate = true;  // ShFitOptions::crossValidate
  int fitPoints = -1;
  int fitSamples = 256;
  int fitHoldout = 2048;

  // Sharded bake (docs/distributed.md; bake.h, bakeProbesShard). shardCount > 0: buildLevel places the
  // probes, runs bake passes 1-2 for shard shardIndex's probes (shardOwnership), stores their states in
  // *shardOut and returns the level as it stands then (probes and tets, no SH). `merged`: every probe's
  // state from the shards replaces passes 1-2 (bakeProbesMerged); the level equals the one-process bake's.
  // shardRound 1: pass 1 of the shard's probes only (bakeProbesShardPass1); 2: passes 2 from `shardPass1`
  // (that shard's round-1 states and the floor, bakeProbesShardPass2); 0: both in one (bakeProbesShard).
  int shardIndex = 0, shardCount = 0, shardRound = 0;
  ShardBake* shardOut = nullptr;
  const ShardBake* shardPass1 = nullptr;
  const ShardBake* merged = nullptr;
  uint64_t expectedProbeCount = 0;  // with `merged` or round 2: the probe count the shards placed (checked)
};

struct PipelineStats {
  size_t gridProbes = 0;      // placed by the grid before rejection
  size_t rejectedProbes = 0;  // inside geometry
  size_t userProbes = 0;
  size_t importedProbes = 0;  // --import-sh
  BakeStats bake;             // rays and time of the path tracer (zero when the SH were imported)
  DeringStats dering;
  OcclusionStats occlusion;  // zero when occlusion.mode is kNone

  // Placement by kind (voxel placement; counts after push-out and merge) and tet quality.
  size_t surfaceProbes = 0, volumeProbes = 0, openProbes = 0, fillerProbes = 0;  // filler: lattice + sliver
  size_t sliverFillers = 0;  // of fillerProbes, added where tets were slivers
  size_t shellProbes = 0;    // on the level's grown bounds (placeShellProbes)
  size_t dilatedProbes = 0;  // shell probes outside a closed level: SH copied from the nearest valid probe
  size_t pushedProbes = 0;   // moved out of geometry or off a surface
  size_t mergedProbes = 0;   // dropped as near-coincident (tolerance 0.1 x local spacing)
  double minDihedralBeforeFiller = 0.0, minDihedral = 0.0;  // worst tet, degrees (minDihedral: final mesh)
  std::vector<uint64_t> dihedralHistogram;  // final mesh: tets per 5-degree bin of min dihedral
  std::array<size_t, 3> tetsBelow{};        // final mesh: tets under 1, 5, 10 degrees
  // The mesh before hole and refinement probes (after the fillers) and before the late sliver pass (after
  // them); the late pass's fillers and the late probes it removed.
  double minDihedralBeforeHoles = 0.0, minDihedralBeforeLate = 0.0;
  std::vector<uint64_t> dihedralHistogramBeforeLate;
  std::array<size_t, 3> tetsBelowBeforeLate{};
  // The worst tet of the final mesh, before hole and refinement probes and before the late pass: angle,
  // hull or interior, volume and its probes' kinds (why it is flat).
  std::string worstTet, worstTetBeforeHoles, worstTetBeforeLate;
  bool latePass = false;
  double lateTargetDeg =
      0.0;  // the bound it worked to  // the late pass ran (probes were added after the fillers)
  size_t lateFillers = 0, lateRemoved = 0, lateRemovedHole = 0, lateRemovedRefinement = 0;
  size_t lateMoved = 0;  // late probes moved off their slivers and traced again

  // Occlusion-hole filling, per round: surface points checked, points seeing none of their probes, probes
  // added; and after the last round, the points still falling back (measured on a fresh draw).
  struct HoleRound {
    size_t checked = 0, holes = 0, added = 0;
    size_t seen = 0;  // --hole-rule unseen: hole points left alone (their fallback probe seen by rays)
  };
  std::vector<HoleRound> holeRounds;
  std::vector<HoleRound> lookupHoleRounds;  // the rounds aimed at the lookup's fallback, after refinement
  size_t holeProbes = 0;
  size_t finalChecked = 0, finalHoles = 0;  // the finished level's (0, 0: no occlusion data)
  size_t finalLookupFallbacks = 0;          // of finalChecked, those whose run-time answer falls back
  // Of those, points no path leaves (closedTestPaths() paths found no light).
  size_t finalClosedFallbacks = 0;
  // Error-driven refinement: probes added, and the error at an independent draw of points before and after.
  size_t refineProbes = 0;
  ErrorEstimate refineBefore, refineAfter;
  // The SH fit: whether it ran and was kept, its statistics, and the hold-out points' score (shFitScore, on
  // the SH as saved: deringed and half precision) before and after.
  bool fitRan = false, fitKept = false;
  ShFitStats fit;
  ShFitScore fitHoldoutBefore, fitHoldoutAfter;

  std::vector<std::pair<std::string, double>> timings;  // stage -> seconds, in order
};

// The SH fit's automatic point count (PipelineOptions::fitPoints < 0).
// The final check's test of a fallback point for "no path leaves" (eval's noPathLeaves): this many reference
// paths, eval's default --samples, that all find no light.
inline int closedTestPaths() {
  return EvalOptions{}.samplesPerPoint;
}
inline constexpr double kLookupHoleOffset = 0.125;
inline constexpr int kFitPointsPerProbe = 6;
inline constexpr int kFitPointsMin = 2048;

// Refinement's automatic point count (--refine-points auto): the largest of kAutoRefinePointsMin, the probe
// budget and kRefinePointsPerCell points per spacing x spacing of surface (area in m^2). Refinement adds
// about 0.085 probes a traced point at every level size (docs/scaling.md), so what it gains on a part of a
// level follows the points traced there: with a count proportional to the surface every part of a large level
// is traced as densely as a small level of the same kind (one point per probe-spacing square of surface), and
// the minimum keeps a small room's estimate from resting on a few hundred points.
inline constexpr int kAutoRefinePointsMin = 2048;
inline constexpr double kRefinePointsPerCell = 1.0;
inline int autoRefinePoints(int budget, double surfaceArea, double spacing) {
  const double byArea = kRefinePointsPerCell * surfaceArea / (spacing * spacing);
  // Clamped below INT_MAX / 4: the point sets are int-sized.
  const double points = std::min(std::max({double(kAutoRefinePointsMin), double(budget), byArea}), 5.0e8);
  return int(std::llround(points));
}
inline constexpr int kFitPointsMax = 16384;

// The default finest probe spacing for `scene` (bake --spacing auto): 1 m, the scale of gameplay space, or
// for a scene whose bounds' largest extent is under 8 m the largest power of two of a metre with at least 8
// voxels along that extent (0.5, 0.25, ...; at least 1/1024 m): 1 m voxels in a 2-unit Cornell box would all
// touch geometry and place no probe. Every shared level and the bundled sample are 8 m or more (1 m).
inline constexpr double kAutoSpacingVoxels = 8.0;
double autoSpacing(const Scene& scene);

// The largest extent of `scene`'s bounds (sceneBounds), in metres; 0 without triangles.
double sceneLargestExtent(const Scene& scene);

// Runs every stage on a loaded scene (an automatic spacing resolved first, autoSpacing) and records the
// options in Level::generator (generatorString, pipeline_options.h). Throws InputError when the input cannot
// give a level (e.g. fewer than four probes survive placement).
Level buildLevel(const Scene& scene, const PipelineOptions& options, PipelineStats& stats);

}  // namespace tetraprobe::cli
