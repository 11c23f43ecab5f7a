// `tetraprobe eval SCENE LEVEL.tpb`: probe lookup error against path-traced ground truth, with cost.
#include <algorithm>
#include <cstdio>

#include "args.h"
#include "commands.h"
#include "tetraprobe/common/error.h"
#include "tetraprobe/eval/evaluate.h"
#include "tetraprobe/occlusion/build_occlusion.h"
#include "tetraprobe/runtime/file_io.h"
#include "tetraprobe/runtime/occlusion.h"
#include "tetraprobe/scene/load.h"

namespace tetraprobe::cli {

int cmdEval(int argc, char** argv) {
  Args args(
      "tetraprobe eval SCENE LEVEL.tpb [options]",
      "Path-traces reference irradiance at random surface points (same light content as the level)\n"
      "and compares each lookup method with it. Error measures are defined in docs/evaluation.md.",
      {{"--points", "", "N", "random surface points", "512"},
       {"--samples", "", "N", "reference paths per point", "4096"},
       {"--bounces", "", "N", "reference path depth (ground truth, independent of the bake)", "8"},
       {"--seed", "", "N", "random seed for points and paths", "1"},
       {"--threads", "", "N", "worker threads, 0 = all cores", "0"},
       {"--occlusion", "", "auto|none|planes|shadow-maps",
        "for a level without stored occlusion: also score tet+occlusion, with occlusion data built from the "
        "scene in this mode (a level that stores occlusion scores `tet` with it and `tet (no occlusion)`)",
        "auto"},
       {"--min-agreement", "", "F", "occlusion auto mode: fraction of ray answers the data must match",
        "0.98"},
       {"--report", "", "FILE.json", "write the figures as JSON", ""},
       {"--points-out", "", "FILE.csv",
        "write every point: position, normal, reference, stderr, direct part of the reference, lookups",
        ""}});
  if (!args.parse(argc, argv)) return 0;
  args.requirePositional(2, 2);
  EvalOptions opt;
  opt.points = args.integer("--points");
  opt.samplesPerPoint = args.integer("--samples");
  opt.referenceBounces = args.integer("--bounces");
  opt.seed = uint64_t(args.number("--seed"));
  opt.threads = args.integer("--threads");
  if (opt.points < 1 || opt.samplesPerPoint < 1 || opt.referenceBounces < 0 || opt.threads < 0)
    throw UsageError("--points and --samples must be >= 1, --bounces and --threads >= 0");

  const Scene scene = loadScene(args.positional()[0]);
  Level level;
  if (const LevelResult r = loadLevel(args.positional()[1], level); !r) throw InputError(r.message);
  const SceneTracer tracer(scene);

  EvalReport report = computeReference(tracer, level.content, opt);
  for (const auto& m : standardMethods(level)) scoreMethod(report, m);
  OcclusionStats occStats;
  OcclusionMode occMode;
  if (!parseOcclusionMode(args.str("--occlusion"), occMode))
    throw UsageError("--occlusion must be auto, none, planes or shadow-maps");
  const bool stored = !level.occlusion.empty();
  if (stored) occMode = OcclusionMode::kNone;  // the level's own data is scored through `tet`
  if (occMode != OcclusionMode::kNone) {
    OcclusionOptions occOpt;
    occOpt.mode = occMode;
    occOpt.minAgreement = args.number("--min-agreement");
    occOpt.threads = opt.threads;
    auto occlusion = std::make_shared<const LevelOcclusion>(buildOcclusion(tracer, level, occOpt, &occStats));
    scoreMethod(report, occlusionMethod(level, occlusion));
  }

  std::printf("tetraprobe eval: %zu points, %d paths each (%d bounces), mean relative stderr %.4f, %.1fs\n",
              report.points.size(), report.samplesPerPoint, report.referenceBounces, report.meanRelStderr,
              report.referenceSeconds);
  if (occMode != OcclusionMode::kNone)
    std::printf(
        "  occlusion (%s): %zu tets with geometry: %zu none, %zu planes, %zu shadow maps; %zu bytes; "
        "agreement %.3f\n",
        occlusionModeName(occMode), occStats.tetsWithGeometry, occStats.none, occStats.planeTets,
        occStats.shadowMapTets, occStats.bytes, occStats.agreement);
  if (stored) {
    size_t counts[3] = {0, 0, 0};
    for (const TetOcclusion& rec : level.occlusion.tets) ++counts[std::min<uint32_t>(rec.kind(), 2)];
    std::printf("  occlusion (stored in the level): %zu none, %zu planes, %zu shadow maps; %zu bytes\n",
                counts[0], counts[1], counts[2], level.occlusion.bytes());
  }
  std::printf("  %zu of %zu points lit only indirectly (leak_ind is the leak over them)\n",
              report.indirectOnlyPoints, report.points.size());
  std::printf("  %-18s %10s %14s %13s %10s %10s %12s %12s\n", "method", "relmse", "mean_rel_err",
              "p95_rel_err", "leak", "leak_ind", "ns/query", "bytes");
  for (const auto& m : report.methods)
    std::printf("  %-18s %10.4f %14.4f %13.4f %10.4f %10.4f %12.1f %12llu\n", m.name.c_str(), m.relmse,
                m.meanRelError, m.p95RelError, m.leak, m.leakIndirect, m.cpuNsPerQuery,
                (unsigned long long)m.bytes);

  if (args.has("--points-out")) {
    std::string csv =
        "x,y,z,nx,ny,nz,ref_r,ref_g,ref_b,stderr_r,stderr_g,stderr_b,direct_r,direct_g,direct_b";
    for (const auto& m : report.methods) csv += "," + m.name + "_r," + m.name + "_g," + m.name + "_b";
    csv += "\n";
    char buf[64];
    auto add = [&](double v) {
      std::snprintf(buf, sizeof buf, "%.7g,", v);
      csv += buf;
    };
    for (size_t i = 0; i < report.points.size(); ++i) {
      const auto& p = report.points[i];
      for (int k = 0; k < 3; ++k) add(p.surface.position[k]);
      for (int k = 0; k < 3; ++k) add(p.surface.normal[k]);
      for (int k = 0; k < 3; ++k) add(p.reference.irradiance[k]);
      for (int k = 0; k < 3; ++k) add(p.reference.stderror[k]);
      for (int k = 0; k < 3; ++k) add(p.direct[k]);
      for (const auto& m : report.methods)
        for (int k = 0; k < 3; ++k) add(m.values[i][k]);
      csv.back() = '\n';
    }
    std::string error;
    if (!writeFileAtomic(args.str("--points-out"), csv, &error)) throw std::runtime_error(error);
  }
  if (args.has("--report")) {
    nlohmann::json methods = nlohmann::json::array();
    for (const auto& m : report.methods)
      methods.push_back({{"name", m.name},
                         {"relmse", m.relmse},
                         {"mean_rel_error", m.meanRelError},
                         {"p95_rel_error", m.p95RelError},
                         {"leak", m.leak},
                         {"leak_indirect", m.leakIndirect},
                         {"cpu_ns_per_query", m.cpuNsPerQuery},
                         {"bytes", m.bytes}});
    nlohmann::json j = {{"scene", args.positional()[0]},
                        {"level", args.positional()[1]},
                        {"reference",
                         {{"points", report.points.size()},
                          {"samples_per_point", report.samplesPerPoint},
                          {"bounces", report.referenceBounces},
                          {"mean_rel_stderr", report.meanRelStderr},
                          {"indirect_only_points", report.indirectOnlyPoints},
                          {"seconds", report.referenceSeconds}}},
                        {"methods", methods}};
    if (stored)
      j["occlusion"] = {{"mode", "stored"}, {"bytes", level.occlusion.bytes()}};
    else if (occMode != OcclusionMode::kNone)
      j["occlusion"] = {{"mode", occlusionModeName(occMode)},
                        {"none", occStats.none},
                        {"planes", occStats.planeTets},
                        {"shadow_maps", occStats.shadowMapTets},
                        {"bytes", occStats.bytes},
                        {"agreement", occStats.agreement}};
    writeJsonReport(args.str("--report"), j);
  }
  return 0;
}

}  // namespace tetraprobe::cli
