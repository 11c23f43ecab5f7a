// The bake pipeline, stage by stage, with timings.
#include "pipeline.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <optional>
#include <sstream>

#include <glm/common.hpp>
#include <glm/geometric.hpp>

#include "pipeline_options.h"
#include "tetraprobe/bake/sh_csv.h"
#include "tetraprobe/common/error.h"
#include "tetraprobe/common/parallel.h"
#include "tetraprobe/common/progress.h"
#include "tetraprobe/eval/refine.h"
#include "tetraprobe/occlusion/occlusion_holes.h"
#include "tetraprobe/runtime/luminance.h"
#include "tetraprobe/runtime/outer_cells.h"
#include "tetraprobe/runtime/sh_half.h"
#include "tetraprobe/scene/scene.h"
#include "tetraprobe/tetra/filler.h"
#include "tetraprobe/tetra/final_slivers.h"
#include "tetraprobe/tetra/placement.h"
#include "tetraprobe/tetra/quality.h"
#include "tetraprobe/tetra/tetrahedralize.h"

namespace tetraprobe::cli {

namespace {

// A shell lattice point within this many shell steps of a surface (by the clearance rays) keeps the fine
// shell; the box's grown bounds put shell points half a step from a surface touching them, and two steps
// keep a fine ring around whatever meets the bounds (a ground plane's edge, a roof near the top).
constexpr double kShellNearSteps = 2.0;

class StageTimer {
 public:
  explicit StageTimer(PipelineStats& stats) : stats_(stats) {}
  void mark(const std::string& stage) {
    const auto now = std::chrono::steady_clock::now();
    stats_.timings.emplace_back(stage, std::chrono::duration<double>(now - last_).count());
    last_ = now;
  }

