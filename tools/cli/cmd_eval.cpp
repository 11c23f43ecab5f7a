// `tetraprobe eval SCENE LEVEL.tpb`: probe lookup error against path-traced ground truth, with memory and
// run time, side by side with the regular SH grid a user would pick instead (eval/grid_volume.h).
#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <map>
#include <memory>
#include <sstream>

#include <glm/common.hpp>
#include <glm/geometric.hpp>

#include "args.h"
#include "commands.h"
#include "eval_plot.h"
#include "half_resolution_report.h"
#include "pipeline.h"
#include "pipeline_options.h"
#include "render_view.h"
#include "tetraprobe/common/error.h"
#include "tetraprobe/common/parallel.h"
#include "tetraprobe/eval/evaluate.h"
#include "tetraprobe/eval/grid_volume.h"
#include "tetraprobe/eval/nearest_probe.h"
#include "tetraprobe/occlusion/build_occlusion.h"
#include "tetraprobe/render/render.h"
#include "tetraprobe/runtime/file_io.h"
#include "tetraprobe/runtime/luminance.h"
#include "tetraprobe/runtime/occlusion.h"
#include "tetraprobe/scene/load.h"

namespace tetraprobe::cli {

namespace {

constexpr const char* kGridEqualBytes = "grid (equal bytes)";
constexpr const char* kGridProbeCount = "grid (probe count)";

// The rows of an `eval --points-out` file by point set ("cameras", "area"): position, normal, reference,
// stderr and direct part (the lookup columns after them are ignored).
std::map<std::string, std::vector<StoredReference>> readStoredReferences(const std::string& path) {
  std::vector<char> bytes;
  std::string error;
  if (!readFile(path, bytes, &error)) throw InputError("--reference-in: " + error);
  std::istringstream in(std::string(bytes.begin(), bytes.end()));
  std::string line;
  const std::string header =
      "set,x,y,z,nx,ny,nz,ref_r,ref_g,ref_b,stderr_r,stderr_g,stderr_b,direct_r,direct_g,direct_b";
  if (!std::getline(in, line) || line.compare(0, header.size(), header) != 0)
    throw InputError("--reference-in: " + path + " is not an `eval --points-out` file (header)");
  std::map<std::string, std::vector<StoredReference>> sets;
  for (int row = 2; std::getline(in, line); ++row) {
    if (line.empty()) continue;
    std::istringstream fields(line);
    std::string set, cell;
    std::getline(fields, set, ',');
    double v[15];
    for (double& x : v) {
      if (!std::getline(fields, cell, ',')) cell.clear();
      char* end = nullptr;
      x = std::strtod(cell.c_str(), &end);
      if (cell.empty() || *end != '\0' || !std::isfinite(x))
        throw InputError("--reference-in: " + path + " line " + std::to_string(row) + ": bad number '" +
                         cell + "'");
    }
    StoredReference r;
    r.position = glm::dvec3(v[0], v[1], v[2]);
    r.normal = glm::vec3(float(v[3]), float(v[4]), float(v[5]));
    r.irradiance = glm::vec3(float(v[6]), float(v[7]), float(v[8]));
    r.stderror = glm::vec3(float(v[9]), float(v[10]), float(v[11]));
    r.direct = glm::vec3(float(v[12]), float(v[13]), float(v[14]));
    sets[set].push_back(r);
  }
  return sets;
}

// A method with what it takes to render it on the GPU (empty: no shader for it).
struct Candidate {
  LookupMethod method;
  std::function<RenderTimings(const RenderView&)> gpu;
};

// Everything eval needs from one level: its methods (and the data they keep alive).
struct LevelUnderTest {
  std::shared_ptr<Level> level;
  std::vector<Candidate> candidates;
  std::vector<std::string> notes;  // printed once (grid sizes, bake settings)
};

struct EvalSetup {
  const Scene* scene = nullptr;
  const SceneTracer* tracer = nullptr;
  RenderMesh mesh;
  bool equalBytesGrid = true, probeCountGrid = true;
  int gridOffsets = 1;                          // lattices of the equal-bytes grid: 1 = the centred one only
  std::shared_ptr<const LevelOcclusion> built;  // --occlusion for a level without stored occlusion
  int threads = 0;
};

std::string mb(uint64_t bytes) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.2f MB", double(bytes) / 1e6);
  return buf;
}

// The level's methods: tet (and tet without occlusion, or tet+occlusion), nearest, and the grids baked with
// the level's own bake settings.
LevelUnderTest prepareLevel(std::shared_ptr<Level> level, const EvalSetup& setup) {
  LevelUnderTest out;
  out.level = level;
  auto query = std::make_shared<ProbeQuery>(*level);
  for (LookupMethod& m : standardMethods(*level)) {
    Candidate c{std::move(m), {}};
    if (c.method.name == "tet") {
      c.gpu = [&setup, level, query](const RenderView& v) {
        return renderLevel(setup.mesh, *level, *query, v).timings;
      };
    } else if (c.method.name == "tet (no occlusion)") {
      auto plain = std::make_shared<Level>(*level);
      plain->occlusion = LevelOcclusion{};
      auto plainQuery = std::make_shared<ProbeQuery>(*plain);
      c.gpu = [&setup, plain, plainQuery](const RenderView& v) {
        return renderLevel(setup.mesh, *plain, *plainQuery, v).timings;
      };
    } else if (c.method.name == "nearest") {
      auto buckets = std::make_shared<const NearestProbe>(*level);  // the same buckets the CPU method builds
      c.gpu = [&setup, level, buckets](const RenderView& v) {  // `level` keeps what buckets point at alive
        return renderNearestProbe(setup.mesh, buckets->gpuBuckets(), v).timings;
      };
    }
    out.candidates.push_back(std::move(c));
  }
  if (setup.built) out.candidates.push_back({occlusionMethod(*level, setup.built), {}});

  if (setup.equalBytesGrid || setup.probeCountGrid) {
    std::vector<std::string> recorded;
    const PipelineOptions settings = pipelineOptionsFromGenerator(level->generator, &recorded);
    BakeOptions bake = settings.bake;
    bake.content = level->content;  // what the level holds, whatever its text says
    bake.threads = setup.threads;
    bake.progress = false;
    glm::vec3 slo, shi;
    sceneBounds(*setup.scene, slo, shi);
    std::string found;
    for (const std::string& k : recorded) found += (found.empty() ? "" : ",") + k;
    std::ostringstream note;
    note << "grid bake settings from the level's generator (" << (found.empty() ? "none found" : found)
         << "): samples " << bake.samplesPerProbe << ", noise " << bake.targetRelError << ", max "
         << bake.maxSamplesPerProbe << ", L" << bake.shOrder << "; bounds = the scene's box";
    out.notes.push_back(note.str());
    const uint64_t tetBytes = out.candidates[0].method.bytes;
    std::vector<std::pair<std::string, GridLayout>> layouts;
    if (setup.equalBytesGrid) {
      const GridLayout centred = gridLayoutForBytes(glm::dvec3(slo), glm::dvec3(shi), tetBytes);
      layouts.emplace_back(kGridEqualBytes, centred);
      // The same spacing shifted by k/N of a step on every axis, one node more per axis to keep the box
      // covered: where the nodes fall against walls changes the grid's error (docs/evaluation.md).
      for (int k = 1; k < setup.gridOffsets; ++k) {
        GridLayout shifted = centred;
        shifted.min -= glm::dvec3(centred.step * double(k) / double(setup.gridOffsets));
        shifted.dims += glm::ivec3(1);
        layouts.emplace_back(
            "grid (equal bytes, offset " + std::to_string(k) + "/" + std::to_string(setup.gridOffsets) + ")",
            shifted);
      }
    }
    if (setup.probeCountGrid)
      layouts.emplace_back(kGridProbeCount,
                           gridLayoutForNodes(glm::dvec3(slo), glm::dvec3(shi), level->probes.size()));
    for (const auto& [name, layout] : layouts) {
      GridBakeStats stats;
      auto grid = std::make_shared<const GridVolume>(
          bakeGridVolume(*setup.tracer, layout, bake, settings.dering, &stats));
      char buf[256];
      std::snprintf(buf, sizeof buf,
                    "%s: %dx%dx%d nodes of %.3g m, %zu inside geometry (dilated), %s; baked in %.1fs",
                    name.c_str(), layout.dims.x, layout.dims.y, layout.dims.z, layout.step,
                    stats.invalidNodes, mb(grid->bytes()).c_str(), stats.seconds);
      out.notes.push_back(buf);
      Candidate c{gridMethod(grid, name), {}};
      c.gpu = [&setup, grid](const RenderView& v) {
        RenderGrid g;
        g.min = grid->layout().min;
        g.step = grid->layout().step;
        g.dims = grid->layout().dims;
        g.sh = grid->sh().data();
        return renderGridVolume(setup.mesh, g, v).timings;
      };
      out.candidates.push_back(std::move(c));
    }
  }
  return out;
}

struct Measured {
  double coherent = 0.0, random = 0.0, gpuMs = -1.0;
  int threads = 0;
};

// CPU timings in both orders and the GPU pass (median of `gpuRuns` renders; -1 when not measured).
std::vector<Measured> measure(const LevelUnderTest& lut, const TimingPoints& coherent,
                              const TimingPoints& random, int threads, const RenderView* gpuView, int gpuRuns,
                              std::string* gpuError) {
  std::vector<Measured> out;
  for (const Candidate& c : lut.candidates) {
    Measured m;
    m.threads = resolveThreads(threads);
    m.coherent = timeLookup(c.method, coherent, threads);
    m.random = timeLookup(c.method, random, threads);
    if (gpuView && c.gpu && gpuError->empty()) {
      try {
        std::vector<double> ms;
        for (int r = 0; r < gpuRuns; ++r) ms.push_back(c.gpu(*gpuView).lightingMs);
        std::sort(ms.begin(), ms.end());
        m.gpuMs = ms[ms.size() / 2];
      } catch (const std::exception& e) {
        *gpuError = e.what();  // no Vulkan device: no GPU column, everything else stands
      }
    }
    out.push_back(m);
  }
  return out;
}

void applyMeasured(EvalReport& report, const std::vector<Measured>& measured) {
  for (size_t i = 0; i < measured.size() && i < report.methods.size(); ++i) {
    report.methods[i].cpuNsCoherent = measured[i].coherent;
    report.methods[i].cpuNsRandom = measured[i].random;
    report.methods[i].threads = measured[i].threads;
    report.methods[i].gpuMs = measured[i].gpuMs;
  }
}

nlohmann::json methodJson(const MethodResult& m, const std::string& coherentOrder) {
  nlohmann::json sections = nlohmann::json::object();
  for (const ByteSection& s : m.sections) sections[s.name] = s.bytes;
  nlohmann::json perProbe = nlohmann::json::object();
  if (m.probes > 0)
    for (const ByteSection& s : m.sections) perProbe[s.name] = double(s.bytes) / double(m.probes);
  nlohmann::json j = {{"name", m.name},
                      {"gross_error", m.grossError},
                      {"dark_holes", m.darkHoles},
                      {"relmse", m.relmse},
                      {"mean_rel_error", m.meanRelError},
                      {"p95_rel_error", m.p95RelError},
                      {"leak", m.leak},
                      {"leak_indirect", m.leakIndirect},
                      {"relmse_abs_floor", m.relmseAbsFloor},
                      {"mean_rel_abs_floor", m.meanRelAbsFloor},
                      {"p95_rel_abs_floor", m.p95RelAbsFloor},
                      {"closed_mean_irradiance", {m.closedMean.x, m.closedMean.y, m.closedMean.z}},
                      {"cpu_ns_per_query", m.cpuNsPerQuery},
                      {"cpu_ns_per_query_single_thread_fastest", m.cpuNsPerQuery},
                      {"cpu_ns_per_query_coherent", m.cpuNsCoherent},
                      {"cpu_ns_per_query_random", m.cpuNsRandom},
                      {"threads", m.threads},
                      {"coherent_order", coherentOrder},
                      {"bytes", m.bytes},
                      {"bytes_sections", sections},
                      {"probes", m.probes},
                      {"bytes_per_probe", m.probes > 0 ? double(m.bytes) / double(m.probes) : 0.0},
                      {"bytes_per_probe_sections", perProbe}};
  j["gpu_ms"] = m.gpuMs >= 0.0 ? nlohmann::json(m.gpuMs) : nlohmann::json(nullptr);
  j["fallback"] = m.fallback >= 0.0 ? nlohmann::json(m.fallback) : nlohmann::json(nullptr);
  if (m.fallback >= 0.0) j["fallback_closed_points"] = m.closedFallbackPoints;
  return j;
}

std::string markdownTable(const EvalReport& report) {
  std::ostringstream md;
  md << "| method | gross | dark | fallback | mean rel | p95 rel | relmse | leak_ind | bytes | bytes/probe | "
        "probes | CPU ns coherent | CPU ns random | GPU ms |\n";
  md << "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n";
  char buf[512];
  for (const MethodResult& m : report.methods) {
    char gpu[32] = "-";
    if (m.gpuMs >= 0.0) std::snprintf(gpu, sizeof gpu, "%.1f", m.gpuMs);
    char fallback[32] = "n/a";
    if (m.fallback >= 0.0) std::snprintf(fallback, sizeof fallback, "%.2f %%", 100.0 * m.fallback);
    std::snprintf(
        buf, sizeof buf,
        "| %s | %.1f %% | %.2f %% | %s | %.3f | %.2f | %.3f | %.3f | %s | %.0f | %llu | %.1f | %.1f | %s |\n",
        m.name.c_str(), 100.0 * m.grossError, 100.0 * m.darkHoles, fallback, m.meanRelError, m.p95RelError,
        m.relmse, m.leakIndirect, mb(m.bytes).c_str(),
        m.probes > 0 ? double(m.bytes) / double(m.probes) : 0.0, (unsigned long long)m.probes,
        m.cpuNsCoherent, m.cpuNsRandom, gpu);
    md << buf;
  }
  return md.str();
}

// Whether --plot FILE asks for a PNG (else SVG); a name ending in neither is a usage error.
bool plotIsPng(const std::string& file) {
  std::string lower = file;  // the ending in any case: .png, .PNG
  for (char& c : lower) c = char(std::tolower(static_cast<unsigned char>(c)));
  if (endsWith(lower, ".png")) return true;
  if (endsWith(lower, ".svg")) return false;
  throw UsageError("--plot FILE must end in .svg or .png, not '" + file + "'");
}

// "spacing=0.25,0.5,1,2" -> the spacings.
std::vector<double> parseSweep(const std::string& text) {
  const std::string prefix = "spacing=";
  if (text.compare(0, prefix.size(), prefix) != 0)
    throw UsageError("--sweep must be spacing=S1,S2,... (metres), not '" + text + "'");
  std::vector<double> out;
  std::istringstream in(text.substr(prefix.size()));
  std::string item;
  while (std::getline(in, item, ',')) {
    const double s = parseNumber(item, "--sweep");
    if (!(s > 0.0) || !std::isfinite(s)) throw UsageError("--sweep spacings must be positive");
    out.push_back(s);
  }
  if (out.empty()) throw UsageError("--sweep needs at least one spacing");
  return out;
}

// The bake pipeline's options for a re-bake at `spacing`: the options the level was baked with, as its
// generator string records them (pipelineOptionsFromGenerator: `tetraprobe bake`'s defaults for any it does
// not), at this spacing. A level of user or imported probes re-bakes with automatic placement (the files are
// not at hand), voxel unless it was a grid; the coarsest cell grows to the spacing when smaller.
PipelineOptions sweepOptions(const Level& level, double spacing, int threads) {
  PipelineOptions opt = pipelineOptionsFromGenerator(level.generator);
  if (!opt.probesCsv.empty() || !opt.importShCsv.empty()) {
    opt.probesCsv.clear();
    opt.importShCsv.clear();
    if (opt.placement == "none") opt.placement = "voxel";
  }
  if (level.content == kContentDefault || level.content == kContentAll) opt.bake.content = level.content;
  opt.bake.threads = threads;
  opt.bake.progress = false;
  opt.spacing = spacing;
  opt.maxSpacing = std::max(opt.maxSpacing, spacing);
  return opt;
}

}  // namespace

