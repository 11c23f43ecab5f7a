// `tetraprobe bake SCENE -o LEVEL.tpb`: the per-level build.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <optional>

#include "args.h"
#include "commands.h"
#include "file_sections.h"
#include "pipeline.h"
#include "pipeline_options.h"
#include "shard_part.h"
#include "tetraprobe/common/error.h"
#include "tetraprobe/common/progress.h"
#include "tetraprobe/runtime/sh_half.h"
#include "tetraprobe/scene/load.h"
#include "trace_farm.h"

namespace tetraprobe::cli {

namespace {

// The bake's noise by the kind of probe (Level::probeKinds): per kind with traced probes, their count and the
// mean and 95th percentile of their relative stderr (BakeStats::probeRelError, summarized as the headline
// is), so a report shows whether the probes added late (hole, refinement) are as converged as the first.
nlohmann::json noiseByKind(const Level& level, const std::vector<float>& noise, double target) {
  nlohmann::json out = nlohmann::json::object();
  if (noise.size() != level.probeKinds.size()) return out;
  std::vector<std::vector<double>> byKind(kLevelProbeKindCount);
  for (size_t i = 0; i < noise.size(); ++i)
    if (noise[i] >= 0.0f && uint8_t(level.probeKinds[i]) < kLevelProbeKindCount)
      byKind[uint8_t(level.probeKinds[i])].push_back(double(noise[i]));
  for (uint32_t k = 0; k < kLevelProbeKindCount; ++k) {
    if (byKind[k].empty()) continue;
    const RelErrorSummary e = summarizeRelErrors(std::move(byKind[k]), target);
    out[levelProbeKindName(LevelProbeKind(k))] = {
        {"probes", e.count}, {"mean_rel_stderr", e.mean}, {"p95_rel_stderr", e.p95}};
  }
  return out;
}

}  // namespace

int runBake(int argc, char** argv, const MergedShards* merge) {
  Args args("tetraprobe bake SCENE -o LEVEL.tpb [options]",
            "Bakes a level: places probes, path-traces each probe's incident radiance into SH L2 RGB,\n"
            "tetrahedralizes the probes and writes one binary level file (written atomically).\n"
            "SCENE is a .gltf/.glb, .obj or .scene.json file (docs/scene_format.md).",
            bakeOptionSpecs());
  if (!args.parse(argc, argv)) return 0;
  // --options-from LEVEL: the level's recorded options first, then this command line's, which override them.
  if (args.has("--options-from")) {
    std::vector<std::string> line;
    const std::string from = args.str("--options-from");
    Level recorded;
    if (const LevelResult r = loadLevel(from, recorded); !r) throw InputError(r.message);
    bool sawOption = false;
    for (const std::string& a : generatorArguments(recorded.generator)) {
      sawOption = true;
      const std::string name = a.substr(0, a.find('='));
      if (name == "--probes" || name == "--import-sh") {
        // The file's name is recorded, not where it is: the user gives it again.
        if (!args.has(name))
          throw UsageError(from + " was baked with " + name + " " + a.substr(name.size() + 1) + ": give " +
                           name + " FILE again");
        continue;
      }
      line.push_back(a);
    }
    if (!sawOption) throw InputError(from + "'s generator string records no bake options");
    for (int i = 0; i < argc; ++i) line.push_back(argv[i]);
    std::vector<char*> again;
    for (std::string& a : line) again.push_back(a.data());
    args = Args("tetraprobe bake SCENE -o LEVEL.tpb [options]", "", bakeOptionSpecs());
    args.parse(int(again.size()), again.data());
  }
  args.requirePositional(1, 1);
  if (!args.has("--output")) throw UsageError("missing -o LEVEL.tpb");
  const std::string scenePath = args.positional()[0];
  const std::string out = args.str("--output");

  PipelineOptions opt = pipelineOptionsFromArgs(args);
  const bool spacingAuto = !(opt.spacing > 0.0);  // resolved from the scene once it is loaded
  const std::string dering = args.str("--dering"), content = args.str("--content");

  // Sharding: every option that can change the level, canonical, so the merge can check the shards agree
  // and bake with the same options (output, report, threads and the shard itself never change it).
  std::string canonical = scenePath + "\n";
  for (const auto& [name, value] : args.values()) {
    if (name == "--output" || name == "--report" || name == "--threads" || name == "--shard" ||
        name == "--round" || name == "--floor" || name == "--resume" || name == "--options-from")
      continue;
    if (value.find('\n') != std::string::npos) throw UsageError(name + " holds a line break");
    canonical += name + "=" + value + "\n";
  }
  ShardBake shardOut;
  if (args.has("--shard")) {
    if (merge) throw UsageError("--shard is not an option of merge");
    const IndexOfCount shard = parseIndexOfCount(args.str("--shard"), "--shard");
    if (!(opt.bake.targetRelError > 0.0)) throw UsageError("--shard needs adaptive sampling (--noise > 0)");
    if (!opt.importShCsv.empty()) throw UsageError("--shard does not take --import-sh (nothing is traced)");
    opt.shardIndex = shard.index;
    opt.shardCount = shard.count;
    opt.shardOut = &shardOut;
  }
  // The two-round protocol (docs/distributed.md): round 1 writes pass-1 states, `merge --floor` the floor,
  // round 2 resumes from this shard's round-1 part with that floor.
  ShardPart resume;
  const std::string round = args.str("--round");
  if (round != "both" && round != "1" && round != "2") throw UsageError("--round must be both, 1 or 2");
  if (round != "both" && !args.has("--shard")) throw UsageError("--round needs --shard I/N");
  if ((args.has("--floor") || args.has("--resume")) != (round == "2"))
    throw UsageError("--round 2 takes --floor FILE and --resume FILE (and only it does)");
  if (round == "1") opt.shardRound = 1;
  if (round == "2") {
    ShardPart floor = readShardPart(args.str("--floor"));
    resume = readShardPart(args.str("--resume"));
    if (floor.stage != PartStage::kFloor)
      throw InputError(args.str("--floor") + " is not a floor part (tetraprobe merge --floor)");
    if (resume.stage != PartStage::kPass1 || resume.index != uint32_t(opt.shardIndex))
      throw InputError(args.str("--resume") + " is not shard " + std::to_string(opt.shardIndex) +
                       "'s round-1 part");
    checkSameBake(resume, floor, args.str("--resume"));
    if (resume.options != canonical || resume.count != uint32_t(opt.shardCount))
      throw InputError(args.str("--resume") + " was baked with different options or shard count");
    resume.bake.floor = floor.bake.floor;
    opt.shardRound = 2;
    opt.shardPass1 = &resume.bake;
    opt.expectedProbeCount = resume.probeCount;
  }

  const auto t0 = std::chrono::steady_clock::now();
  const Scene scene = [&] {
    const Progress loading("load", 0, "", opt.bake.progress);
    return loadScene(scenePath);
  }();
  const double loadSeconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  for (const auto& w : scene.warnings) std::fprintf(stderr, "tetraprobe bake: warning: %s\n", w.c_str());
  const uint64_t sceneHash = sceneContentHash(scene);
  if (merge) {
    if (merge->sceneHash != sceneHash)
      throw InputError("scene " + scenePath + " differs from the one the shards baked (content hash)");
    opt.merged = &merge->bake;
    opt.expectedProbeCount = merge->probeCount;
  }
  if (opt.shardRound == 2 && resume.sceneHash != sceneHash)
    throw InputError("scene " + scenePath + " differs from the one round 1 baked (content hash)");

  if (spacingAuto) opt.spacing = autoSpacing(scene);

  // `merge --farm`: the merge's tracing goes to the workers (trace_farm.h); the level is the same bytes.
  std::optional<FileFarm> farm;
  TraceFarm farmFunction;
  if (merge && !merge->farmDir.empty()) {
    farm.emplace(merge->farmDir, merge->farmWorkers, sceneHash, merge->farmTimeout, opt.bake.progress);
    farmFunction = farm->function();
    opt.bake.farm = &farmFunction;
  }

  PipelineStats stats;
  stats.timings.emplace_back("load", loadSeconds);
  Level level = buildLevel(scene, opt, stats);
  if (farm) farm->finish();

  if (opt.shardCount > 0) {
    ShardPart part;
    part.stage = opt.shardRound == 1 ? PartStage::kPass1 : PartStage::kPass12;
    part.index = uint32_t(opt.shardIndex);
    part.count = uint32_t(opt.shardCount);
    part.probeCount = level.probes.size();
    part.sceneHash = sceneHash;
    part.options = canonical;
    part.bake = std::move(shardOut);
    const auto tw = std::chrono::steady_clock::now();
    std::optional<Progress> writing(std::in_place, "write", 0, "", opt.bake.progress);
    writeShardPart(out, part);
    writing.reset();
    stats.timings.emplace_back("write",
                               std::chrono::duration<double>(std::chrono::steady_clock::now() - tw).count());
    uint64_t batches = 0;
    for (const ProbeBakeState& st : part.bake.states) batches += uint64_t(st.batches);
    std::printf("tetraprobe bake: shard %d/%d of %s -> %s\n  probes  %zu of %zu, %llu paths (%s)\n",
                opt.shardIndex, opt.shardCount, scenePath.c_str(), out.c_str(), part.bake.probes.size(),
                level.probes.size(), (unsigned long long)(batches * kBakeBatchSize),
                opt.shardRound == 1 ? "pass 1" : "passes 1-2");
    std::printf("  time   ");
    double total = 0.0;
    for (const auto& [stage, sec] : stats.timings) {
      std::printf(" %s %.2fs", stage.c_str(), sec);
      total += sec;
    }
    std::printf("  (total %.2fs)\n", total);
    return 0;
  }

  const auto tw = std::chrono::steady_clock::now();
  std::optional<Progress> writing(std::in_place, "write", 0, "", opt.bake.progress);
  if (const LevelResult r = saveLevel(out, level); !r) throw std::runtime_error(r.message);
  writing.reset();
  stats.timings.emplace_back("write",
                             std::chrono::duration<double>(std::chrono::steady_clock::now() - tw).count());
  double total = 0.0;
  for (const auto& [stage, s] : stats.timings) total += s;

  const uint64_t fileBytes = std::filesystem::file_size(out);
  const uint64_t probeBytes = level.probes.size() * sizeof(glm::vec3);
  const uint64_t shBytes = level.sh.size() * sizeof(ShHalf);  // as stored (runtime/sh_half.h)
  // As stored: the tets' probe indices, packed (level_format.md, TETM; TETC for a streamed level).
  const uint64_t tetBytes = sectionBytes(fileSections(out), {"TETM", "TETC", "TETS"});

  const nlohmann::json noiseKinds = noiseByKind(level, stats.bake.probeRelError, opt.bake.targetRelError);
  std::printf("tetraprobe bake: %s -> %s\n", scenePath.c_str(), out.c_str());
  glm::vec3 sceneLo, sceneHi;
  sceneBounds(scene, sceneLo, sceneHi);
  const glm::vec3 extent = sceneHi - sceneLo;
  std::printf("  scene   %zu triangles, %zu materials, %zu lights; %.3g x %.3g x %.3g m\n",
              scene.triangles.size(), scene.materials.size(), scene.lights.size(), extent.x, extent.y,
              extent.z);
  if (spacingAuto && opt.spacing < 1.0)
    std::printf(
        "  spacing %.4g m (auto: the scene is under %.0f m across; %.0f voxels along its largest extent)\n",
        opt.spacing, kAutoSpacingVoxels, kAutoSpacingVoxels);
  if (stats.importedProbes)
    std::printf("  probes  %zu (imported with their SH, from %s)\n", level.probes.size(),
                opt.importShCsv.c_str());
  else if (opt.placement == "none")
    std::printf("  probes  %zu (user, from %s)\n", level.probes.size(), opt.probesCsv.c_str());
  else if (opt.placement == "voxel")
    std::printf(
        "  probes  %zu (voxel %.3g..%.3g m: %zu surface, %zu volume, %zu open, %zu filler (%zu at "
        "slivers), %zu shell (%zu dilated), %zu user; %zu rejected, %zu pushed, %zu merged)\n",
        level.probes.size(), opt.spacing, opt.maxSpacing, stats.surfaceProbes, stats.volumeProbes,
        stats.openProbes, stats.fillerProbes, stats.sliverFillers, stats.shellProbes, stats.dilatedProbes,
        stats.userProbes, stats.rejectedProbes, stats.pushedProbes, stats.mergedProbes);
  else
    std::printf("  probes  %zu (grid %.3g m: %zu placed, %zu inside geometry rejected)\n",
                level.probes.size(), opt.spacing, stats.gridProbes, stats.rejectedProbes);
  std::printf(
      "  tets    %zu (%s), final mesh worst min dihedral %.3g deg, %zu / %zu / %zu tets under 1 / 5 / 10 deg "
      "(%.3g before fillers, %.3g before hole and refinement probes)\n",
      level.tets.size(), opt.tetra.c_str(), stats.minDihedral, stats.tetsBelow[0], stats.tetsBelow[1],
      stats.tetsBelow[2], stats.minDihedralBeforeFiller, stats.minDihedralBeforeHoles);
  if (stats.latePass)
    std::printf(
        "  late    slivers after hole and refinement probes (bound %.3g deg): worst %.3g -> %.3g deg, under "
        "1 / 5 / 10 deg "
        "%zu / %zu / %zu -> %zu / %zu / %zu; %zu fillers added, %zu late probes moved, %zu dropped (%zu "
        "hole, "
        "%zu refinement)\n",
        stats.lateTargetDeg, stats.minDihedralBeforeLate, stats.minDihedral, stats.tetsBelowBeforeLate[0],
        stats.tetsBelowBeforeLate[1], stats.tetsBelowBeforeLate[2], stats.tetsBelow[0], stats.tetsBelow[1],
        stats.tetsBelow[2], stats.lateFillers, stats.lateMoved, stats.lateRemoved, stats.lateRemovedHole,
        stats.lateRemovedRefinement);
  if (!stats.importedProbes) {
    std::printf("  rays    %llu (%.3g Mrays/s), %llu paths (%.0f per probe, at most %d)\n",
                (unsigned long long)stats.bake.rays(), stats.bake.raysPerSecond() * 1e-6,
                (unsigned long long)stats.bake.paths,
                level.probes.empty() ? 0.0 : double(stats.bake.paths) / double(level.probes.size()),
                stats.bake.maxPathsPerProbe);
    if (opt.bake.targetRelError > 0.0)
      std::printf(
          "  noise   target %.3g: achieved relative stderr mean %.4f, p95 %.4f, max %.4f; %zu probes "
          "above target at the cap; %llu paths from the path budget\n",
          opt.bake.targetRelError, stats.bake.meanRelError, stats.bake.p95RelError, stats.bake.maxRelError,
          stats.bake.probesAtCap, (unsigned long long)stats.bake.budgetPaths);
    // By kind, when more than one kind was traced: whether the probes added late converged as the first.
    if (opt.bake.targetRelError > 0.0 && noiseKinds.size() > 1) {
      std::string text;
      for (const auto& [name, k] : noiseKinds.items()) {
        char item[96];
        std::snprintf(item, sizeof item, "%s%s %.4f / %.4f (%lld)", text.empty() ? "" : ", ", name.c_str(),
                      k.at("mean_rel_stderr").get<double>(), k.at("p95_rel_stderr").get<double>(),
                      (long long)k.at("probes").get<int64_t>());
        text += item;
      }
      std::printf("          by kind, mean / p95 (probes): %s\n", text.c_str());
    }
  }
  std::printf("  sh      L%d, dering %s: %zu probes changed, min irradiance %.4g -> %.4g W/m^2\n",
              opt.bake.shOrder, dering.c_str(), stats.dering.deringedProbes, stats.dering.minIrradianceBefore,
              stats.dering.minIrradianceAfter);
  if (opt.occlusion.mode != OcclusionMode::kNone)
    std::printf(
        "  occl    %s: %zu tets with geometry; %zu none, %zu planes, %zu shadow maps; %zu bytes (%.2f per "
        "tet); agreement %.4f, %llu blackouts\n",
        occlusionModeName(opt.occlusion.mode), stats.occlusion.tetsWithGeometry, stats.occlusion.none,
        stats.occlusion.planeTets, stats.occlusion.shadowMapTets, level.occlusion.bytes(),
        level.tets.empty() ? 0.0 : double(level.occlusion.bytes()) / double(level.tets.size()),
        stats.occlusion.agreement, (unsigned long long)stats.occlusion.blackouts);
  else
    std::printf("  occl    none\n");
  if (stats.refineBefore.points > 0)
    std::printf(
        "  refine  +%zu probes; error at %zu independent points: mean |log2| %.4f -> %.4f, gross %.4f -> "
        "%.4f\n",
        stats.refineProbes, stats.refineBefore.points, stats.refineBefore.meanLogError,
        stats.refineAfter.meanLogError, stats.refineBefore.gross, stats.refineAfter.gross);
  if (stats.fitRan)
    std::printf(
        "  fit     %s (--fit %s): %zu of %zu points fitted (%zu fall back, %zu skipped), %zu probes touched, "
        "%zu capped, %zu held by cross-validation; hold-out at %zu independent points: mean rel. error %.4f "
        "-> "
        "%.4f, gross %.4f -> %.4f\n",
        stats.fitKept ? "kept" : "dropped", opt.fit.c_str(), stats.fit.fitted, stats.fit.points,
        stats.fit.fallbackPoints, stats.fit.otherSkipped, stats.fit.probesTouched, stats.fit.cappedProbes,
        stats.fit.heldProbes, stats.fitHoldoutBefore.points, stats.fitHoldoutBefore.meanRelError,
        stats.fitHoldoutAfter.meanRelError, stats.fitHoldoutBefore.gross, stats.fitHoldoutAfter.gross);
  if (!stats.holeRounds.empty()) {
    std::printf("  holes  ");
    for (const auto& r : stats.holeRounds)
      if (opt.holesOnlyUnseen)
        std::printf(
            " [%zu of %zu points see no probe, %zu of them their fallback probe by rays: +%zu probes]",
            r.holes, r.checked, r.seen, r.added);
      else
        std::printf(" [%zu of %zu points see no probe: +%zu probes]", r.holes, r.checked, r.added);
    for (const auto& r : stats.lookupHoleRounds)
      std::printf(" [after refinement, %zu of %zu points fall back in the lookup: +%zu probes]", r.holes,
                  r.checked, r.added);
    std::printf("\n");
  }
  if (stats.finalChecked > 0) {
    const size_t open = stats.finalLookupFallbacks - stats.finalClosedFallbacks;
    std::printf(
        "  fallback %zu of %zu surface points (%.1f %%) see none of their tet's probes in the finished "
        "level by its data; %zu (%.2f %%) after the blend with the tets around them (the lookup's answer), "
        "%zu more where no path leaves (closed: %d paths found no light)\n",
        stats.finalHoles, stats.finalChecked, 100.0 * double(stats.finalHoles) / double(stats.finalChecked),
        open, 100.0 * double(open) / double(stats.finalChecked), stats.finalClosedFallbacks,
        closedTestPaths());
  }
  const CellGrid& grid = level.cellGrid;
  const size_t gridBytes = cellGridBytes(grid), gridCells = occupiedCells(grid);
  std::printf(
      "  locate  %zu cells of %g m, BSP %zu nodes, %zu leaves (at most %d tets each), depth max %d mean "
      "%.1f; "
      "%zu bytes in memory (%.1f per tet)\n",
      gridCells, double(grid.cellSize), grid.nodes.size(), grid.leaves, kDefaultLeafTets, grid.maxDepth,
      grid.meanDepth, gridBytes, level.tets.empty() ? 0.0 : double(gridBytes) / double(level.tets.size()));
  std::printf(
      "  bytes   %llu in the file, %.0f per probe (probes %llu, SH %llu, tets %llu; `inspect` has every "
      "section)\n",
      (unsigned long long)fileBytes,
      level.probes.empty() ? 0.0 : double(fileBytes) / double(level.probes.size()),
      (unsigned long long)probeBytes, (unsigned long long)shBytes, (unsigned long long)tetBytes);
  if (farm)
    std::printf(
        "  farm    %d workers, %d jobs, %llu probe steps and %llu reference points traced there; %.2fs "
        "waiting on them, %.2fs serial (the rest)\n",
        merge->farmWorkers, farm->jobs(), (unsigned long long)farm->items(),
        (unsigned long long)farm->points(), farm->waitSeconds(), total - farm->waitSeconds());
  std::printf("  time   ");
  for (const auto& [stage, s] : stats.timings) std::printf(" %s %.2fs", stage.c_str(), s);
  std::printf("  (total %.2fs)\n", total);

  if (args.has("--report")) {
    nlohmann::json j;
    j["scene"] = {{"path", scenePath},
                  {"triangles", scene.triangles.size()},
                  {"materials", scene.materials.size()},
                  {"lights", scene.lights.size()},
                  {"bounds", {{sceneLo.x, sceneLo.y, sceneLo.z}, {sceneHi.x, sceneHi.y, sceneHi.z}}},
                  {"surface_area_m2", surfaceArea(scene)},
                  {"warnings", scene.warnings}};
    j["level"] = out;
    const nlohmann::json refinePoints =
        opt.refinePoints < 0 ? nlohmann::json("auto") : nlohmann::json(opt.refinePoints);
    j["options"] = {{"spacing", opt.spacing},
                    {"spacing_auto", spacingAuto},
                    {"bounces", opt.bake.bounces},
                    {"samples", opt.bake.samplesPerProbe},
                    {"target_error", opt.bake.targetRelError},
                    {"max_samples", opt.bake.maxSamplesPerProbe},
                    {"content", content},
                    {"seed", opt.bake.seed},
                    {"placement", !opt.importShCsv.empty()  ? "imported"
                                  : opt.placement == "none" ? "user"
                                                            : opt.placement},
                    {"max_spacing", opt.maxSpacing},
                    {"filler_spacing", opt.fillerSpacing},
                    {"shell_spacing", opt.shellSpacing < 0.0 ? opt.spacing : opt.shellSpacing},
                    {"tetra", opt.tetra},
                    {"sh_order", opt.bake.shOrder},
                    {"dering", dering},
                    {"occlusion", occlusionModeName(opt.occlusion.mode)},
                    {"min_agreement", opt.occlusion.minAgreement},
                    {"fill_holes", opt.holeRounds},
                    {"lookup_holes", opt.lookupHoleRounds},
                    {"hole_rule", opt.holesOnlyUnseen ? "unseen" : "all"},
                    {"probe_budget", opt.probeBudget},
                    {"refine_points", refinePoints}};
    j["probes"] = {{"count", level.probes.size()},
                   {"grid", stats.gridProbes},
                   {"user", stats.userProbes},
                   {"rejected", stats.rejectedProbes},
                   {"surface", stats.surfaceProbes},
                   {"volume", stats.volumeProbes},
                   {"open", stats.openProbes},
                   {"filler", stats.fillerProbes},
                   {"filler_at_slivers", stats.sliverFillers},
                   {"shell", stats.shellProbes},
                   {"dilated", stats.dilatedProbes},
                   {"pushed", stats.pushedProbes},
                   {"merged", stats.mergedProbes}};
    j["tets"] = {
        {"count", level.tets.size()},
        {"min_dihedral_deg", stats.minDihedral},
        {"min_dihedral_deg_before_filler", stats.minDihedralBeforeFiller},
        {"min_dihedral_deg_before_holes", stats.minDihedralBeforeHoles},
        {"quality_histogram", {{"bin_deg", 5}, {"min_dihedral", stats.dihedralHistogram}}},
        {"below_1_5_10_deg", stats.tetsBelow},
        {"worst_tet", stats.worstTet},
        {"worst_tet_before_holes", stats.worstTetBeforeHoles},
        {"late_pass",
         {{"ran", stats.latePass},
          {"min_dihedral_deg_before", stats.minDihedralBeforeLate},
          {"bound_deg", stats.lateTargetDeg},
          {"quality_histogram_before", {{"bin_deg", 5}, {"min_dihedral", stats.dihedralHistogramBeforeLate}}},
          {"below_1_5_10_deg_before", stats.tetsBelowBeforeLate},
          {"worst_tet_before", stats.worstTetBeforeLate},
          {"fillers_added", stats.lateFillers},
          {"probes_moved", stats.lateMoved},
          {"probes_removed", stats.lateRemoved},
          {"hole_probes_removed", stats.lateRemovedHole},
          {"refinement_probes_removed", stats.lateRemovedRefinement}}},
        {"outer_cells", level.outerCells.size()}};
    j["sh"] = {{"order", opt.bake.shOrder},
               {"deringed_probes", stats.dering.deringedProbes},
               {"unfixable_probes", stats.dering.unfixableProbes},
               {"max_dering_strength", stats.dering.maxStrength},
               {"min_irradiance_before", stats.dering.minIrradianceBefore},
               {"min_irradiance_after", stats.dering.minIrradianceAfter}};
    j["bake"] = {{"rays", stats.bake.rays()},
                 {"intersect_rays", stats.bake.intersectRays},
                 {"occluded_rays", stats.bake.occludedRays},
                 {"seconds", stats.bake.seconds},
                 {"rays_per_s", stats.bake.raysPerSecond()},
                 {"paths", stats.bake.paths},
                 {"max_paths_per_probe", stats.bake.maxPathsPerProbe},
                 {"noise",
                  {{"target", opt.bake.targetRelError},
                   {"mean_rel_stderr", stats.bake.meanRelError},
                   {"p95_rel_stderr", stats.bake.p95RelError},
                   {"max_rel_stderr", stats.bake.maxRelError},
                   {"probes_above_target", stats.bake.probesAtCap},
                   {"path_budget", opt.bake.pathBudget},
                   {"budget_paths", stats.bake.budgetPaths},
                   {"by_kind", noiseKinds}}},
                 {"imported", stats.importedProbes > 0}};
    j["occlusion"] = {{"mode", occlusionModeName(opt.occlusion.mode)},
                      {"none", level.occlusion.empty() ? level.tets.size() : stats.occlusion.none},
                      {"planes", stats.occlusion.planeTets},
                      {"shadow_maps", stats.occlusion.shadowMapTets},
                      {"tets_with_geometry", stats.occlusion.tetsWithGeometry},
                      {"bytes", level.occlusion.bytes()},
                      {"agreement", stats.occlusion.agreement},
                      {"blackouts", stats.occlusion.blackouts}};
    nlohmann::json rounds = nlohmann::json::array();
    for (const auto& r : stats.holeRounds)
      rounds.push_back({{"points_checked", r.checked},
                        {"hole_points", r.holes},
                        {"fallback_probe_seen", r.seen},
                        {"probes_added", r.added}});
    nlohmann::json lookupRounds = nlohmann::json::array();
    for (const auto& r : stats.lookupHoleRounds)
      lookupRounds.push_back(
          {{"points_checked", r.checked}, {"lookup_fallback_points", r.holes}, {"probes_added", r.added}});
    j["holes"] = {{"rounds", rounds},
                  {"lookup_rounds", lookupRounds},
                  {"probes_added", stats.holeProbes},
                  {"final_points_checked", stats.finalChecked},
                  {"final_hole_points", stats.finalHoles},
                  {"final_lookup_fallback_points", stats.finalLookupFallbacks - stats.finalClosedFallbacks},
                  {"final_closed_fallback_points", stats.finalClosedFallbacks}};
    j["refine"] = {{"probes_added", stats.refineProbes},
                   {"points", stats.refineBefore.points},
                   {"mean_log2_error_before", stats.refineBefore.meanLogError},
                   {"mean_log2_error_after", stats.refineAfter.meanLogError},
                   {"gross_before", stats.refineBefore.gross},
                   {"gross_after", stats.refineAfter.gross}};
    j["fit"] = {
        {"mode", opt.fit},
        {"ran", stats.fitRan},
        {"kept", stats.fitKept},
        {"lambda", opt.fitLambda},
        {"max_move", opt.fitMaxMove},
        {"points", stats.fit.points},
        {"fitted_points", stats.fit.fitted},
        {"fallback_points", stats.fit.fallbackPoints},
        {"skipped_points", stats.fit.otherSkipped},
        {"probes_touched", stats.fit.probesTouched},
        {"capped_probes", stats.fit.cappedProbes},
        {"cross_validate", opt.fitValidate},
        {"held_probes", stats.fit.heldProbes},
        {"cg_iterations", {stats.fit.iterations[0], stats.fit.iterations[1], stats.fit.iterations[2]}},
        {"objective_before", stats.fit.objectiveBefore},
        {"objective_after", stats.fit.objectiveAfter},
        {"holdout_points", stats.fitHoldoutBefore.points},
        {"holdout_mean_rel_error_before", stats.fitHoldoutBefore.meanRelError},
        {"holdout_mean_rel_error_after", stats.fitHoldoutAfter.meanRelError},
        {"holdout_gross_before", stats.fitHoldoutBefore.gross},
        {"holdout_gross_after", stats.fitHoldoutAfter.gross}};
    j["locate"] = {{"cell_size_m", grid.cellSize},
                   {"cells", gridCells},
                   {"hash_slots", grid.slots.size()},
                   {"bsp_nodes", grid.nodes.size()},
                   {"leaves", grid.leaves},
                   {"unproven_leaves", grid.unprovenLeaves},
                   {"max_depth", grid.maxDepth},
                   {"mean_depth", grid.meanDepth},
                   {"bytes", gridBytes}};
    nlohmann::json timings = nlohmann::json::object();
    for (const auto& [stage, s] : stats.timings) timings[stage] = s;
    timings["total"] = total;
    j["timings_s"] = timings;
    if (farm)
      j["farm"] = {{"workers", merge->farmWorkers}, {"jobs", farm->jobs()},
                   {"probe_steps", farm->items()},  {"reference_points", farm->points()},
                   {"wait_s", farm->waitSeconds()}, {"serial_s", total - farm->waitSeconds()}};
    j["bytes"] = {{"total", fileBytes}, {"probes", probeBytes}, {"sh", shBytes}, {"tets", tetBytes}};
    writeJsonReport(args.str("--report"), j);
  }
  return 0;
}

int cmdBake(int argc, char** argv) {
  return runBake(argc, argv, nullptr);
}

}  // namespace tetraprobe::cli
