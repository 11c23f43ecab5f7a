// `tetraprobe bake`'s options: the table whose defaults come from PipelineOptions{}, the checked parse into
// PipelineOptions, and the generator string that records every option changing the level and reads back.
#include "pipeline_options.h"

#include <charconv>
#include <cmath>
#include <filesystem>
#include <map>
#include <sstream>

#include "tetraprobe/common/error.h"
#include "tetraprobe/eval/grid_volume.h"

namespace tetraprobe::cli {

namespace {

// The shortest text that parses back to exactly `v` (std::to_chars without a format).
std::string exactNumber(double v) {
  char buf[64];
  const auto r = std::to_chars(buf, buf + sizeof buf, v);
  return std::string(buf, r.ptr);
}

std::string fileName(const std::string& path) {
  return std::filesystem::path(path).filename().string();
}

// levelOptions(PipelineOptions{}) by name: the defaults the option table shows.
std::map<std::string, std::string> defaultValues() {
  std::map<std::string, std::string> out;
  for (auto& [name, value] : levelOptions(PipelineOptions{})) out[name] = value;
  return out;
}

}  // namespace

std::vector<OptionSpec> bakeOptionSpecs() {
  const std::map<std::string, std::string> d = defaultValues();
  auto def = [&d](const std::string& name) { return d.at(name); };
  return {
      {"--output", "-o", "LEVEL.tpb", "level file to write", ""},
      {"--report", "", "FILE.json", "also write a JSON report of the bake", ""},
      {"--options-from", "", "LEVEL.tpb",
       "bake with every option that changes the level taken from LEVEL's generator string (`inspect` shows "
       "it), so the same scene gives the same level byte for byte; options given here override them; a "
       "level baked from --probes or --import-sh needs that file given again",
       ""},
      {"--spacing", "", "auto|METRES",
       "finest probe spacing (voxel edge near geometry and in fine volumes; grid step); auto = 1 m, or for "
       "a scene under 8 m across the largest power of two of a metre giving 8 voxels along its largest "
       "extent",
       def("--spacing")},
      {"--probes", "", "FILE.csv",
       "user probes (x,y,z a line), kept exactly: alone (or with --placement none) they are the level's only "
       "probes, and --fill-holes and --probe-budget default to 0 (give them to add probes); with "
       "--placement voxel they are added to the automatic ones (automatic probes near them are dropped)",
       ""},
      {"--placement", "", "voxel|grid|none",
       "voxel: probes in empty voxels next to geometry, coarser cells in open space, filler probes; grid: a "
       "regular grid (for comparison); none: only --probes",
       def("--placement")},
      {"--max-spacing", "", "METRES", "voxel: coarsest open-space cell", def("--max-spacing")},
      {"--filler-spacing", "", "METRES", "voxel: open-space filler lattice (0 = none)",
       def("--filler-spacing")},
      {"--shell-spacing", "", "auto|METRES",
       "voxel: shell probes on the level's bounds grown outward, so every surface lies inside a tet where "
       "occlusion applies (docs/occlusion.md): this step within 2 steps of a surface, --max-spacing "
       "elsewhere "
       "(an open level's top and sides); auto = --spacing, 0 = none",
       def("--shell-spacing")},
      {"--tetra", "", "cgal|tetgen",
       "tetrahedralizer: CGAL Delaunay + circumcentre fillers at slivers, or TetGen Delaunay + quality "
       "refinement whose Steiner points become fillers",
       def("--tetra")},
      {"--bounces", "", "N|unbounded",
       "diffuse bounces after the first hit; unbounded = Russian roulette only (unbiased)", def("--bounces")},
      {"--samples", "", "N", "paths per probe: the minimum with --noise, else exactly N", def("--samples")},
      {"--noise", "", "E",
       "adaptive sampling: each probe takes batches of 64 paths until the standard error of its irradiance "
       "is at most E x its mean (0 = exactly --samples paths)",
       def("--noise")},
      {"--max-samples", "", "N", "adaptive sampling: paths per probe at most", def("--max-samples")},
      {"--guide", "", "on|off",
       "adaptive sampling: after --samples paths, a probe's later batches draw half their directions toward "
       "where its earlier paths found light (path guiding of the first direction; unbiased; "
       "docs/accuracy.md#probe-guiding)",
       def("--guide")},
      {"--lit-patches", "", "probe|bounces|off",
       "adaptive sampling, with --guide, for probes that would stop at --max-samples: their later batches "
       "also "
       "draw points on the surfaces their paths found lit by point, spot or sun lights, MIS-weighted against "
       "their directions (unbiased); bounces: their paths' first three hits too (costlier; "
       "docs/accuracy.md#lit-patch-sampling)",
       def("--lit-patches")},
      {"--path-budget", "", "N",
       "adaptive sampling: paths the bake may spend in all (the probes the hole and refinement rounds add "
       "trace their first paths besides); once every probe is placed, what is left (with --share-caps on, at "
       "least what --max-samples a probe would have spent) is shared among the probes above --noise, the "
       "noisier the more (each at most 16 x --max-samples), so a small level converges; 0 = none",
       def("--path-budget")},
      {"--share-caps", "", "on|off",
       "adaptive sampling with --path-budget: on: probes first stop at half of --max-samples, and the "
       "budget, once every probe is placed, spends at least what --max-samples a probe would have (each "
       "probe's paths to --noise as its error projects them, at most --max-samples), the noisier a probe "
       "the larger its share (one lit map for the whole bake); off: every probe up to --max-samples first, "
       "the budget only beyond",
       def("--share-caps")},
      {"--content", "", "default|all",
       "default: everything but light arriving directly from point/spot/sun lights (drawn in real "
       "time); all: that too",
       def("--content")},
      {"--seed", "", "N",
       "random seed, an integer in [0, 2^64-1] (the output is a pure function of input, options and seed)",
       def("--seed")},
      {"--dering", "", "none|auto|window|S",
       "make each probe's irradiance non-negative (SH L2 rings): auto = per channel the nearest "
       "non-negative field with the same mean (the dark side stays dark), window = the smallest Hann "
       "window on bands 1-2 per probe (lifts the dark side), S = this window strength in [0, 2] for all, "
       "none = keep the SH as projected",
       def("--dering")},
      {"--sh-order", "", "1|2", "SH order of the probes (1: coefficients 4..8 zero)", def("--sh-order")},
      {"--import-sh", "", "FILE.csv",
       "take probe positions and SH from another baker (x,y,z + 27 coefficients a line, see "
       "bake/include/tetraprobe/bake/sh_csv.h) instead of placing and path tracing",
       ""},
      {"--occlusion", "", "auto|none|planes|shadow-maps",
       "per-tet occlusion against light leaking, stored in the level (docs/occlusion.md): auto = the "
       "cheapest of none, 1-3 planes, shadow maps that meets --min-agreement; none = store nothing",
       def("--occlusion")},
      {"--min-agreement", "", "F", "occlusion auto mode: fraction of ray answers the data must match",
       def("--min-agreement")},
      {"--fill-holes", "", "ROUNDS",
       "rounds of occlusion-hole filling: surface points that see none of their tet's probes get a probe in "
       "front of them, then tetrahedralize, bake and occlude again; stops early when none are left (0 = "
       "none, the default with --probes alone)",
       def("--fill-holes")},
      {"--hole-rule", "", "all|unseen",
       "which hole points get a probe: all of them, or only those whose fallback does not already answer "
       "with a probe they see (reached by a ray, not darker than the blend capping the fallback): fewer "
       "probes, smaller levels and shorter bakes, accuracy mixed (docs/accuracy.md)",
       def("--hole-rule")},
      {"--lookup-holes", "", "ROUNDS",
       "rounds after refinement that add a probe an eighth of the spacing in front of surface points where "
       "the "
       "lookup's answer (after the blend over the probes' stars) still falls back; stops when none do; needs "
       "--fill-holes > 0 (0 = none)",
       def("--lookup-holes")},
      {"--probe-budget", "", "N|auto",
       "error-driven refinement: at most N probes added in front of the surface points where the lookup's "
       "error against the path-traced oracle is largest (only where it exceeds 7 %); auto = a quarter of "
       "the placed probes (shell probes not counted), at least 1024; 0 = none (the default with --probes "
       "alone)",
       def("--probe-budget")},
      {"--refine-points", "", "N|auto",
       "refinement: surface points the error is measured at (twice: select, check); auto = one per "
       "spacing x spacing of surface, at least 2048 and at least the probe budget, so that every part of a "
       "larger level is measured as densely as a room",
       def("--refine-points")},
      {"--refine-offset", "", "auto|METRES",
       "refinement: how far in front of its surface point a new probe sits at most (half the free "
       "distance when less); auto = spacing / 8, close enough to see what the surface sees",
       def("--refine-offset")},
      {"--late-slivers", "", "fix|keep",
       "after hole and refinement probes: fix = bring the final mesh's worst tet back to the worst before "
       "them (late fillers, then the late probe of each sliver left is dropped; docs/occlusion.md); keep = "
       "leave their slivers (the default: dropping refinement probes cost the Cornell box accuracy)",
       def("--late-slivers")},
      {"--late-nudge", "", "ROUNDS",
       "late sliver pass: rounds that move the late probes at slivers (a short step away from the sliver's "
       "opposite faces, then traced again) before any is dropped; 0 = drop only",
       def("--late-nudge")},
      {"--late-fillers", "", "N",
       "late sliver pass: filler probes it may add (each baked like a refinement probe) before it drops "
       "late probes",
       def("--late-fillers")},
      {"--late-min-dihedral", "", "auto|DEG",
       "late sliver pass: the min dihedral it brings the final mesh's tets to, at most the worst tet's "
       "before "
       "hole and refinement probes; auto = that worst (on some levels it drops most of those probes and "
       "their accuracy: docs/occlusion.md)",
       def("--late-min-dihedral")},
      {"--fit", "", "auto|on|off",
       "fit the probe SH to the traced irradiance of surface points (least squares through the lookup's own "
       "weights, pulled toward the traced values; docs/accuracy.md): on = always, auto = kept only when the "
       "error at independent points drops, off = the traced SH",
       def("--fit")},
      {"--fit-lambda", "", "F", "fit: weight of the pull toward each probe's traced SH (by its noise)",
       def("--fit-lambda")},
      {"--fit-max-move", "", "F", "fit: a probe's RMS irradiance change at most F x its mean irradiance",
       def("--fit-max-move")},
      {"--fit-validate", "", "on|off",
       "fit: hold at its traced SH each probe whose fit, cross-validated on two halves of the points, "
       "worsens the points it was not fitted to",
       def("--fit-validate")},
      {"--fit-points", "", "N|auto",
       "fit: area-uniform surface points (auto = 6 per probe that is not a shell probe, 2048 to 16384)",
       def("--fit-points")},
      {"--fit-samples", "", "N", "fit: reference paths per fit and hold-out point", def("--fit-samples")},
      {"--fit-holdout", "", "N", "fit: independent points scoring the level before and after",
       def("--fit-holdout")},
      {"--threads", "", "N", "worker threads, 0 = all cores (never changes the output)",
       std::to_string(PipelineOptions{}.bake.threads)},
      {"--shard", "", "I/N",
       "sharded bake (docs/distributed.md): place the probes, trace passes 1-2 of shard I's probes (of N "
       "equal-count x slabs) and write their states to -o as a part file for `tetraprobe merge`",
       ""},
      {"--round", "", "both|1|2",
       "with --shard: both = passes 1-2 in one run (pass 1 of every probe is traced by every shard); "
       "1 = pass 1 of the shard's probes only; 2 = pass 2, from --resume and --floor",
       "both"},
      {"--floor", "", "FILE",
       "--round 2: the floor part `tetraprobe merge --floor` made of the round-1 parts", ""},
      {"--resume", "", "FILE", "--round 2: this shard's round-1 part", ""}};
}

PipelineOptions pipelineOptionsFromArgs(const Args& args) {
  PipelineOptions opt;
  opt.spacing = args.str("--spacing") == "auto" ? 0.0 : parseNumber(args.str("--spacing"), "--spacing");
  if (args.str("--spacing") != "auto" && (!(opt.spacing > 0.0) || !std::isfinite(opt.spacing)))
    throw UsageError("--spacing must be auto or a positive number of metres");
  opt.probesCsv = args.str("--probes");
  if (args.has("--placement"))
    opt.placement = args.str("--placement");
  else if (!opt.probesCsv.empty())
    opt.placement = "none";
  if (opt.placement != "voxel" && opt.placement != "grid" && opt.placement != "none")
    throw UsageError("--placement must be voxel, grid or none, not '" + opt.placement + "'");
  if (opt.placement == "none" && opt.probesCsv.empty())
    throw UsageError("--placement none needs --probes FILE.csv");
  if (opt.placement == "grid" && !opt.probesCsv.empty())
    throw UsageError("--placement grid does not take --probes (use voxel or none)");
  opt.maxSpacing = args.number("--max-spacing");
  // (auto resolves to at most 1 m, so checking it as 1 m holds for it too)
  if (!(opt.maxSpacing >= (opt.spacing > 0.0 ? opt.spacing : 1.0)))
    throw UsageError("--max-spacing must be at least --spacing");
  opt.fillerSpacing = args.number("--filler-spacing");
  if (!(opt.fillerSpacing >= 0.0)) throw UsageError("--filler-spacing must be >= 0");
  const std::string shellSpacing = args.str("--shell-spacing");
  opt.shellSpacing = shellSpacing == "auto" ? -1.0 : parseNumber(shellSpacing, "--shell-spacing");
  if (!(opt.shellSpacing >= 0.0 || shellSpacing == "auto") || !std::isfinite(opt.shellSpacing))
    throw UsageError("--shell-spacing must be auto or a finite number >= 0");
  opt.tetra = args.str("--tetra");
  if (opt.tetra != "cgal" && opt.tetra != "tetgen")
    throw UsageError("--tetra must be cgal or tetgen, not '" + opt.tetra + "'");
  opt.importShCsv = args.str("--import-sh");
  if (!opt.probesCsv.empty() && !opt.importShCsv.empty())
    throw UsageError("--probes and --import-sh both give the probes; use one");
  const std::string shOrder = args.str("--sh-order");
  if (shOrder != "1" && shOrder != "2") throw UsageError("--sh-order must be 1 or 2, not '" + shOrder + "'");
  opt.bake.shOrder = shOrder == "1" ? 1 : 2;
  const std::string dering = args.str("--dering");
  if (dering == "none") {
    opt.dering.mode = DeringMode::kNone;
  } else if (dering == "auto") {
    opt.dering.mode = DeringMode::kAuto;
  } else if (dering == "window") {
    opt.dering.mode = DeringMode::kWindow;
  } else {
    opt.dering.mode = DeringMode::kFixed;
    opt.dering.strength = parseNumber(dering, "--dering");
    if (!(opt.dering.strength >= 0.0 && opt.dering.strength <= kDeringMaxStrength))
      throw UsageError("--dering must be none, auto, window or a strength in [0, 2], not '" + dering + "'");
  }
  opt.bake.bounces = args.bounces("--bounces");
  opt.bake.samplesPerProbe = args.integer("--samples");
  opt.bake.threads = args.integer("--threads");
  opt.bake.seed = args.u64("--seed");
  if (opt.bake.samplesPerProbe < 1) throw UsageError("--samples must be at least 1");
  opt.bake.targetRelError = args.number("--noise");
  opt.bake.maxSamplesPerProbe = args.integer("--max-samples");
  if (args.str("--guide") != "on" && args.str("--guide") != "off")
    throw UsageError("--guide must be on or off, not '" + args.str("--guide") + "'");
  opt.bake.guide = args.str("--guide") == "on";
  const std::string lit = args.str("--lit-patches");
  if (lit != "probe" && lit != "bounces" && lit != "off")
    throw UsageError("--lit-patches must be probe, bounces or off, not '" + lit + "'");
  opt.bake.litPatches = lit == "off"     ? LitPatches::kOff
                        : lit == "probe" ? LitPatches::kProbe
                                         : LitPatches::kBounces;
  if (args.str("--share-caps") != "on" && args.str("--share-caps") != "off")
    throw UsageError("--share-caps must be on or off, not '" + args.str("--share-caps") + "'");
  opt.shareCaps = args.str("--share-caps") == "on";
  const double pathBudget = args.number("--path-budget");
  if (!(pathBudget >= 0.0 && pathBudget <= 1e15))
    throw UsageError("--path-budget must be a number of paths in [0, 1e15]");
  opt.bake.pathBudget = uint64_t(pathBudget);
  if (!(opt.bake.targetRelError >= 0.0) || !std::isfinite(opt.bake.targetRelError))
    throw UsageError("--noise must be a finite number >= 0");
  if (opt.bake.targetRelError > 0.0 && opt.bake.maxSamplesPerProbe < opt.bake.samplesPerProbe)
    throw UsageError("--max-samples must be at least --samples");
  if (opt.bake.threads < 0) throw UsageError("--threads must be >= 0");
  const std::string content = args.str("--content");
  if (content == "default")
    opt.bake.content = kContentDefault;
  else if (content == "all")
    opt.bake.content = kContentAll;
  else
    throw UsageError("--content must be 'default' or 'all', not '" + content + "'");

  if (!parseOcclusionMode(args.str("--occlusion"), opt.occlusion.mode))
    throw UsageError("--occlusion must be auto, none, planes or shadow-maps, not '" +
                     args.str("--occlusion") + "'");
  opt.occlusion.minAgreement = args.number("--min-agreement");
  opt.holeRounds = args.integer("--fill-holes");
  if (args.str("--hole-rule") != "all" && args.str("--hole-rule") != "unseen")
    throw UsageError("--hole-rule must be all or unseen, not '" + args.str("--hole-rule") + "'");
  opt.holesOnlyUnseen = args.str("--hole-rule") == "unseen";
  opt.lookupHoleRounds = args.integer("--lookup-holes");
  if (opt.lookupHoleRounds < 0 || opt.lookupHoleRounds > 16)
    throw UsageError("--lookup-holes must be in [0, 16]");
  opt.probeBudget = args.str("--probe-budget") == "auto" ? -1 : args.integer("--probe-budget");
  // User probes alone are the level's probes: hole filling and refinement add probes only when asked.
  if (opt.placement == "none") {
    if (!args.has("--fill-holes")) opt.holeRounds = 0;
    if (!args.has("--probe-budget")) opt.probeBudget = 0;
  }
  opt.refinePoints = args.str("--refine-points") == "auto" ? -1 : args.integer("--refine-points");
  if (opt.probeBudget < -1) throw UsageError("--probe-budget must be auto or >= 0");
  if (opt.refinePoints == 0 || opt.refinePoints < -1)
    throw UsageError("--refine-points must be auto or >= 1");
  if (args.str("--refine-offset") != "auto") {
    opt.refineOffset = args.number("--refine-offset");
    if (!(opt.refineOffset > 0.0) || !std::isfinite(opt.refineOffset))
      throw UsageError("--refine-offset must be auto or a positive number of metres");
  }
  if (args.str("--late-slivers") != "fix" && args.str("--late-slivers") != "keep")
    throw UsageError("--late-slivers must be fix or keep, not '" + args.str("--late-slivers") + "'");
  opt.lateSlivers = args.str("--late-slivers") == "fix";
  opt.lateFillers = args.integer("--late-fillers");
  opt.lateNudgeRounds = args.integer("--late-nudge");
  if (opt.lateNudgeRounds < 0 || opt.lateNudgeRounds > 16)
    throw UsageError("--late-nudge must be in [0, 16]");
  opt.lateMinDihedral = -1.0;
  if (args.str("--late-min-dihedral") != "auto") {
    opt.lateMinDihedral = args.number("--late-min-dihedral");
    if (!(opt.lateMinDihedral >= 0.0 && opt.lateMinDihedral < 70.0))
      throw UsageError("--late-min-dihedral must be auto or a number of degrees in [0, 70)");
  }
  if (opt.lateFillers < 0) throw UsageError("--late-fillers must be >= 0");
  opt.fit = args.str("--fit");
  if (opt.fit != "auto" && opt.fit != "on" && opt.fit != "off")
    throw UsageError("--fit must be auto, on or off, not '" + opt.fit + "'");
  opt.fitLambda = args.number("--fit-lambda");
  if (!(opt.fitLambda >= 0.0) || !std::isfinite(opt.fitLambda))
    throw UsageError("--fit-lambda must be a finite number >= 0");
  opt.fitMaxMove = args.number("--fit-max-move");
  if (!(opt.fitMaxMove >= 0.0) || !std::isfinite(opt.fitMaxMove))
    throw UsageError("--fit-max-move must be a finite number >= 0");
  if (args.str("--fit-validate") != "on" && args.str("--fit-validate") != "off")
    throw UsageError("--fit-validate must be on or off, not '" + args.str("--fit-validate") + "'");
  opt.fitValidate = args.str("--fit-validate") == "on";
  opt.fitPoints = args.str("--fit-points") == "auto" ? -1 : args.integer("--fit-points");
  if (opt.fitPoints < -1) throw UsageError("--fit-points must be auto or >= 0");
  opt.fitSamples = args.integer("--fit-samples");
  if (opt.fitSamples < 1) throw UsageError("--fit-samples must be >= 1");
  opt.fitHoldout = args.integer("--fit-holdout");
  if (opt.fitHoldout < 1) throw UsageError("--fit-holdout must be >= 1");
  if (opt.holeRounds < 0 || opt.holeRounds > 16) throw UsageError("--fill-holes must be in [0, 16]");
  if (!(opt.occlusion.minAgreement >= 0.0 && opt.occlusion.minAgreement <= 1.0))
    throw UsageError("--min-agreement must be in [0, 1]");
  return opt;
}

std::vector<std::pair<std::string, std::string>> levelOptions(const PipelineOptions& o) {
  std::vector<std::pair<std::string, std::string>> v;
  auto add = [&v](const char* name, std::string value) { v.emplace_back(name, std::move(value)); };
  add("--spacing", o.spacing > 0.0 ? exactNumber(o.spacing) : "auto");
  if (!o.probesCsv.empty()) add("--probes", fileName(o.probesCsv));
  add("--placement", o.placement);
  add("--max-spacing", exactNumber(o.maxSpacing));
  add("--filler-spacing", exactNumber(o.fillerSpacing));
  add("--shell-spacing", o.shellSpacing < 0.0 ? "auto" : exactNumber(o.shellSpacing));
  add("--tetra", o.tetra);
  add("--bounces", o.bake.bounces == kUnboundedBounces ? "unbounded" : std::to_string(o.bake.bounces));
  add("--samples", std::to_string(o.bake.samplesPerProbe));
  add("--noise", exactNumber(o.bake.targetRelError));
  add("--max-samples", std::to_string(o.bake.maxSamplesPerProbe));
  add("--guide", o.bake.guide ? "on" : "off");
  add("--lit-patches", o.bake.litPatches == LitPatches::kOff     ? "off"
                       : o.bake.litPatches == LitPatches::kProbe ? "probe"
                                                                 : "bounces");
  add("--path-budget", std::to_string(o.bake.pathBudget));
  add("--share-caps", o.shareCaps ? "on" : "off");
  if (o.bake.content != kContentDefault && o.bake.content != kContentAll)
    throw std::logic_error("levelOptions: content flags " + std::to_string(o.bake.content) +
                           " are neither default nor all");
  add("--content", o.bake.content == kContentAll ? "all" : "default");
  add("--seed", std::to_string(o.bake.seed));
  add("--dering", o.dering.mode == DeringMode::kNone     ? "none"
                  : o.dering.mode == DeringMode::kAuto   ? "auto"
                  : o.dering.mode == DeringMode::kWindow ? "window"
                                                         : exactNumber(o.dering.strength));
  add("--sh-order", std::to_string(o.bake.shOrder));
  if (!o.importShCsv.empty()) add("--import-sh", fileName(o.importShCsv));
  add("--occlusion", occlusionModeName(o.occlusion.mode));
  add("--min-agreement", exactNumber(o.occlusion.minAgreement));
  add("--fill-holes", std::to_string(o.holeRounds));
  add("--hole-rule", o.holesOnlyUnseen ? "unseen" : "all");
  add("--lookup-holes", std::to_string(o.lookupHoleRounds));
  add("--probe-budget", o.probeBudget < 0 ? "auto" : std::to_string(o.probeBudget));
  add("--refine-points", o.refinePoints < 0 ? "auto" : std::to_string(o.refinePoints));
  add("--refine-offset", o.refineOffset > 0.0 ? exactNumber(o.refineOffset) : "auto");
  add("--late-slivers", o.lateSlivers ? "fix" : "keep");
  add("--late-fillers", std::to_string(o.lateFillers));
  add("--late-nudge", std::to_string(o.lateNudgeRounds));
  add("--late-min-dihedral", o.lateMinDihedral < 0.0 ? "auto" : exactNumber(o.lateMinDihedral));
  add("--fit", o.fit);
  add("--fit-lambda", exactNumber(o.fitLambda));
  add("--fit-max-move", exactNumber(o.fitMaxMove));
  add("--fit-validate", o.fitValidate ? "on" : "off");
  add("--fit-points", o.fitPoints < 0 ? "auto" : std::to_string(o.fitPoints));
  add("--fit-samples", std::to_string(o.fitSamples));
  add("--fit-holdout", std::to_string(o.fitHoldout));
  return v;
}

std::string generatorString(const PipelineOptions& options) {
  std::string s = "tetraprobe 0.1.0 bake";
  for (const auto& [name, value] : levelOptions(options)) s += " " + name + "=" + value;
  return s;
}

std::vector<std::string> generatorArguments(const std::string& generator) {
  std::vector<std::string> out;
  const std::vector<std::pair<std::string, std::string>> fields = generatorFields(generator);
  std::map<std::string, std::string> legacy;  // "key=value; " items: key -> value
  for (const auto& [key, value] : fields) {
    if (key.rfind("--", 0) == 0)
      out.push_back(key + "=" + value);
    else
      legacy[key] = value;
  }
  if (!out.empty() || legacy.empty()) return out;
  // Written before the option list: the keys it had, by the option each is.
  const std::pair<const char*, const char*> renamed[] = {{"tetra", "--tetra"},
                                                         {"spacing", "--spacing"},
                                                         {"bounces", "--bounces"},
                                                         {"samples", "--samples"},
                                                         {"target_error", "--noise"},
                                                         {"max_samples", "--max-samples"},
                                                         {"content", "--content"},
                                                         {"seed", "--seed"},
                                                         {"sh_order", "--sh-order"},
                                                         {"dering", "--dering"},
                                                         {"occlusion", "--occlusion"},
                                                         {"min_agreement", "--min-agreement"},
                                                         {"hole_rounds", "--fill-holes"},
                                                         {"hole_rule", "--hole-rule"},
                                                         {"path_budget", "--path-budget"}};
  for (const auto& [key, option] : renamed) {
    auto it = legacy.find(key);
    std::string value = it != legacy.end() ? it->second : "";
    if (key == std::string("path_budget") && value.empty()) value = "0";  // baked before the budget existed
    if (value.empty()) continue;
    if (key == std::string("bounces") && value == std::to_string(kUnboundedBounces)) value = "unbounded";
    out.push_back(std::string(option) + "=" + value);
  }
  // Placement "user" or "imported" came from a file these did not name: the default placement.
  if (auto it = legacy.find("placement");
      it != legacy.end() && (it->second == "voxel" || it->second == "grid"))
    out.push_back("--placement=" + it->second);
  // The shell spacing was written resolved: equal to the spacing, it was auto.
  if (auto it = legacy.find("shell_spacing"); it != legacy.end())
    out.push_back("--shell-spacing=" +
                  (legacy.count("spacing") && legacy["spacing"] == it->second ? "auto" : it->second));
  return out;
}

PipelineOptions pipelineOptionsFromGenerator(const std::string& generator, std::vector<std::string>* found) {
  std::vector<std::string> line = generatorArguments(generator);
  if (found) {
    found->clear();
    for (const std::string& a : line) found->push_back(a.substr(0, a.find('=')));
  }
  std::vector<char*> argv;
  for (std::string& a : line) argv.push_back(a.data());
  Args args("tetraprobe bake", "", bakeOptionSpecs());
  try {
    args.parse(int(argv.size()), argv.data());
    return pipelineOptionsFromArgs(args);
  } catch (const UsageError& e) {
    throw InputError("the level's generator string: " + std::string(e.what()));
  }
}

}  // namespace tetraprobe::cli
