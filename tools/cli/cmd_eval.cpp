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

namespace {
double luminanceOf(const glm::vec3& c) {
  return 0.2126 * c.r + 0.7152 * c.g + 0.0722 * c.b;
}
}  // namespace

int cmdEval(int argc, char** argv) {
  Args args(
      "tetraprobe eval SCENE LEVEL.tpb [options]",
      "Path-traces reference irradiance at random surface points (same light content as the level)\n"
      "and compares each lookup method with it. Error measures are defined in docs/evaluation.md.",
      {{"--points", "", "N", "random surface points", "512"},
       {"--samples", "", "N", "reference paths per point", "4096"},
       {"--bounces", "", "N|unbounded",
        "reference path depth; unbounded = Russian roulette only (unbiased ground truth)", "unbounded"},
       {"--sampling", "", "auto|cameras|area|both",
        "where points are drawn: cameras = where the scene's cameras look, area = area-uniform on the\n"
        "surfaces; auto = both when the scene has cameras (cameras first: the headline), else area",
        "auto"},
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
  opt.referenceBounces = args.bounces("--bounces");
  opt.seed = uint64_t(args.number("--seed"));
  opt.threads = args.integer("--threads");
  if (opt.points < 1 || opt.samplesPerPoint < 1 || opt.threads < 0)
    throw UsageError("--points and --samples must be >= 1, --threads >= 0");
  const std::string sampling = args.str("--sampling");
  if (sampling != "auto" && sampling != "cameras" && sampling != "area" && sampling != "both")
    throw UsageError("--sampling must be auto, cameras, area or both, not '" + sampling + "'");

  const Scene scene = loadScene(args.positional()[0]);
  Level level;
  if (const LevelResult r = loadLevel(args.positional()[1], level); !r) throw InputError(r.message);
  const SceneTracer tracer(scene);
  opt.cameras = scene.cameras;
  if ((sampling == "cameras" || sampling == "both") && scene.cameras.empty())
    throw InputError("--sampling " + sampling +
                     ": the scene names no cameras (give a scene JSON with cameras)");
  // The first set is the headline (top-level JSON keys): the cameras' view when the scene has one.
  std::vector<EvalSampling> sets;
  if (sampling == "cameras" || ((sampling == "auto" || sampling == "both") && !scene.cameras.empty()))
    sets.push_back(EvalSampling::kCameras);
  if (sampling == "area" || sampling == "auto" || sampling == "both") sets.push_back(EvalSampling::kArea);

  OcclusionStats occStats;
  OcclusionMode occMode;
  if (!parseOcclusionMode(args.str("--occlusion"), occMode))
    throw UsageError("--occlusion must be auto, none, planes or shadow-maps");
  const bool stored = !level.occlusion.empty();
  if (stored) occMode = OcclusionMode::kNone;  // the level's own data is scored through `tet`
  std::shared_ptr<const LevelOcclusion> built;
  if (occMode != OcclusionMode::kNone) {
    OcclusionOptions occOpt;
    occOpt.mode = occMode;
    occOpt.minAgreement = args.number("--min-agreement");
    occOpt.threads = opt.threads;
    built = std::make_shared<const LevelOcclusion>(buildOcclusion(tracer, level, occOpt, &occStats));
  }

  std::vector<EvalReport> reports;
  for (const EvalSampling set : sets) {
    opt.sampling = set;
    EvalReport report = computeReference(tracer, level.content, opt);
    for (const auto& m : standardMethods(level)) scoreMethod(report, m);
    if (built) scoreMethod(report, occlusionMethod(level, built));
    reports.push_back(std::move(report));
  }

  if (occMode != OcclusionMode::kNone)
    std::printf(
        "tetraprobe eval: occlusion (%s): %zu tets with geometry: %zu none, %zu planes, %zu shadow maps; %zu "
        "bytes; agreement %.3f\n",
        occlusionModeName(occMode), occStats.tetsWithGeometry, occStats.none, occStats.planeTets,
        occStats.shadowMapTets, occStats.bytes, occStats.agreement);
  if (stored) {
    size_t counts[3] = {0, 0, 0};
    for (const TetOcclusion& rec : level.occlusion.tets) ++counts[std::min<uint32_t>(rec.kind(), 2)];
    std::printf(
        "tetraprobe eval: occlusion stored in the level: %zu none, %zu planes, %zu shadow maps; %zu bytes\n",
        counts[0], counts[1], counts[2], level.occlusion.bytes());
  }
  const std::string depth = opt.referenceBounces == kUnboundedBounces ? std::string("unbounded")
                                                                      : std::to_string(opt.referenceBounces);
  for (const EvalReport& report : reports) {
    std::printf(
        "tetraprobe eval [%s]: %zu points, %d paths each (%s bounces), mean relative stderr %.4f, %.1fs\n",
        evalSamplingName(report.sampling), report.points.size(), report.samplesPerPoint, depth.c_str(),
        report.meanRelStderr, report.referenceSeconds);
    std::printf("  %zu of %zu points lit only indirectly (leak_ind is the leak over them)\n",
                report.indirectOnlyPoints, report.points.size());
    if (!level.occlusion.empty() && !report.methods.empty()) {
      const std::vector<float> share = fallbackShares(level, report);
      size_t fallback = 0, gross = 0, dark = 0;
      const MethodResult& tet = report.methods[0];
      for (size_t i = 0; i < share.size(); ++i) {
        if (!(share[i] > 0.0f)) continue;
        ++fallback;
        const double lx = std::max(luminanceOf(tet.values[i]), 0.01),
                     lr = std::max(luminanceOf(report.points[i].reference.irradiance), 0.01);
        gross += (lx > 2 * lr || lx < 0.5 * lr) ? 1 : 0;
        dark += lx < 0.25 * lr ? 1 : 0;
      }
      std::printf(
          "  %zu points see none of their tet's probes (occlusion fallback): %zu of them gross, %zu dark\n",
          fallback, gross, dark);
    }
    std::printf("  %-18s %8s %8s %8s %8s %8s %8s %8s %10s %10s\n", "method", "gross", "dark", "mean_rel",
                "p95_rel", "relmse", "leak", "leak_ind", "ns/query", "bytes");
    for (const auto& m : report.methods)
      std::printf("  %-18s %8.4f %8.4f %8.4f %8.4f %8.4f %8.4f %8.4f %10.1f %10llu\n", m.name.c_str(),
                  m.grossError, m.darkHoles, m.meanRelError, m.p95RelError, m.relmse, m.leak, m.leakIndirect,
                  m.cpuNsPerQuery, (unsigned long long)m.bytes);
  }

  if (args.has("--points-out")) {
    std::string csv =
        "set,x,y,z,nx,ny,nz,ref_r,ref_g,ref_b,stderr_r,stderr_g,stderr_b,direct_r,direct_g,direct_b";
    for (const auto& m : reports[0].methods) csv += "," + m.name + "_r," + m.name + "_g," + m.name + "_b";
    csv += "\n";
    char buf[64];
    auto add = [&](double v) {
      std::snprintf(buf, sizeof buf, "%.7g,", v);
      csv += buf;
    };
    for (const EvalReport& report : reports)
      for (size_t i = 0; i < report.points.size(); ++i) {
        const auto& p = report.points[i];
        csv += std::string(evalSamplingName(report.sampling)) + ",";
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
    auto setJson = [&](const EvalReport& report) {
      nlohmann::json methods = nlohmann::json::array();
      for (const auto& m : report.methods)
        methods.push_back({{"name", m.name},
                           {"gross_error", m.grossError},
                           {"dark_holes", m.darkHoles},
                           {"relmse", m.relmse},
                           {"mean_rel_error", m.meanRelError},
                           {"p95_rel_error", m.p95RelError},
                           {"leak", m.leak},
                           {"leak_indirect", m.leakIndirect},
                           {"cpu_ns_per_query", m.cpuNsPerQuery},
                           {"bytes", m.bytes}});
      nlohmann::json ref = {{"sampling", evalSamplingName(report.sampling)},
                            {"points", report.points.size()},
                            {"samples_per_point", report.samplesPerPoint},
                            {"bounces", depth},
                            {"mean_rel_stderr", report.meanRelStderr},
                            {"indirect_only_points", report.indirectOnlyPoints},
                            {"seconds", report.referenceSeconds}};
      return nlohmann::json{{"reference", ref}, {"methods", methods}};
    };
    nlohmann::json j = setJson(reports[0]);
    j["scene"] = args.positional()[0];
    j["level"] = args.positional()[1];
    j["sets"] = nlohmann::json::object();
    for (const EvalReport& report : reports) j["sets"][evalSamplingName(report.sampling)] = setJson(report);
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