int cmdEval(int argc, char** argv) {
  Args args(
      "tetraprobe eval SCENE LEVEL.tpb [options]",
      "Path-traces reference irradiance at random surface points (same light content as the level)\n"
      "and compares each lookup method with it: the level's tet lookup, the nearest probe, and a regular\n"
      "SH L2 grid baked the same way at the level's bytes and at its probe count. Error, memory and run "
      "time\n"
      "are defined in docs/evaluation.md.",
      {{"--points", "", "N", "random surface points", "512"},
       {"--samples", "", "N", "reference paths per point", "4096"},
       {"--bounces", "", "N|unbounded",
        "reference path depth; unbounded = Russian roulette only (unbiased ground truth)", "unbounded"},
       {"--sampling", "", "auto|cameras|area|both",
        "where points are drawn: cameras = where the scene's cameras look, area = area-uniform on the\n"
        "surfaces; auto = both when the scene has cameras (cameras first: the headline), else area",
        "auto"},
       {"--seed", "", "N", "random seed for points and paths", "1"},
       {"--threads", "", "N", "worker threads, 0 = all cores (also the CPU timing's threads)", "0"},
       {"--occlusion", "", "auto|none|planes|shadow-maps",
        "for a level without stored occlusion: also score tet+occlusion, with occlusion data built from the "
        "scene in this mode (a level that stores occlusion scores `tet` with it and `tet (no occlusion)`)",
        "auto"},
       {"--min-agreement", "", "F", "occlusion auto mode: fraction of ray answers the data must match",
        "0.98"},
       {"--grid", "", "both|equal-bytes|probe-count|none",
        "the regular SH grid competitor: at the tet level's total bytes, at its probe count, both or none",
        "both"},
       {"--grid-offsets", "", "N",
        "also bake the equal-bytes grid at N-1 more lattice offsets (shifted by k/N of its node spacing on "
        "every axis, one node more per axis to cover the box): the spread of the grid's error with where its "
        "nodes fall",
        "1"},
       {"--timing-size", "", "WxH",
        "CPU timing: the hit pixels of the first camera at this size, in pixel order (coherent) and shuffled "
        "(random); scenes without cameras use the points in Morton order",
        "640x360"},
       {"--gpu", "", "auto|none",
        "time each method's full-screen lookup pass at 1280x720 on Vulkan (median of 3; the first camera "
        "or a view of the scene's box); none = skip",
        "auto"},
       {"--markdown", "", "", "print each point set's table as Markdown", ""},
       {"--plot", "", "FILE.svg|FILE.png",
        "write error against bytes and against GPU ms (or CPU ns) as an SVG or PNG chart (by the name's "
        "ending)",
        ""},
       {"--sweep", "", "spacing=S1,S2,...",
        "re-bake the scene at these spacings (the bake pipeline with the level's settings), score every "
        "method on the same points and draw each method's curve with the Pareto front",
        ""},
       {"--report", "", "FILE.json", "write the figures as JSON", ""},
       {"--points-out", "", "FILE.csv",
        "write every point: position, normal, reference, stderr, direct part of the reference, lookups", ""},
       {"--reference-in", "", "FILE.csv",
        "take the references from an earlier run's --points-out (same scene, --points, --seed, --sampling "
        "and --samples) instead of tracing them again; points that do not match are refused",
        ""}});
  if (!args.parse(argc, argv)) return 0;
  args.requirePositional(2, 2);
  EvalOptions opt;
  opt.points = args.integer("--points");
  opt.samplesPerPoint = args.integer("--samples");
  opt.referenceBounces = args.bounces("--bounces");
  opt.seed = args.u64("--seed");
  opt.threads = args.integer("--threads");
  if (opt.points < 1 || opt.samplesPerPoint < 1 || opt.threads < 0)
    throw UsageError("--points and --samples must be >= 1, --threads >= 0");
  const std::string sampling = args.str("--sampling");
  if (sampling != "auto" && sampling != "cameras" && sampling != "area" && sampling != "both")
    throw UsageError("--sampling must be auto, cameras, area or both, not '" + sampling + "'");
  const std::string gridArg = args.str("--grid");
  if (gridArg != "both" && gridArg != "equal-bytes" && gridArg != "probe-count" && gridArg != "none")
    throw UsageError("--grid must be both, equal-bytes, probe-count or none, not '" + gridArg + "'");
  int timingW = 0, timingH = 0;
  if (std::sscanf(args.str("--timing-size").c_str(), "%dx%d", &timingW, &timingH) != 2 || timingW < 1 ||
      timingH < 1 || timingW > 16384 || timingH > 16384)
    throw UsageError("--timing-size must be WxH with 1..16384 pixels a side");
  const std::string gpuArg = args.str("--gpu");
  if (gpuArg != "auto" && gpuArg != "none") throw UsageError("--gpu must be auto or none");
  const std::vector<double> sweep =
      args.has("--sweep") ? parseSweep(args.str("--sweep")) : std::vector<double>{};
  if (args.has("--plot")) plotIsPng(args.str("--plot"));  // refuse a bad name before the work

  const Scene scene = loadScene(args.positional()[0]);
  auto level = std::make_shared<Level>();
  if (const LevelResult r = loadLevel(args.positional()[1], *level); !r) throw InputError(r.message);
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
  const bool stored = !level->occlusion.empty();
  if (stored) occMode = OcclusionMode::kNone;  // the level's own data is scored through `tet`
  EvalSetup setup;
  setup.scene = &scene;
  setup.tracer = &tracer;
  setup.mesh = toRenderMesh(scene);
  setup.equalBytesGrid = gridArg == "both" || gridArg == "equal-bytes";
  setup.probeCountGrid = gridArg == "both" || gridArg == "probe-count";
  setup.gridOffsets = args.integer("--grid-offsets");
  if (setup.gridOffsets < 1 || setup.gridOffsets > 16) throw UsageError("--grid-offsets must be 1..16");
  setup.threads = opt.threads;
  if (occMode != OcclusionMode::kNone) {
    OcclusionOptions occOpt;
    occOpt.mode = occMode;
    occOpt.minAgreement = args.number("--min-agreement");
    occOpt.threads = opt.threads;
    setup.built = std::make_shared<const LevelOcclusion>(buildOcclusion(tracer, *level, occOpt, &occStats));
  }

  std::vector<EvalReport> reports;
  const std::map<std::string, std::vector<StoredReference>> storedRefs =
      args.has("--reference-in") ? readStoredReferences(args.str("--reference-in"))
                                 : std::map<std::string, std::vector<StoredReference>>{};
  for (const EvalSampling set : sets) {
    opt.sampling = set;
    if (!args.has("--reference-in")) {
      reports.push_back(computeReference(tracer, level->content, opt));
      continue;
    }
    const auto it = storedRefs.find(evalSamplingName(set));
    if (it == storedRefs.end())
      throw InputError("--reference-in: " + args.str("--reference-in") + " holds no '" +
                       evalSamplingName(set) + "' points (give --sampling to match the run that wrote it)");
    reports.push_back(reuseReference(tracer, opt, it->second));
  }

  const LevelUnderTest lut = prepareLevel(level, setup);
  for (const std::string& note : lut.notes) std::printf("tetraprobe eval: %s\n", note.c_str());
  for (EvalReport& report : reports)
    for (const Candidate& c : lut.candidates) scoreMethod(report, c.method);

  // Timing: the same query points for every method, coherent (a camera's pixels in order) and shuffled.
  const TimingPoints coherent =
      scene.cameras.empty() ? mortonTimingPoints(reports[0])
                            : cameraTimingPoints(tracer, scene.cameras[0], timingW, timingH, opt.threads);
  const TimingPoints random = shuffledTimingPoints(coherent, opt.seed ^ 0x7193ull);
  RenderView gpuView;
  gpuView.width = 1280;
  gpuView.height = 720;
  gpuView.mode = RenderMode::kIrradiance;
  if (!scene.cameras.empty()) {
    gpuView.eye = scene.cameras[0].eye;
    gpuView.target = scene.cameras[0].target;
    gpuView.up = scene.cameras[0].up;
    gpuView.fovYDeg = scene.cameras[0].fovYDeg;
  } else {  // the view `tetraprobe render` takes for a scene without cameras
    glm::vec3 lo, hi;
    sceneBounds(scene, lo, hi);
    const glm::vec3 c = (lo + hi) * 0.5f, ext = hi - lo;
    gpuView.target = c;
    gpuView.eye = c + glm::vec3(0.7f, 0.5f, 0.9f) * glm::max(ext, glm::vec3(glm::length(ext) * 0.3f));
  }
  const bool gpu = gpuArg == "auto";
  std::string gpuError;
  const std::vector<Measured> measured =
      measure(lut, coherent, random, opt.threads, gpu ? &gpuView : nullptr, 3, &gpuError);
  for (EvalReport& report : reports) applyMeasured(report, measured);
  if (!gpuError.empty()) std::printf("tetraprobe eval: no GPU timing (%s)\n", gpuError.c_str());
  // The half-resolution lookup (an engine option) at the same view: its passes and its difference from the
  // full-resolution pass of the same render (the tet method's level, median of 3 frames after 1 warm-up).
  nlohmann::json halfJson;
  if (gpu && gpuError.empty()) {
    RenderOptions halfOptions;
    halfOptions.halfResolution = true;
    halfOptions.warmupFrames = 1;
    halfOptions.timedFrames = 3;
    const ProbeQuery halfQuery(*level);
    const RenderResult r = renderLevel(setup.mesh, *level, halfQuery, gpuView, halfOptions);
    std::printf(
        "tetraprobe eval: half-resolution lookup at 1280x720 (an engine option; full lighting pass %.1f "
        "ms):\n",
        r.timings.lightingMs);
    const HalfResolutionReport report = halfResolutionReport(r, r.timings.lightingMs, 0.0);
    printHalfResolution(report);
    halfJson = halfResolutionJson(report);
    halfJson["full_ms"] = r.timings.lightingMs;
  }

  if (occMode != OcclusionMode::kNone)
    std::printf(
        "tetraprobe eval: occlusion (%s): %zu tets with geometry: %zu none, %zu planes, %zu shadow maps; %zu "
        "bytes; agreement %.3f\n",
        occlusionModeName(occMode), occStats.tetsWithGeometry, occStats.none, occStats.planeTets,
        occStats.shadowMapTets, occStats.bytes, occStats.agreement);
  if (stored) {
    size_t counts[3] = {0, 0, 0};
    for (const TetOcclusion& rec : level->occlusion.tets) ++counts[std::min<uint32_t>(rec.kind(), 2)];
    std::printf(
        "tetraprobe eval: occlusion stored in the level: %zu none, %zu planes, %zu shadow maps; %zu bytes\n",
        counts[0], counts[1], counts[2], level->occlusion.bytes());
  }
  {
    const MethodResult& tet = reports[0].methods[0];
    std::printf("tetraprobe eval: tet bytes %llu (%.0f per probe):", (unsigned long long)tet.bytes,
                tet.probes ? double(tet.bytes) / double(tet.probes) : 0.0);
    for (const ByteSection& s : tet.sections)
      std::printf(" %s %.0f", s.name.c_str(), tet.probes ? double(s.bytes) / double(tet.probes) : 0.0);
    std::printf(" bytes/probe\n");
    std::printf(
        "tetraprobe eval: CPU timing on %d threads over %zu points (%s; and shuffled), median of 7; GPU "
        "%s\n",
        resolveThreads(opt.threads), coherent.position.size(), coherent.order.c_str(),
        gpu && gpuError.empty() ? "1280x720 lighting pass, median of 3" : "not measured");
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
    if (!level->occlusion.empty() && !report.methods.empty()) {
      const std::vector<float> share = fallbackShares(*level, report);
      size_t fallback = 0, gross = 0, dark = 0;
      const MethodResult& tet = report.methods[0];
      for (size_t i = 0; i < share.size(); ++i) {
        if (!(share[i] > 0.0f)) continue;
        ++fallback;
        const double lx = std::max(luminance(glm::dvec3(tet.values[i])), 0.01),
                     lr = std::max(luminance(glm::dvec3(report.points[i].reference.irradiance)), 0.01);
        gross += (lx > 2 * lr || lx < 0.5 * lr) ? 1 : 0;
        dark += lx < 0.25 * lr ? 1 : 0;
      }
      std::printf(
          "  %zu points see none of their tet's probes (occlusion fallback): %zu of them gross, %zu dark\n",
          fallback, gross, dark);
    }
    std::printf(
        "  relative errors over the %zu open points, floor f = %.4g W/m^2 (5 %% of their mean luminance); "
        "*_abs: the former sqrt(r^2 + 0.01) over all points\n",
        report.points.size() - report.closedPoints, report.relFloor);
    std::printf("  %-18s %8s %8s %8s %8s %8s %8s %8s %8s %9s %9s %10s %9s %9s %8s\n", "method", "gross",
                "dark", "fallback", "mean_rel", "p95_rel", "relmse", "leak", "leak_ind", "mrel_abs",
                "rmse_abs", "bytes", "ns coh", "ns rand", "gpu ms");
    for (const auto& m : report.methods) {
      char fallback[16] = "n/a";
      if (m.fallback >= 0.0) std::snprintf(fallback, sizeof fallback, "%.4f", m.fallback);
      std::printf(
          "  %-18s %8.4f %8.4f %8s %8.4f %8.4f %8.4f %8.4f %8.4f %9.4f %9.4f %10llu %9.1f %9.1f %8.1f\n",
          m.name.c_str(), m.grossError, m.darkHoles, fallback, m.meanRelError, m.p95RelError, m.relmse,
          m.leak, m.leakIndirect, m.meanRelAbsFloor, m.relmseAbsFloor, (unsigned long long)m.bytes,
          m.cpuNsCoherent, m.cpuNsRandom, m.gpuMs);
    }
    if (report.closedPoints > 0) {
      std::printf(
          "  %zu points no path leaves (reference exactly 0; left out above), mean answer (luminance):",
          report.closedPoints);
      for (const auto& m : report.methods)
        std::printf(" %s %.4g", m.name.c_str(), luminance(glm::dvec3(m.closedMean)));
      std::printf(" W/m^2\n");
      for (const auto& m : report.methods)
        if (m.fallback >= 0.0 && m.closedFallbackPoints > 0)
          std::printf(
              "  %s falls back at %zu of them (not in its fallback share, which counts open points)\n",
              m.name.c_str(), m.closedFallbackPoints);
    }
  }

  // Sweep: re-bake at each spacing, score every method on the headline set's points (same references).
  struct SweepRow {
    double spacing;
    size_t probes;
    EvalReport report;  // methods only (points shared with reports[0])
  };
  std::vector<SweepRow> sweepRows;
  for (const double spacing : sweep) {
    PipelineStats stats;
    const PipelineOptions po = sweepOptions(*level, spacing, opt.threads);
    std::shared_ptr<Level> swept;
    try {
      swept = std::make_shared<Level>(buildLevel(scene, po, stats));
    } catch (const InputError& e) {  // e.g. a spacing coarser than the level: skip it, keep the others
      std::printf("tetraprobe eval: sweep spacing %g m skipped: %s\n", spacing, e.what());
      continue;
    }
    const LevelUnderTest s = prepareLevel(swept, setup);
    EvalReport r = reports[0];
    r.methods.clear();
    for (const Candidate& c : s.candidates) scoreMethod(r, c.method);
    applyMeasured(r, measure(s, coherent, random, opt.threads, gpu && gpuError.empty() ? &gpuView : nullptr,
                             3, &gpuError));
    std::printf("tetraprobe eval: sweep spacing %g m: %zu probes\n", spacing, swept->probes.size());
    for (const auto& m : r.methods)
      std::printf("  %-18s gross %.4f mean_rel %.4f bytes %llu ns coh %.1f gpu ms %.1f\n", m.name.c_str(),
                  m.grossError, m.meanRelError, (unsigned long long)m.bytes, m.cpuNsCoherent, m.gpuMs);
    for (auto& m : r.methods) m.values.clear();
    sweepRows.push_back({spacing, swept->probes.size(), std::move(r)});
  }

  if (args.has("--markdown")) {
    for (const EvalReport& report : reports) {
      std::printf("\n**%s points** (%zu, %d reference paths each):\n\n", evalSamplingName(report.sampling),
                  report.points.size(), report.samplesPerPoint);
      std::printf("%s", markdownTable(report).c_str());
    }
    if (!sweepRows.empty()) {
      std::printf("\n**sweep** (%s points):\n\n", evalSamplingName(reports[0].sampling));
      std::printf("| spacing | method | gross | mean rel | bytes | CPU ns coherent | GPU ms |\n");
      std::printf("|---|---|---|---|---|---|---|\n");
      for (const SweepRow& row : sweepRows)
        for (const MethodResult& m : row.report.methods) {
          char g[32] = "-";
          if (m.gpuMs >= 0.0) std::snprintf(g, sizeof g, "%.1f", m.gpuMs);
          std::printf("| %g m | %s | %.1f %% | %.3f | %s | %.1f | %s |\n", row.spacing, m.name.c_str(),
                      100.0 * m.grossError, m.meanRelError, mb(m.bytes).c_str(), m.cpuNsCoherent, g);
        }
    }
  }

  if (args.has("--plot")) {
    const bool haveGpu = std::any_of(reports[0].methods.begin(), reports[0].methods.end(),
                                     [](const MethodResult& m) { return m.gpuMs >= 0.0; });
    PlotOptions po;
    po.title = args.positional()[0] + " (" + evalSamplingName(reports[0].sampling) + " points)";
    po.timeAxis = haveGpu ? "GPU ms, 1280x720 lookup pass (lavapipe)"
                          : "CPU ns per query (" + std::to_string(resolveThreads(opt.threads)) + " threads)";
    po.pareto = !sweepRows.empty();
    std::vector<PlotPoint> points;
    auto add = [&](const MethodResult& m, const std::string& label) {
      // A method without a GPU pass (tet+occlusion) is placed by CPU time only when no method has a GPU time.
      points.push_back({m.name, label, double(m.bytes), haveGpu ? m.gpuMs : m.cpuNsCoherent, m.meanRelError,
                        m.grossError});
    };
    if (sweepRows.empty()) {
      for (const MethodResult& m : reports[0].methods) add(m, m.name);
    } else {
      for (const SweepRow& row : sweepRows) {
        char label[32];
        std::snprintf(label, sizeof label, "%g m", row.spacing);
        for (const MethodResult& m : row.report.methods) add(m, label);
      }
    }
    const std::string plot = args.str("--plot");
    std::string error;
    if (!writeFileAtomic(plot, evalPlot(points, po, plotIsPng(plot) ? PlotFormat::kPng : PlotFormat::kSvg),
                         &error))
      throw std::runtime_error(error);
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
      for (const auto& m : report.methods) methods.push_back(methodJson(m, coherent.order));
      nlohmann::json ref = {{"sampling", evalSamplingName(report.sampling)},
                            {"points", report.points.size()},
                            {"samples_per_point", report.samplesPerPoint},
                            {"bounces", depth},
                            {"mean_rel_stderr", report.meanRelStderr},
                            {"indirect_only_points", report.indirectOnlyPoints},
                            {"closed_points", report.closedPoints},
                            {"rel_floor", report.relFloor},
                            {"seconds", report.referenceSeconds}};
      return nlohmann::json{{"reference", ref}, {"methods", methods}};
    };
    nlohmann::json j = setJson(reports[0]);
    j["scene"] = args.positional()[0];
    j["level"] = args.positional()[1];
    j["sets"] = nlohmann::json::object();
    for (const EvalReport& report : reports) j["sets"][evalSamplingName(report.sampling)] = setJson(report);
    j["timing"] = {{"threads", resolveThreads(opt.threads)},
                   {"points", coherent.position.size()},
                   {"coherent_order", coherent.order},
                   {"cpu_runs", 7},
                   {"gpu", gpu && gpuError.empty() ? "1280x720 lighting pass, median of 3 renders"
                                                   : (gpu ? "failed: " + gpuError : "not measured")}};
    j["grid_notes"] = lut.notes;
    if (!halfJson.is_null()) j["half_resolution"] = halfJson;
    if (!sweepRows.empty()) {
      j["sweep"] = nlohmann::json::array();
      for (const SweepRow& row : sweepRows) {
        nlohmann::json methods = nlohmann::json::array();
        for (const auto& m : row.report.methods) methods.push_back(methodJson(m, coherent.order));
        j["sweep"].push_back({{"spacing", row.spacing}, {"probes", row.probes}, {"methods", methods}});
      }
    }
    if (stored)
      j["occlusion"] = {{"mode", "stored"}, {"bytes", level->occlusion.bytes()}};
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
