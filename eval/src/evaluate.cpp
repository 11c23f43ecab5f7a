// Accuracy evaluation of probe lookups: path-traced references at random surface points, then per-method
// error statistics (relmse, mean/p95 relative error, leak) and single-thread lookup cost.
#include "tetraprobe/eval/evaluate.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <memory>
#include <string>
#include <utility>

#include <glm/common.hpp>
#include <glm/geometric.hpp>

#include "tetraprobe/common/error.h"
#include "tetraprobe/common/parallel.h"
#include "tetraprobe/common/progress.h"
#include "tetraprobe/common/splitmix.h"
#include "tetraprobe/eval/nearest_probe.h"
#include "tetraprobe/eval/reference_image.h"
#include "tetraprobe/occlusion/occlusion_holes.h"
#include "tetraprobe/runtime/gpu_layout.h"
#include "tetraprobe/runtime/gpu_tets.h"
#include "tetraprobe/runtime/luminance.h"
#include "tetraprobe/runtime/query.h"
#include "tetraprobe/runtime/sh_half.h"
#include "tetraprobe/runtime/shade.h"
#include "tetraprobe/runtime/start_bricks.h"

namespace tetraprobe {

namespace {

constexpr double kFloor = 0.01;  // W/m^2, see evaluate.h

// The report's header and its points' surfaces, drawn as options.sampling says (both reference paths draw
// the same points for the same options).
EvalReport drawPoints(const SceneTracer& tracer, const EvalOptions& options,
                      std::vector<SurfacePoint>& surface) {
  if (options.sampling == EvalSampling::kCameras && options.cameras.empty())
    throw InputError("eval: camera sampling needs at least one camera (the scene names none)");
  EvalReport report;
  report.sampling = options.sampling;
  report.samplesPerPoint = options.samplesPerPoint;
  report.referenceBounces = options.referenceBounces;
  surface = options.sampling == EvalSampling::kCameras
                ? sampleCameraPoints(tracer, options.cameras, options.points, options.seed)
                : sampleSurfacePoints(tracer, options.points, options.seed);
  report.points.resize(surface.size());
  return report;
}

// Each point's indirectOnly, and indirectOnlyPoints and meanRelStderr, from the points' references.
void summarizeReferences(EvalReport& report) {
  double sum = 0.0;
  for (auto& p : report.points) {
    const double y = luminance(glm::dvec3(p.reference.irradiance));
    p.indirectOnly = luminance(glm::dvec3(p.direct)) < kIndirectOnlyFraction * y;
    report.indirectOnlyPoints += p.indirectOnly ? 1 : 0;
    sum += luminance(glm::dvec3(p.reference.stderror)) / std::sqrt(y * y + kFloor);
  }
  report.meanRelStderr = report.points.empty() ? 0.0 : sum / double(report.points.size());
}

}  // namespace

const char* evalSamplingName(EvalSampling sampling) {
  return sampling == EvalSampling::kCameras ? "cameras" : "area";
}

EvalReport computeReference(const SceneTracer& tracer, uint32_t content, const EvalOptions& options) {
  const auto start = std::chrono::steady_clock::now();
  std::vector<SurfacePoint> surface;
  EvalReport report = drawPoints(tracer, options, surface);
  BakeOptions bake;
  bake.bounces = options.referenceBounces;
  bake.content = content;
  bake.threads = 1;
  bake.progress = false;
  Progress progress("reference", surface.size(), "points", options.progress);
  parallelFor(surface.size(), options.threads, [&](size_t i) {
    report.points[i].surface = surface[i];
    report.points[i].reference =
        referenceIrradiance(tracer, surface[i].position, surface[i].normal, options.samplesPerPoint,
                            splitmix64(options.seed ^ splitmix64(i)), bake);
    // The direct part (0 bounces: only NEE and emitters hit at once; cheap, so a quarter of the samples).
    BakeOptions direct = bake;
    direct.bounces = 0;
    report.points[i].direct =
        referenceIrradiance(tracer, surface[i].position, surface[i].normal,
                            std::max(1, options.samplesPerPoint / 4),
                            splitmix64(options.seed ^ splitmix64(i) ^ 0xd1ec7ull), direct)
            .irradiance;
    progress.advance();
  });
  progress.finish();
  summarizeReferences(report);
  report.referenceSeconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return report;
}

EvalReport reuseReference(const SceneTracer& tracer, const EvalOptions& options,
                          const std::vector<StoredReference>& stored) {
  std::vector<SurfacePoint> surface;
  EvalReport report = drawPoints(tracer, options, surface);
  const std::string set = evalSamplingName(options.sampling);
  if (surface.size() != stored.size())
    throw InputError("eval: the stored references hold " + std::to_string(stored.size()) + " " + set +
                     " points, the sampling draws " + std::to_string(surface.size()) +
                     " (another scene, --points or --seed?)");
  for (size_t i = 0; i < surface.size(); ++i) {
    const StoredReference& s = stored[i];
    const double tol = 1e-4 + 1e-6 * glm::length(surface[i].position);
    if (glm::length(surface[i].position - s.position) > tol ||
        glm::length(surface[i].normal - s.normal) > 1e-4f)
      throw InputError("eval: stored " + set + " reference point " + std::to_string(i) +
                       " is not the point the sampling draws (another scene, --points or --seed?)");
    EvalPoint& p = report.points[i];
    p.surface = surface[i];
    p.reference.irradiance = s.irradiance;
    p.reference.stderror = s.stderror;
    p.reference.samples = options.samplesPerPoint;
    p.direct = s.direct;
  }
  summarizeReferences(report);
  return report;
}

bool noPathLeaves(const ReferenceIrradiance& reference) {
  const glm::vec3 r = reference.irradiance;
  return r.x == 0.0f && r.y == 0.0f && r.z == 0.0f;
}

bool noPathLeaves(const EvalPoint& point) {
  return noPathLeaves(point.reference);
}

void scoreMethod(EvalReport& report, const LookupMethod& method) {
  MethodResult m;
  m.name = method.name;
  m.bytes = method.bytes;
  m.sections = method.sections;
  m.probes = method.probes;
  const size_t n = report.points.size();
  m.values.resize(n);
  for (size_t i = 0; i < n; ++i)
    m.values[i] = method.lookup(report.points[i].surface.position, report.points[i].surface.normal);

  // The relative floor f: kRelFloorFraction of the open points' mean reference luminance (kFloor when
  // there is no open point or no light).
  size_t open = 0;
  double brightness = 0.0;
  for (const EvalPoint& p : report.points)
    if (!noPathLeaves(p)) {
      brightness += luminance(glm::dvec3(p.reference.irradiance));
      ++open;
    }
  const double f = open > 0 && brightness > 0.0 ? kRelFloorFraction * brightness / double(open) : kFloor;
  report.relFloor = f;
  report.closedPoints = n - open;

  std::vector<double> rel, relAbs(n);
  rel.reserve(open);
  double se = 0.0, seAbs = 0.0, leak = 0.0, leakIndirect = 0.0;
  glm::dvec3 closedSum(0.0);
  size_t indirect = 0, gross = 0, dark = 0, fallback = 0, closedFallback = 0;
  for (size_t i = 0; i < n; ++i) {
    const glm::vec3 x = m.values[i], r = report.points[i].reference.irradiance;
    if (method.fallback &&
        method.fallback(report.points[i].surface.position, report.points[i].surface.normal) > 0.0f)
      ++(noPathLeaves(report.points[i]) ? closedFallback : fallback);
    double e = 0.0, eAbs = 0.0, sq = 0.0;
    for (int c = 0; c < 3; ++c) {
      const double d = double(x[c]) - double(r[c]), rc = double(r[c]);
      seAbs += d * d / (rc * rc + kFloor);
      eAbs += std::abs(d) / std::sqrt(rc * rc + kFloor);
      const double scale = std::max(rc, f);
      sq += d * d / (scale * scale);
      e += std::abs(d) / scale;
    }
    relAbs[i] = eAbs / 3.0;
    if (noPathLeaves(report.points[i])) {  // reported apart: no scale to be relative to
      closedSum += glm::dvec3(x);
      continue;
    }
    se += sq;
    rel.push_back(e / 3.0);
    const double yx = luminance(glm::dvec3(x)), yr = luminance(glm::dvec3(r));
    const double lx = std::max(yx, kFloor), lr = std::max(yr, kFloor);
    gross += (lx > 2.0 * lr || lx < 0.5 * lr) ? 1 : 0;
    dark += lx < 0.25 * lr ? 1 : 0;
    const double l = std::max(0.0, yx - yr) / lr;
    leak += l;
    if (report.points[i].indirectOnly) {
      leakIndirect += l;
      ++indirect;
    }
  }
  // The p-th percentile of `v` (sorted in place): the ceil(p n)-th smallest.
  auto percentile = [](std::vector<double>& v, double p) {
    std::sort(v.begin(), v.end());
    return v[std::min(v.size() - 1, size_t(std::ceil(p * double(v.size()))) - 1)];
  };
  if (indirect > 0) m.leakIndirect = leakIndirect / double(indirect);
  if (method.fallback) {
    m.fallback = open > 0 ? double(fallback) / double(open) : 0.0;
    m.closedFallbackPoints = closedFallback;
  }
  if (n > open) m.closedMean = glm::vec3(closedSum / double(n - open));
  if (open > 0) {
    m.relmse = se / double(3 * open);
    double sum = 0.0;
    for (double e : rel) sum += e;
    m.meanRelError = sum / double(open);
    m.leak = leak / double(open);
    m.grossError = double(gross) / double(open);
    m.darkHoles = double(dark) / double(open);
    m.p95RelError = percentile(rel, 0.95);
  }
  if (n > 0) {
    m.relmseAbsFloor = seAbs / double(3 * n);
    double sum = 0.0;
    for (double e : relAbs) sum += e;
    m.meanRelAbsFloor = sum / double(n);
    m.p95RelAbsFloor = percentile(relAbs, 0.95);

    // Cost: repeat full passes until ~20 ms have run, take the fastest pass (least disturbed).
    double bestNs = 1e300;
    volatile float sink = 0.0f;
    const auto budgetStart = std::chrono::steady_clock::now();
    for (int pass = 0; pass < 1000; ++pass) {
      const auto t0 = std::chrono::steady_clock::now();
      for (size_t i = 0; i < n; ++i)
        sink = sink + method.lookup(report.points[i].surface.position, report.points[i].surface.normal).x;
      const auto t1 = std::chrono::steady_clock::now();
      bestNs = std::min(bestNs, std::chrono::duration<double, std::nano>(t1 - t0).count() / double(n));
      if (pass >= 4 && std::chrono::duration<double>(t1 - budgetStart).count() > 0.02) break;
    }
    m.cpuNsPerQuery = bestNs;
  }
  report.methods.push_back(std::move(m));
}

uint64_t totalBytes(const std::vector<ByteSection>& sections) {
  uint64_t sum = 0;
  for (const ByteSection& s : sections) sum += s.bytes;
  return sum;
}

std::vector<ByteSection> tetLookupBytes(const ProbeQuery& query, bool occlusion) {
  const Level& level = query.level();
  std::vector<ByteSection> out = {
      {"positions", level.probes.size() * sizeof(glm::vec3)},
      {"sh",
       level.sh.size() * sizeof(ShHalf)},  // as the file and the GPU hold them (the CPU expands to float)
      {"tets", gpuTetBytes(level.probes.size(), level.tets.size())},  // packed (gpu_tets.h)
      {"start_bricks",
       startBricksBytes(query.cellGrid(),
                        level.tets.size())},  // the GPU's start (the CPU's BSP is not read there)
      {"outer_cells", query.outerCells().size() * sizeof(GpuOuterCell)},
      {"start_grid", query.startGrid().startTet.size() * sizeof(int32_t)},
  };
  if (occlusion) out.push_back({"occlusion", gpuOcclusionBytes(level.occlusion)});
  return out;
}

std::vector<LookupMethod> standardMethods(const Level& level) {
  std::vector<LookupMethod> methods;
  const glm::dvec3 origin = level.origin;
  const uint64_t probes = level.probes.size();

  // ProbeQuery applies the level's stored occlusion, if any; then `tet (no occlusion)` shows what it removes.
  auto query = std::make_shared<ProbeQuery>(level);
  {
    LookupMethod tet;
    tet.name = "tet";
    tet.sections = tetLookupBytes(*query, !level.occlusion.empty());
    tet.bytes = totalBytes(tet.sections);
    tet.probes = probes;
    tet.lookup = [query](const glm::dvec3& p, const glm::vec3& n) { return query->irradiance(p, n); };
    tet.fallback = [query](const glm::dvec3& p, const glm::vec3& n) {
      ShadeRecord record;
      query->explain(p, n, record);
      return record.fallback;
    };
    tet.batch = [query](const glm::dvec3* p, const glm::vec3* n, glm::vec3* out, size_t count) {
      query->irradianceBatch(p, n, out, count, 1);
    };
    methods.push_back(std::move(tet));
  }
  if (!level.occlusion.empty()) {
    auto plain = std::make_shared<ProbeQuery>(level);
    plain->setUseOcclusion(false);
    LookupMethod tet;
    tet.name = "tet (no occlusion)";
    tet.sections = tetLookupBytes(*plain, false);
    tet.bytes = totalBytes(tet.sections);
    tet.probes = probes;
    tet.lookup = [plain](const glm::dvec3& p, const glm::vec3& n) { return plain->irradiance(p, n); };
    tet.fallback = [plain](const glm::dvec3& p, const glm::vec3& n) {
      ShadeRecord record;
      plain->explain(p, n, record);
      return record.fallback;
    };
    tet.batch = [plain](const glm::dvec3* p, const glm::vec3* n, glm::vec3* out, size_t count) {
      plain->irradianceBatch(p, n, out, count, 1);
    };
    methods.push_back(std::move(tet));
  }

  auto nearest = std::make_shared<NearestProbe>(level);
  const Level* lv = &level;
  LookupMethod near;
  near.name = "nearest";
  near.sections = {{"positions", probes * sizeof(glm::vec3)},
                   {"sh", probes * sizeof(ShHalf)},
                   {"buckets", nearest->bytes()}};
  near.bytes = totalBytes(near.sections);
  near.probes = probes;
  near.lookup = [nearest, lv, origin](const glm::dvec3& p, const glm::vec3& n) {
    const int32_t i = nearest->nearest(glm::vec3(p - origin));
    return i < 0 ? glm::vec3(0.0f) : shIrradiance(lv->sh[size_t(i)], n);
  };
  methods.push_back(std::move(near));
  return methods;
}

LookupMethod gridMethod(std::shared_ptr<const GridVolume> grid, const std::string& name) {
  LookupMethod m;
  m.name = name;
  m.sections = {{"header", kGridHeaderBytes}, {"sh", grid->layout().nodes() * kGridNodeBytes}};
  m.bytes = grid->bytes();
  m.probes = grid->layout().nodes();
  m.lookup = [grid](const glm::dvec3& p, const glm::vec3& n) { return grid->irradiance(p, n); };
  return m;
}

TimingPoints cameraTimingPoints(const SceneTracer& tracer, const Camera& camera, int width, int height,
                                int threads) {
  RenderView view;
  view.eye = camera.eye;
  view.target = camera.target;
  view.up = camera.up;
  view.fovYDeg = camera.fovYDeg;
  view.width = width;
  view.height = height;
  const ReferenceGBuffer g = traceReferenceGBuffer(tracer, view, threads);
  TimingPoints out;
  for (size_t i = 0; i < g.hit.size(); ++i)
    if (g.hit[i]) {
      out.position.push_back(g.position[i]);
      out.normal.push_back(g.normal[i]);
    }
  out.order = "pixels of camera " + (camera.name.empty() ? std::string("0") : camera.name) + " " +
              std::to_string(width) + "x" + std::to_string(height);
  return out;
}

TimingPoints mortonTimingPoints(const EvalReport& report) {
  TimingPoints out;
  const size_t n = report.points.size();
  if (n == 0) return out;
  glm::dvec3 lo = report.points[0].surface.position, hi = lo;
  for (const EvalPoint& p : report.points) {
    lo = glm::min(lo, p.surface.position);
    hi = glm::max(hi, p.surface.position);
  }
  const glm::dvec3 ext = glm::max(hi - lo, glm::dvec3(1e-9));
  auto spread = [](uint64_t v) {  // 21 bits -> every third bit
    v &= 0x1fffff;
    v = (v | v << 32) & 0x1f00000000ffffull;
    v = (v | v << 16) & 0x1f0000ff0000ffull;
    v = (v | v << 8) & 0x100f00f00f00f00full;
    v = (v | v << 4) & 0x10c30c30c30c30c3ull;
    v = (v | v << 2) & 0x1249249249249249ull;
    return v;
  };
  std::vector<std::pair<uint64_t, size_t>> keys(n);
  for (size_t i = 0; i < n; ++i) {
    const glm::dvec3 u = (report.points[i].surface.position - lo) / ext * double((1 << 21) - 1);
    keys[i] = {spread(uint64_t(u.x)) | spread(uint64_t(u.y)) << 1 | spread(uint64_t(u.z)) << 2, i};
  }
  std::sort(keys.begin(), keys.end());
  for (const auto& [key, i] : keys) {
    out.position.push_back(report.points[i].surface.position);
    out.normal.push_back(report.points[i].surface.normal);
  }
  out.order = "morton order of the points";
  return out;
}

TimingPoints shuffledTimingPoints(const TimingPoints& points, uint64_t seed) {
  TimingPoints out = points;
  uint64_t state = seed;
  for (size_t i = out.position.size(); i > 1; --i) {
    state = splitmix64(state);
    const size_t j = size_t(state % i);
    std::swap(out.position[i - 1], out.position[j]);
    std::swap(out.normal[i - 1], out.normal[j]);
  }
  out.order = "random";
  return out;
}

double timeLookup(const LookupMethod& method, const TimingPoints& points, int threads, int runs) {
  const size_t n = points.position.size();
  if (n == 0) return 0.0;
  const int t = std::max(1, std::min<int>(resolveThreads(threads), int(n)));
  std::vector<glm::vec3> out(n);
  auto pass = [&] {
    parallelFor(
        size_t(t), t,
        [&](size_t k) {
          const size_t begin = n * k / size_t(t), end = n * (k + 1) / size_t(t);
          if (method.batch) {
            method.batch(&points.position[begin], &points.normal[begin], &out[begin], end - begin);
          } else {
            for (size_t i = begin; i < end; ++i) out[i] = method.lookup(points.position[i], points.normal[i]);
          }
        },
        1);
  };
  pass();  // warm-up: caches, page faults, lazily built data
  std::vector<double> ns;
  for (int r = 0; r < std::max(1, runs); ++r) {
    const auto t0 = std::chrono::steady_clock::now();
    pass();
    ns.push_back(std::chrono::duration<double, std::nano>(std::chrono::steady_clock::now() - t0).count() /
                 double(n));
  }
  std::sort(ns.begin(), ns.end());
  return ns[ns.size() / 2];
}

}  // namespace tetraprobe