 private:
  PipelineStats& stats_;
  std::chrono::steady_clock::time_point last_ = std::chrono::steady_clock::now();
};

// Clearance of probe positions (tetra/placement.h) from 64 rays of a fixed spherical Fibonacci set each:
// hits and back-face hits for insideByRays(), escape = mean direction of rays that escaped or hit a front
// face beyond `reach`, nearest hit and the side it faces. Per point, so any thread count gives the same.
// Only opaque surfaces count: probes may sit behind or between glass panes (which enclose nothing).
ClearanceQuery tracerClearance(const SceneTracer& tracer, int threads) {
  return [&tracer, threads](const std::vector<glm::dvec3>& pts, const std::vector<double>& reach) {
    constexpr int kRays = 64;
    std::vector<glm::vec3> dirs;
    const double golden = 3.14159265358979323846 * (3.0 - std::sqrt(5.0));
    for (int i = 0; i < kRays; ++i) {
      const double z = 1.0 - (i + 0.5) * 2.0 / kRays, r = std::sqrt(1.0 - z * z);
      dirs.emplace_back(float(r * std::cos(golden * i)), float(r * std::sin(golden * i)), float(z));
    }
    std::vector<Clearance> out(pts.size());
    parallelFor(
        pts.size(), threads,
        [&](size_t i) {
          FlushDenormalsScope ftz;
          Clearance& c = out[i];
          int hits = 0, back = 0;
          glm::dvec3 escape(0.0);
          for (const glm::vec3& d : dirs) {
            const Hit h =
                tracer.intersect(glm::vec3(pts[i]), d, 0.0f, std::numeric_limits<float>::infinity(), 0.0f);
            hits += h.hit;
            back += h.hit && !h.frontFace;
            if (!h.hit || (h.frontFace && double(h.t) > reach[i])) escape += glm::dvec3(d);
            if (h.hit && double(h.t) < c.nearest) {
              c.nearest = double(h.t);
              c.away = glm::dvec3(h.frontFace ? h.geometricNormal : -h.geometricNormal);
            }
          }
          c.inside = insideByRays(kRays, hits, back);
          if (glm::length(escape) > 0.0) c.escape = glm::normalize(escape);
        },
        64);
    return out;
  };
}

// Tets of `mesh` whose min dihedral is under 1, 5 and 10 degrees.
void tetsBelowDeg(const std::vector<glm::dvec3>& points, const TetMesh& mesh, std::array<size_t, 3>& out) {
  out = {0, 0, 0};
  for (const auto& t : mesh.tets) {
    const double d =
        tetQuality(points[size_t(t[0])], points[size_t(t[1])], points[size_t(t[2])], points[size_t(t[3])])
            .minDihedralDeg;
    out[0] += d < 1.0;
    out[1] += d < 5.0;
    out[2] += d < 10.0;
  }
}

// The worst tet of `mesh` by min dihedral: its angle, whether a face is on the hull, its volume and its
// probes' kinds, e.g. "0.000 deg, hull, 1.2e-17 m^3, shell shell shell surface".
std::string describeWorstTet(const std::vector<glm::dvec3>& points, const TetMesh& mesh,
                             const std::vector<LevelProbeKind>& kinds) {
  size_t worst = mesh.tets.size();
  double angle = 180.0;
  for (size_t t = 0; t < mesh.tets.size(); ++t) {
    const auto& v = mesh.tets[t];
    const double d =
        tetQuality(points[size_t(v[0])], points[size_t(v[1])], points[size_t(v[2])], points[size_t(v[3])])
            .minDihedralDeg;
    if (d < angle) {
      angle = d;
      worst = t;
    }
  }
  if (worst == mesh.tets.size()) return "";
  const auto& v = mesh.tets[worst];
  const auto& nb = mesh.neighbours[worst];
  const glm::dvec3 p0 = points[size_t(v[0])];
  const double volume =
      glm::dot(points[size_t(v[1])] - p0, glm::cross(points[size_t(v[2])] - p0, points[size_t(v[3])] - p0)) /
      6.0;
  std::ostringstream out;
  out.precision(3);
  out << angle << " deg, " << (std::find(nb.begin(), nb.end(), -1) != nb.end() ? "hull" : "interior") << ", "
      << volume << " m^3,";
  for (int k = 0; k < 4; ++k) {
    const size_t i = size_t(v[size_t(k)]);
    out << ' ' << (i < kinds.size() ? levelProbeKindName(kinds[i]) : "?");
  }
  return out.str();
}

}  // namespace

double sceneLargestExtent(const Scene& scene) {
  glm::vec3 lo, hi;
  sceneBounds(scene, lo, hi);
  return std::max({double(hi.x) - lo.x, double(hi.y) - lo.y, double(hi.z) - lo.z});
}

double autoSpacing(const Scene& scene) {
  const double extent = sceneLargestExtent(scene);
  double spacing = 1.0;
  if (!(extent > 0.0) || !std::isfinite(extent)) return spacing;  // no triangles: placement refuses the scene
  while (extent < kAutoSpacingVoxels * spacing && spacing > 1.0 / 1024.0) spacing *= 0.5;
  return spacing;
}

Level buildLevel(const Scene& scene, const PipelineOptions& given, PipelineStats& stats) {
  PipelineOptions options = given;
  if (!(options.spacing > 0.0)) options.spacing = autoSpacing(scene);
  StageTimer timer(stats);
  // Progress lines for the stages that have none of their own (a log's heartbeat, common/progress.h);
  // emplace() ends the previous stage first.
  std::optional<Progress> stage;
  const bool show = options.bake.progress;
  stage.emplace("bvh", 0, "", show);
  SceneTracer tracer(scene);
  timer.mark("bvh");
  stage.emplace("place", 0, "", show);

  std::vector<glm::dvec3> probes;
  std::optional<TetMesh> voxelMesh;   // voxel placement tetrahedralizes with its fillers
  std::vector<size_t> shell;          // indices of shell probes in `probes`
  std::vector<uint32_t> dilatedFrom;  // per probe, the probe whose SH it holds (after dilation)
  // The path budget's pass (BakeOptions::pathBudget, adaptive sampling) runs once, over the finished level:
  // every traced probe's state after its pass 2 is kept here, by probe index, so that the hole, refinement
  // and late probes share the budget with the probes placed first. (Spent on the first probes, as it was,
  // it left the added ones, a third to a half of a level's traced probes, at the per-probe cap: on Veach Ajar
  // their mean relative stderr was 0.09-0.21 against the first probes' 0.046.)
  const bool deferBudget =
      options.importShCsv.empty() && options.bake.targetRelError > 0.0 && options.bake.pathBudget > 0;
  // --share-caps: pass 2 stops at half the cap and the budget's pass covers what the cap would have spent
  // (and, once the probes are placed, one lit map for the whole bake: BakeOptions::litVoxel, below).
  const bool shareCaps = options.shareCaps && deferBudget;
  if (shareCaps) options.bake.pass2MaxSamples = options.bake.maxSamplesPerProbe / 2;
  std::vector<ProbeBakeState> bakeState;  // per probe; valid where hasBakeState
  std::vector<uint8_t> hasBakeState;
  double bakeFloor = 0.0;  // the first probes' floor (bakeErrorFloor), which the budget's pass measures by
  // Paths of the added probes' passes 1 and 2: outside the budget, as they were when the first call spent
  // it, so a level whose first probes used the whole budget traces as many paths as before, shared out
  // differently (one whose first probes left some gives it to the added ones).
  // (With shareCaps their passes 2 stop short of the cap, so what counts is what they would have traced
  // under it: flatCapPaths.)
  uint64_t addedPaths = 0;
  auto keepStates = [&](const ShardBake& r, size_t first, size_t count) {
    bakeState.resize(first + count);
    hasBakeState.resize(first + count, 0);
    for (size_t k = 0; k < r.probes.size(); ++k) {
      bakeState[first + r.probes[k]] = r.states[k];
      hasBakeState[first + r.probes[k]] = 1;
    }
  };
  // The SH of `at` from its passes 1 and 2: those of `given` (a merge's shard states), else traced into
  // `states` (kept by the caller for the budget's pass).
  auto bakeDeferred = [&](const std::vector<glm::dvec3>& at, const BakeOptions& bake, BakeStats& more,
                          const std::vector<uint8_t>* skip, const ShardBake* given, ShardBake& states) {
    const auto t0 = std::chrono::steady_clock::now();
    if (!given) states = bakeProbesShard(tracer, at, bake, std::vector<uint8_t>(at.size(), 1), skip);
    BakeOptions noBudget = bake;
    noBudget.pathBudget = 0;
    std::vector<ShRgb> sh = bakeProbesMerged(tracer, at, noBudget, given ? *given : states, &more, skip);
    more.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    return sh;
  };
  std::vector<LevelProbeKind> kinds;  // per probe, the stage that placed it (Level::probeKinds)
  std::vector<double> spacing;        // per probe, its local spacing (voxel placement; else --spacing)
  ProbeShTable imported;
  if (!options.importShCsv.empty()) {
    if (!options.probesCsv.empty())
      throw InputError("give either a probe CSV or an SH CSV to import, not both");
    imported = readShCsv(options.importShCsv);
    probes = imported.positions;
    kinds.assign(probes.size(), LevelProbeKind::kUser);
    stats.importedProbes = stats.userProbes = probes.size();
  } else if (options.placement == "none") {
    if (options.probesCsv.empty()) throw InputError("placement 'none' needs user probes (--probes FILE.csv)");
    probes = readProbeCsv(options.probesCsv);
    stats.userProbes = probes.size();
    kinds.assign(probes.size(), LevelProbeKind::kUser);
  } else if (options.placement == "voxel") {
    // User probes first (kept exactly), then the adaptive voxel probes; push-out, merge.
    PlacedProbes placed;
    if (!options.probesCsv.empty())
      for (const glm::dvec3& p : readProbeCsv(options.probesCsv))
        placed.add(p, ProbeKind::kUser, options.spacing);
    stats.userProbes = placed.size();
    VoxelPlacementOptions vo;
    vo.spacing = options.spacing;
    vo.maxSpacing = options.maxSpacing;
    vo.fillerSpacing = options.fillerSpacing;
    vo.threads = options.bake.threads;
    const PlacedProbes voxel = placeVoxelProbes(scene, vo);
    for (size_t i = 0; i < voxel.size(); ++i)
      placed.add(voxel.positions[i], voxel.kinds[i], voxel.spacing[i]);
    stats.gridProbes = voxel.size();
    const ClearanceQuery clearance = tracerClearance(tracer, options.bake.threads);
    const PushOutStats push = pushOutProbes(placed, clearance);
    stats.rejectedProbes = push.rejected;
    stats.pushedProbes = push.pushed;
    stats.mergedProbes = mergeProbes(placed, 0.1);
    timer.mark("place");
    stage.emplace("tetrahedralize", 0, "", show);
    if (placed.size() < 4) {
      std::ostringstream msg;
      msg << "only " << placed.size()
          << " probe(s) left after voxel placement (need at least 4 that are not all coplanar) at --spacing "
          << options.spacing << " m in a scene " << sceneLargestExtent(scene)
          << " m across (voxels touching geometry hold no probe): try a smaller --spacing (auto picks "
          << autoSpacing(scene) << " m here)";
      throw InputError(msg.str());
    }
    const double shellStep = options.shellSpacing < 0.0 ? options.spacing : options.shellSpacing;
    if (shellStep > 0.0) {
      // Around the scene and every probe, so the shell is at least half a step from all of them.
      glm::vec3 slo, shi;
      sceneBounds(scene, slo, shi);
      glm::dvec3 lo(slo), hi(shi);
      for (const glm::dvec3& p : placed.positions) {
        lo = glm::min(lo, p);
        hi = glm::max(hi, p);
      }
      // Fine where a surface is within kShellNearSteps steps (or the point is inside geometry), at
      // --max-spacing elsewhere: an open level's box top and sides over open ground hold nothing to light.
      const double nearReach = kShellNearSteps * shellStep;
      const NearGeometryQuery near = [&](const std::vector<glm::dvec3>& pts) {
        const std::vector<Clearance> c = clearance(pts, std::vector<double>(pts.size(), nearReach));
        std::vector<uint8_t> out(pts.size());
        for (size_t i = 0; i < pts.size(); ++i) out[i] = c[i].inside || c[i].nearest <= nearReach;
        return out;
      };
      for (const glm::dvec3& p : placeShellProbes(lo, hi, shellStep, options.maxSpacing, near))
        placed.add(p, ProbeKind::kShell, shellStep);
      stats.shellProbes = placed.count(ProbeKind::kShell);
    }
    FillerOptions fo;
    fo.backend = options.tetra == "tetgen" ? TetraBackend::kTetGen : TetraBackend::kCgal;
    const FillerResult filled = addSliverFillers(placed, fo, [&](const std::vector<glm::dvec3>& pts) {
      const std::vector<Clearance> c = clearance(pts, std::vector<double>(pts.size(), options.spacing));
      std::vector<uint8_t> in(pts.size());
      for (size_t i = 0; i < pts.size(); ++i) in[i] = c[i].inside || c[i].nearest < 0.05 * options.spacing;
      return in;
    });
    stats.sliverFillers = filled.added;
    stats.minDihedralBeforeFiller = filled.before.worstMinDihedralDeg;
    stats.minDihedral = filled.after.worstMinDihedralDeg;
    stats.dihedralHistogram.assign(filled.after.minDihedralHistogram.begin(),
                                   filled.after.minDihedralHistogram.end());
    stats.surfaceProbes = placed.count(ProbeKind::kSurface);
    stats.volumeProbes = placed.count(ProbeKind::kVolume);
    stats.openProbes = placed.count(ProbeKind::kOpen);
    stats.fillerProbes = placed.count(ProbeKind::kFiller);
    voxelMesh = filled.mesh;
    for (size_t i = 0; i < placed.size(); ++i)
      if (placed.kinds[i] == ProbeKind::kShell) shell.push_back(i);
    static_assert(uint8_t(ProbeKind::kShell) == uint8_t(LevelProbeKind::kShell) &&
                      uint8_t(ProbeKind::kFiller) == uint8_t(LevelProbeKind::kFiller) &&
                      uint8_t(ProbeKind::kSurface) == uint8_t(LevelProbeKind::kSurface),
                  "placement kinds 0..5 are stored as they are");
    for (ProbeKind k : placed.kinds) kinds.push_back(LevelProbeKind(uint8_t(k)));
    spacing = std::move(placed.spacing);
    probes = std::move(placed.positions);
  } else if (options.placement != "grid") {
    throw InputError("unknown placement '" + options.placement + "' (voxel, grid or none)");
  } else {
    glm::vec3 lo, hi;
    sceneBounds(scene, lo, hi);
    // Half a spacing in from the bounds, so no probe sits on the level's outer surfaces.
    const glm::dvec3 margin(options.spacing * 0.5);
    const glm::dvec3 glo = glm::dvec3(lo) + margin, ghi = glm::max(glm::dvec3(hi) - margin, glo);
    std::vector<glm::dvec3> grid = placeGridProbes(glo, ghi, options.spacing);
    stats.gridProbes = grid.size();
    const std::vector<uint8_t> inside = probesInsideGeometry(tracer, grid, 64, 0.25, options.bake.threads);
    for (size_t i = 0; i < grid.size(); ++i)
      if (!inside[i]) probes.push_back(grid[i]);
    kinds.assign(probes.size(), LevelProbeKind::kGrid);
    stats.rejectedProbes = grid.size() - probes.size();
  }
  if (!voxelMesh) {
    timer.mark("place");
    stage.emplace("tetrahedralize", 0, "", show);
  }
  if (probes.size() < 4) {
    std::ostringstream msg;
    msg << "only " << probes.size() << " probe(s) left after placement (need at least 4 that are not all "
        << "coplanar); the level may be smaller than --spacing " << options.spacing
        << " m or closed with the probes outside";
    throw InputError(msg.str());
  }

  std::vector<Clearance> shellClearance;  // of the shell probes, in `shell` order
  TetMesh mesh;
  if (voxelMesh) {
    mesh = std::move(*voxelMesh);  // tetrahedralized with the fillers
  } else {
    mesh = options.tetra == "tetgen" ? tetrahedralizeTetGen(probes).mesh : tetrahedralizeDelaunay(probes);
    const MeshQuality q = meshQuality(probes, mesh);
    stats.minDihedralBeforeFiller = stats.minDihedral = q.worstMinDihedralDeg;
    stats.dihedralHistogram.assign(q.minDihedralHistogram.begin(), q.minDihedralHistogram.end());
  }
  // The bound the late sliver pass restores after hole and refinement probes.
  stats.minDihedralBeforeHoles = stats.minDihedral;
  const size_t firstLate = probes.size();
  spacing.resize(probes.size(), options.spacing);
  tetsBelowDeg(probes, mesh, stats.tetsBelow);
  stats.worstTet = stats.worstTetBeforeHoles = describeWorstTet(probes, mesh, kinds);
  timer.mark("tetrahedralize");
  stage.emplace("tet records", 0, "", show);

  Level level;
  level.content = options.bake.content;
  level.shOrder = uint32_t(options.bake.shOrder);
  // Local origin: the probe bounds' centre rounded to whole metres (deterministic, keeps floats small).
  glm::dvec3 plo = probes[0], phi = probes[0];
  for (const auto& p : probes) {
    plo = glm::min(plo, p);
    phi = glm::max(phi, p);
  }
  level.origin = glm::round((plo + phi) * 0.5);
  level.probes.reserve(probes.size());
  for (const auto& p : probes) level.probes.push_back(glm::vec3(p - level.origin));
  level.tets = buildTetRecords(probes, mesh, level.origin);
  level.outerCells = buildOuterCells(level.probes, level.tets);  // continuous answers outside the hull
  // The cell grid (point location: 16 m cells, a BSP each) is built once, for the final probes, below: the
  // rounds in between locate their points by walks (ProbeQuery with kStoredCellGridOnly), which give the
  // same answers, instead of rebuilding a BSP per round (50 s a round for 200,000 random probes, 2 cores).
  if ((options.shardCount > 0 || options.merged) && !options.importShCsv.empty())
    throw InputError("a sharded bake traces probes: it does not take --import-sh");
  if (!options.importShCsv.empty()) {
    level.sh = std::move(imported.sh);
    truncateShOrder(level.sh, options.bake.shOrder);
    timer.mark("import");
  } else {
    // Shell probes that fail the inside rule are dilated whatever they see: not traced.
    std::vector<uint8_t> skip(probes.size(), 0);
    if (!shell.empty()) {
      stage.emplace("shell clearance", 0, "", show);
      std::vector<glm::dvec3> pts;
      for (size_t i : shell) pts.push_back(probes[i]);
      shellClearance = tracerClearance(tracer, options.bake.threads)(
          pts, std::vector<double>(pts.size(), options.spacing));
      for (size_t k = 0; k < shell.size(); ++k) skip[shell[k]] = shellClearance[k].inside ? 1 : 0;
    }
    if ((options.merged || options.shardRound == 2) && options.expectedProbeCount != probes.size())
      throw InputError("the shards placed " + std::to_string(options.expectedProbeCount) +
                       " probes, this placement " + std::to_string(probes.size()));
    stage.reset();  // the bake has progress of its own
    // With --share-caps, one lit map for every call of the bake, so the probes' lit-patch histograms carry
    // from pass to pass (BakeOptions::litVoxel).
    if (shareCaps) options.bake.litVoxel = litMapVoxelEdge(probes, &skip);
    if (options.shardCount > 0) {
      const std::vector<uint8_t> own = shardOwnership(probes, options.shardIndex, options.shardCount);
      *options.shardOut =
          options.shardRound == 1 ? bakeProbesShardPass1(tracer, probes, options.bake, own, &skip)
          : options.shardRound == 2
              ? bakeProbesShardPass2(tracer, probes, options.bake, own, *options.shardPass1, &skip)
              : bakeProbesShard(tracer, probes, options.bake, own, &skip);
      timer.mark("bake (shard)");
      return level;
    }
    if (deferBudget) {
      ShardBake traced;
      level.sh = bakeDeferred(probes, options.bake, stats.bake, &skip, options.merged, traced);
      const ShardBake& states = options.merged ? *options.merged : traced;
      keepStates(states, 0, probes.size());
      bakeFloor = states.floor;
    } else {
      level.sh = options.merged
                     ? bakeProbesMerged(tracer, probes, options.bake, *options.merged, &stats.bake, &skip)
                     : bakeProbes(tracer, probes, options.bake, &stats.bake, &skip);
    }
    timer.mark("bake");
  }
  if (!shell.empty() && options.importShCsv.empty()) {
    // Shell probes outside a closed level see the backs of its walls (the push-out's inside rule, so the
    // same probes would have been rejected as inside), or, under a black sky, nothing lit at all (a level
    // whose walls are closed boxes shows them front faces): either way they carry no light of their own
    // and take their nearest valid probe's SH. "Nothing lit": mean radiance (the SH's DC term, luminance)
    // at most 1e-3 of the median over the other probes.
    const std::vector<Clearance>& c = shellClearance;
    auto dc = [&](size_t i) {
      const glm::vec3 v = level.sh[i].c[0];
      return luminance(glm::dvec3(v));
    };
    stage.emplace("dilate", 0, "", show);
    std::vector<uint8_t> invalid(probes.size(), 0), isShell(probes.size(), 0);
    for (size_t i : shell) isShell[i] = 1;
    std::vector<double> interior;
    for (size_t i = 0; i < probes.size(); ++i)
      if (!isShell[i]) interior.push_back(dc(i));
    double median = 0.0;
    if (!interior.empty()) {
      std::nth_element(interior.begin(), interior.begin() + long(interior.size() / 2), interior.end());
      median = interior[interior.size() / 2];
    }
    for (size_t k = 0; k < shell.size(); ++k)
      invalid[shell[k]] = c[k].inside || !(dc(shell[k]) > 1e-3 * median) ? 1 : 0;
    stats.dilatedProbes = dilateInvalidProbes(probes, invalid, level.sh, &dilatedFrom);
    for (size_t i : shell)
      if (invalid[i]) kinds[i] = LevelProbeKind::kDilated;
    timer.mark("dilate");
  }
  DeringOptions dering = options.dering;
  dering.threads = options.bake.threads;
  stage.emplace("dering", 0, "", show);
  stats.dering = deringProbes(level.sh, dering);
  timer.mark("dering");
  stage.reset();  // occlusion has progress of its own

  // The hole and refinement rounds grow the level; the tets they leave as they were keep their data.
  OcclusionCache occlusionCache;
  auto occlude = [&] {
    OcclusionOptions occ = options.occlusion;
    occ.threads = options.bake.threads;
    occ.progress = options.bake.progress;
    occ.visibilitySource = dilatedFrom;
    if (!occ.visibilitySource.empty()) occ.visibilitySource.resize(level.probes.size());
    for (size_t i = dilatedFrom.size(); i < occ.visibilitySource.size(); ++i)
      occ.visibilitySource[i] = uint32_t(i);
    stats.occlusion = OcclusionStats{};
    level.occlusion = LevelOcclusion{};
    level.occlusion = buildOcclusion(tracer, level, occ, &stats.occlusion, &occlusionCache);
  };
  if (options.occlusion.mode != OcclusionMode::kNone) {
    occlude();
    timer.mark("occlusion");
  }

  // The level's tets and outer cells for `probes` as they stand (`given`: their Delaunay mesh, already
  // computed), and the final-mesh quality figures.
  auto remesh = [&](const TetMesh* given) {
    stage.emplace("tetrahedralize", 0, "", show);
    const TetMesh grown = given                       ? *given
                          : options.tetra == "tetgen" ? tetrahedralizeTetGen(probes).mesh
                                                      : tetrahedralizeDelaunay(probes);
    const MeshQuality q = meshQuality(probes, grown);
    stats.minDihedral = q.worstMinDihedralDeg;
    stats.dihedralHistogram.assign(q.minDihedralHistogram.begin(), q.minDihedralHistogram.end());
    tetsBelowDeg(probes, grown, stats.tetsBelow);
    stats.worstTet = describeWorstTet(probes, grown, kinds);
    stage.emplace("tet records", 0, "", show);
    level.tets = buildTetRecords(probes, grown, level.origin);
    level.outerCells = buildOuterCells(level.probes, level.tets);
  };
  bool occlusionStale = false;  // probes changed since the last occlude()

  // Appends probes (earlier probes keep their index, so their SH and seeds), bakes them with a seed of their
  // own, and tetrahedralizes the whole level again; occludes it again unless `reocclude` is false.
  // Traces probes at `at` with a seed of their own (`salt`), counts them in the bake's figures and derings them.
  // `states` receives their states after pass 2 when the budget's pass is deferred.
  auto trace = [&](const std::vector<glm::dvec3>& at, uint64_t salt, BakeStats& more, ShardBake& states) {
    BakeOptions bake = options.bake;
    bake.seed = options.bake.seed ^ (salt * 0x9e3779b97f4a7c15ull);
    // The path budget is the whole bake's: without deferBudget, added probes get what the earlier passes left
    // (with it, bakeDeferred traces their passes 1 and 2 only and spendBudget shares the budget later).
    bake.pathBudget = bake.pathBudget > stats.bake.paths ? bake.pathBudget - stats.bake.paths : 0;
    stage.reset();  // the bake and occlusion have progress of their own
    std::vector<ShRgb> sh = deferBudget ? bakeDeferred(at, bake, more, nullptr, nullptr, states)
                                        : bakeProbes(tracer, at, bake, &more);
    if (deferBudget) addedPaths += shareCaps ? flatCapPaths(states, options.bake) : more.paths;
    stats.bake.intersectRays += more.intersectRays;
    stats.bake.occludedRays += more.occludedRays;
    stats.bake.paths += more.paths;
    stats.bake.budgetPaths += more.budgetPaths;
    stats.bake.seconds += more.seconds;
    stats.bake.maxPathsPerProbe = std::max(stats.bake.maxPathsPerProbe, more.maxPathsPerProbe);
    deringProbes(sh, dering);
    return sh;
  };

  auto addProbes = [&](const std::vector<glm::dvec3>& added, uint64_t salt, LevelProbeKind kind,
                       bool reocclude = true, const TetMesh* given = nullptr) {
    probes.insert(probes.end(), added.begin(), added.end());
    kinds.insert(kinds.end(), added.size(), kind);
    spacing.insert(spacing.end(), added.size(), options.spacing);
    for (const glm::dvec3& p : added) level.probes.push_back(glm::vec3(p - level.origin));
    remesh(given);
    BakeStats more;
    ShardBake states;
    const std::vector<ShRgb> sh = trace(added, salt, more, states);
    if (deferBudget) keepStates(states, probes.size() - added.size(), added.size());
    if (!stats.bake.probeRelError.empty() || more.probeRelError.size() == added.size()) {
      stats.bake.probeRelError.resize(level.sh.size(), -1.0f);
      more.probeRelError.resize(added.size(), -1.0f);
      stats.bake.probeRelError.insert(stats.bake.probeRelError.end(), more.probeRelError.begin(),
                                      more.probeRelError.end());
    }
    level.sh.insert(level.sh.end(), sh.begin(), sh.end());
    occlusionStale = options.occlusion.mode != OcclusionMode::kNone;
    if (reocclude && occlusionStale) {
      occlude();
      occlusionStale = false;
    }
  };

  // The late sliver pass (tetra/final_slivers.h), once every hole and refinement probe is in: fillers within
  // --late-fillers, then the late probe of each sliver left is dropped (its SH with it); the level is
  // tetrahedralized and occluded for the final probes.
  bool lateDone = false;
  auto latePass = [&] {
    lateDone = true;
    // Voxel placement only: the filler bounded its mesh; user probes alone and the grid have no bound to keep.
    if (options.lateSlivers && options.placement == "voxel" && probes.size() > firstLate) {
      stage.emplace("late slivers", 0, "", show);
      stats.latePass = true;
      FinalSliverOptions fo;
      fo.backend = options.tetra == "tetgen" ? TetraBackend::kTetGen : TetraBackend::kCgal;
      fo.targetDeg = options.lateMinDihedral < 0.0
                         ? stats.minDihedralBeforeHoles
                         : std::min(options.lateMinDihedral, stats.minDihedralBeforeHoles);
      stats.lateTargetDeg = fo.targetDeg;
      fo.firstLate = firstLate;
      fo.maxFillers = size_t(std::max(0, options.lateFillers));
      fo.nudgeRounds = options.lateNudgeRounds;
      const ClearanceQuery clearance = tracerClearance(tracer, options.bake.threads);
      const FinalSliverResult r =
          fixFinalSlivers(probes, spacing, fo, [&](const std::vector<glm::dvec3>& pts) {
            const std::vector<Clearance> c = clearance(pts, std::vector<double>(pts.size(), options.spacing));
            std::vector<uint8_t> in(pts.size());
            for (size_t i = 0; i < pts.size(); ++i)
              in[i] = c[i].inside || c[i].nearest < 0.05 * options.spacing;
            return in;
          });
      stats.minDihedralBeforeLate = r.before.worstMinDihedralDeg;
      stats.dihedralHistogramBeforeLate.assign(r.before.minDihedralHistogram.begin(),
                                               r.before.minDihedralHistogram.end());
      stats.tetsBelowBeforeLate = stats.tetsBelow;
      stats.worstTetBeforeLate = stats.worstTet;
      stats.lateRemoved = r.removed.size();
      stats.lateFillers = r.added.size();
      stats.lateMoved = r.moved.size();
      if (!r.moved.empty()) {
        // Moved late probes are traced again where they now stand (their own seeds, as the rounds' probes).
        std::vector<glm::dvec3> at;
        for (const auto& [i, p] : r.moved) {
          probes[i] = p;
          level.probes[i] = glm::vec3(p - level.origin);
          at.push_back(p);
        }
        BakeStats more;
        ShardBake states;
        const std::vector<ShRgb> sh = trace(at, 0x3017eull, more, states);
        std::vector<float>& noise = stats.bake.probeRelError;
        for (size_t k = 0; k < states.probes.size(); ++k)
          bakeState[r.moved[states.probes[k]].first] = states.states[k];
        for (size_t k = 0; k < r.moved.size(); ++k) {
          level.sh[r.moved[k].first] = sh[k];
          if (noise.size() == probes.size() && k < more.probeRelError.size())
            noise[r.moved[k].first] = more.probeRelError[k];
        }
        occlusionStale = options.occlusion.mode != OcclusionMode::kNone;
      }
      if (!r.removed.empty()) {
        std::vector<uint8_t> drop(probes.size(), 0);
        for (size_t i : r.removed) {
          drop[i] = 1;
          stats.lateRemovedHole += kinds[i] == LevelProbeKind::kHole;
          stats.lateRemovedRefinement += kinds[i] == LevelProbeKind::kRefinement;
        }
        // The bake's per-probe noise (the SH fit's pull) follows its probes.
        std::vector<float>& noise = stats.bake.probeRelError;
        const bool perProbeNoise = noise.size() == probes.size();
        size_t w = 0;
        for (size_t i = 0; i < probes.size(); ++i) {
          if (drop[i]) continue;
          probes[w] = probes[i];
          kinds[w] = kinds[i];
          spacing[w] = spacing[i];
          level.probes[w] = level.probes[i];
          level.sh[w] = level.sh[i];
          if (perProbeNoise) noise[w] = noise[i];
          if (deferBudget) {
            bakeState[w] = bakeState[i];
            hasBakeState[w] = hasBakeState[i];
          }
          ++w;
        }
        if (perProbeNoise) noise.resize(w);
        if (deferBudget) {
          bakeState.resize(w);
          hasBakeState.resize(w);
        }
        probes.resize(w);
        kinds.resize(w);
        spacing.resize(w);
        level.probes.resize(w);
        level.sh.resize(w);
      }
      if (!r.added.empty())
        addProbes(r.added, 0x51173ull, LevelProbeKind::kFiller, false, &r.mesh);
      else if (!r.removed.empty() || !r.moved.empty())
        remesh(&r.mesh);
      occlusionStale = occlusionStale || !r.removed.empty();
      timer.mark("late slivers");
    } else {
      stats.minDihedralBeforeLate = stats.minDihedral;
      stats.dihedralHistogramBeforeLate = stats.dihedralHistogram;
      stats.tetsBelowBeforeLate = stats.tetsBelow;
      stats.worstTetBeforeLate = stats.worstTet;
    }
    if (occlusionStale && options.occlusion.mode != OcclusionMode::kNone) {
      occlude();
      occlusionStale = false;
      timer.mark("occlusion (final)");
    }
  };
  const bool baked = options.importShCsv.empty();

  // One hole round (occlusion_holes.h) with `ho` (its spacing set here), logged in `log`; its probes are baked
  // with `salt`. False when it proposed none (the rounds stop there).
  auto holeRound = [&](OcclusionHoleOptions ho, const std::string& label, uint64_t salt,
                       std::vector<PipelineStats::HoleRound>& log) {
    ho.spacing = options.spacing;
    stage.emplace(label, 0, "", show);
    const OcclusionHoles holes = findOcclusionHoles(tracer, level, ho);
    log.push_back({holes.pointsChecked, holes.holePoints, holes.probes.size(), holes.seenPoints});
    stage.reset();
    if (holes.probes.empty()) return false;
    stats.holeProbes += holes.probes.size();
    addProbes(holes.probes, salt, LevelProbeKind::kHole);
    return true;
  };
  auto roundLabel = [](const std::string& what, int round, int rounds) {
    return what + "round " + std::to_string(round + 1) + " of " + std::to_string(rounds) + ")";
  };

  // The rounds aimed at the lookup's fallback, once the hole and refinement probes are in (before the late
  // sliver pass, which bounds the tets of every probe added after the fillers).
  auto lookupHoles = [&] {
    if (options.lookupHoleRounds <= 0 || options.holeRounds <= 0 ||
        options.occlusion.mode == OcclusionMode::kNone || !baked)
      return;
    if (occlusionStale) {
      occlude();
      occlusionStale = false;
    }
    for (int round = 0; round < options.lookupHoleRounds; ++round) {
      OcclusionHoleOptions ho;
      ho.seed = options.bake.seed ^ (0x100c5ull + uint64_t(round));
      ho.lookupOnly = true;
      ho.maxOffset = kLookupHoleOffset * options.spacing;
      if (!holeRound(ho, roundLabel("holes (lookup, ", round, options.lookupHoleRounds),
                     0x100c5ull + uint64_t(round), stats.lookupHoleRounds))
        break;
    }
    timer.mark("holes (lookup)");
  };

  // The path budget's pass over every traced probe of the finished level (deferBudget): what is left of the
  // budget (plus the added probes' passes 1 and 2) after every probe's pass 2, shared among the probes
  // above the target (bakeProbesMerged's pass 3, each probe's own index its stream); then their SH, the
  // dilated probes' copies and the deringing again. The bake's figures become those of every traced probe.
  bool budgetSpent = !deferBudget || !baked;
  auto spendBudget = [&] {
    if (budgetSpent) return;
    budgetSpent = true;
    stage.reset();  // the pass has progress of its own
    std::vector<uint8_t> skip(probes.size(), 1);
    ShardBake all;
    all.floor = bakeFloor;
    for (size_t i = 0; i < probes.size(); ++i) {
      if (!hasBakeState[i]) continue;
      skip[i] = 0;
      all.probes.push_back(uint32_t(i));
      all.states.push_back(bakeState[i]);
    }
    std::vector<ProbeBakeState>().swap(bakeState);  // `all` holds them now: one copy in memory, not two
    BakeStats total;
    const double before = stats.bake.seconds;
    BakeOptions bake = options.bake;
    bake.pathBudget += addedPaths;
    const std::vector<ShRgb> sh = bakeProbesMerged(tracer, probes, bake, all, &total, &skip);
    for (size_t i = 0; i < probes.size(); ++i)
      if (hasBakeState[i]) level.sh[i] = sh[i];
    for (size_t i = 0; i < dilatedFrom.size() && i < probes.size(); ++i)
      if (dilatedFrom[i] != i) level.sh[i] = level.sh[dilatedFrom[i]];
    stats.dering = deringProbes(level.sh, dering);
    total.seconds += before;
    stats.bake = std::move(total);
    timer.mark("bake (path budget)");
  };

  // Occlusion holes: probes where a surface point sees none of its tet's probes (occlusion_holes.h).
  if (options.holeRounds > 0 && options.occlusion.mode != OcclusionMode::kNone && baked) {
    for (int round = 0; round < options.holeRounds; ++round) {
      OcclusionHoleOptions ho;
      ho.seed = options.bake.seed ^ (0x401e5ull + uint64_t(round));
      ho.onlyUnseen = options.holesOnlyUnseen;
      if (!holeRound(ho, roundLabel("holes (", round, options.holeRounds), 0xb01e5ull + uint64_t(round),
                     stats.holeRounds))
        break;
    }
    timer.mark("holes");
  }

  // Error-driven refinement (eval/refine.h): the lookup's error against the oracle at area-uniform surface
  // points; probes in front of the worst, up to the budget; the error measured again on an independent draw.
  // auto: a quarter of the placed probes (shell probes not counted), at least kAutoRefineMin: a small level's
  // rooms hold few probes at the default spacing, and that is where 1 m probes resolve the light worst.
  // 1024: enough that on every level measured the refinement stops at the points over its error threshold
  // (its proposals run out) rather than at the count; at 256 the Cornell box and two_rooms stopped at the count
  // (docs/accuracy.md#error-driven-refinement).
  constexpr int kAutoRefineMin = 1024;
  const int budget = options.probeBudget >= 0
                         ? options.probeBudget
                         : std::max(kAutoRefineMin, int(0.25 * double(probes.size() - shell.size())));
  // The refinement's traced points, which the SH fit reuses (its fit and hold-out points) when it traces its
  // points with as many paths.
  std::vector<RefinePoint> select, check;
  if (budget > 0 && baked) {
    RefineOptions ro;
    ro.spacing = options.spacing;
    ro.points = options.refinePoints > 0
                    ? options.refinePoints
                    : autoRefinePoints(budget, surfaceArea(tracer.scene()), options.spacing);
    ro.content = options.bake.content;
    ro.threads = options.bake.threads;
    ro.seed = options.bake.seed ^ 0x2ef1eull;
    ro.progress = show;  // the oracle's references, by point
    ro.farm = options.bake.farm;
    select = refinePoints(tracer, ro);
    ro.seed = options.bake.seed ^ 0x7a11dull;
    check = refinePoints(tracer, ro);
    stage.emplace("refine (select)", 0, "", show);
    stats.refineBefore = scoreRefinePoints(level, check);
    scoreRefinePoints(level, select);
    const std::vector<glm::dvec3> added =
        proposeRefinement(tracer, level, select, size_t(budget), options.spacing, 0.1, options.refineOffset);
    stats.refineProbes = added.size();
    // Occluded once, after the late sliver pass (which may remove some of these probes).
    if (!added.empty()) addProbes(added, 0x2ef1eull, LevelProbeKind::kRefinement, !options.lateSlivers);
    timer.mark("refine");
    lookupHoles();
    latePass();
    spendBudget();
    stage.emplace("refine (check)", 0, "", show);
    stats.refineAfter = scoreRefinePoints(level, check);
    timer.mark("refine (check)");
    stage.reset();
  }
  if (!lateDone) {
    lookupHoles();
    latePass();
  }
  spendBudget();

  // The SH fit (eval/sh_fit.h): the probe SH that make the lookup's answer match the traced irradiance at
  // area-uniform surface points, pulled toward the traced values by their noise; deringed, then kept (auto)
  // only when an independent draw of points says the level got better. Both scores are taken on the SH as
  // saved (half precision), so the reported figures are the saved level's.
  if (options.fit != "off" && baked && !level.tets.empty()) {
    const int count = options.fitPoints >= 0
                          ? options.fitPoints
                          : std::clamp(kFitPointsPerProbe * int(probes.size() - shell.size()), kFitPointsMin,
                                       kFitPointsMax);
    stage.reset();
    // `count` points: those of `pool` first (when traced with fitSamples paths), then fresh ones.
    auto points = [&](const std::vector<RefinePoint>& pool, int count, uint64_t seed) {
      std::vector<ShFitPoint> out;
      if (options.fitSamples == RefineOptions{}.samplesPerPoint)
        for (size_t i = 0; i < pool.size() && out.size() < size_t(count); ++i)
          out.push_back({pool[i].surface.position, pool[i].surface.normal, pool[i].reference.irradiance,
                         pool[i].reference.stderror});
      if (out.size() < size_t(count)) {
        const std::vector<ShFitPoint> more =
            shFitPoints(tracer, count - int(out.size()), options.fitSamples, seed, options.bake.content,
                        options.bake.threads, show, options.bake.farm);
        out.insert(out.end(), more.begin(), more.end());
      }
      return out;
    };
    const std::vector<ShFitPoint> fitPoints = points(select, count, options.bake.seed ^ 0x5f17ull);
    const std::vector<ShFitPoint> holdout = points(check, options.fitHoldout, options.bake.seed ^ 0x401d0ull);
    stage.emplace("fit", 0, "", show);
    const std::vector<ShRgb> traced = level.sh;
    for (ShRgb& s : level.sh) s = quantizeSh(s);
    stats.fitHoldoutBefore = shFitScore(level, holdout);
    level.sh = traced;
    ShFitOptions fo;
    fo.lambda = options.fitLambda;
    fo.maxMove = options.fitMaxMove;
    fo.crossValidate = options.fitValidate;
    std::vector<ShRgb> fitted =
        fitProbeSh(level, fitPoints, stats.bake.probeRelError, fo, &stats.fit, options.bake.threads);
    deringProbes(fitted, dering);
    for (ShRgb& s : fitted) s = quantizeSh(s);
    level.sh = std::move(fitted);
    stats.fitHoldoutAfter = shFitScore(level, holdout);
    stats.fitRan = true;
    stats.fitKept = options.fit == "on" || shFitKept(stats.fitHoldoutBefore, stats.fitHoldoutAfter);
    if (!stats.fitKept) level.sh = traced;
    timer.mark("fit");
    stage.reset();
  }

  // Point location for the final probes (stored in the level; engines' and eval's queries use it).
  stage.emplace("cell grid", 0, "", show);
  level.cellGrid = buildCellGrid(level.probes, level.tets, 16.0f, options.bake.threads);
  timer.mark("cell grid");
  stage.reset();

  // What the user gets: the surface points of the finished level (after hole filling and refinement, which
  // both re-tetrahedralize) that still see none of their tet's probes, on a draw of their own. Reported only.
  if (!level.occlusion.empty()) {
    OcclusionHoleOptions ho;
    ho.spacing = options.spacing;
    ho.seed = options.bake.seed ^ 0xf1a1ull;
    ho.propose = false;
    ho.keepLookupFallbacks = true;
    stage.emplace("check", 0, "", show);
    const OcclusionHoles left = findOcclusionHoles(tracer, level, ho);
    stats.finalChecked = left.pointsChecked;
    stats.finalHoles = left.holePoints;
    stats.finalLookupFallbacks = left.lookupFallbackPoints;
    // Points no path leaves (a closed cavity: eval's noPathLeaves, evaluate.h) are counted apart: no viewer
    // sees their answer. A point is one when closedTestPaths() reference paths (eval's default count) find
    // no light at all.
    ReferenceBatch paths;
    paths.options = options.bake;    // its farm, if any, traces them
    paths.options.progress = false;  // within the check's stage
    paths.samples = closedTestPaths();
    for (size_t i = 0; i < left.lookupFallbacks.size(); ++i)
      paths.items.push_back({left.lookupFallbacks[i].position,
                             left.lookupFallbacks[i].normal,
                             options.bake.seed ^ (0xc105edull + i),
                             {}});
    traceReferences(tracer, paths, options.bake.threads);
    std::vector<uint8_t> closed(paths.items.size(), 0);
    for (size_t i = 0; i < paths.items.size(); ++i) closed[i] = noPathLeaves(paths.items[i].result) ? 1 : 0;
    stats.finalClosedFallbacks = size_t(std::count(closed.begin(), closed.end(), uint8_t(1)));
    timer.mark("check");
    stage.reset();
  }

  // The SH as the level file and the GPU hold them (half precision, runtime/sh_half.h), so that what the caller
  // reports and evaluates is what saveLevel writes and loadLevel reads back, bit for bit.
  for (ShRgb& s : level.sh) s = quantizeSh(s);

  if (kinds.size() == level.probes.size()) level.probeKinds = std::move(kinds);

  level.generator = generatorString(options);
  return level;
}

}  // namespace tetraprobe::cli