namespace tetraprobe {

std::vector<float> fallbackShares(const Level& level, const EvalReport& report) {
  std::vector<float> out(report.points.size(), 0.0f);
  if (level.occlusion.empty()) return out;
  const ProbeQuery query(level);
  for (size_t i = 0; i < out.size(); ++i)
    out[i] = occlusionFallbackShare(level, query, report.points[i].surface.position,
                                    report.points[i].surface.normal);
  return out;
}

LookupMethod occlusionMethod(const Level& level, std::shared_ptr<const LevelOcclusion> occlusion) {
  auto query = std::make_shared<ProbeQuery>(level);
  std::vector<ByteSection> sections = tetLookupBytes(*query, false);
  sections.push_back({"occlusion", gpuOcclusionBytes(*occlusion)});
  const Level* lv = &level;
  LookupMethod m{"tet+occlusion", totalBytes(sections), sections, level.probes.size(),
                 [query, occlusion, lv](const glm::dvec3& p, const glm::vec3& n) {
                   return shadeLocated(*lv, occlusion.get(), query->locate(p), p, n);
                 }};
  m.fallback = [query, occlusion, lv](const glm::dvec3& p, const glm::vec3& n) {
    ShadeRecord record;
    shadeLocated(*lv, occlusion.get(), query->locate(p), p, n, &record);
    return record.fallback;
  };
  return m;
}

}  // namespace tetraprobe
