// `tetraprobe reference SCENE --points FILE.csv`: path-traced ground-truth irradiance at given surface
// points, each sampled until its luminance's relative standard error reaches a target
// (referenceIrradianceToError).
#include <cmath>
#include <cstdio>
#include <fstream>
#include <sstream>

#include <glm/geometric.hpp>

#include "args.h"
#include "commands.h"
#include "tetraprobe/bake/bake.h"
#include "tetraprobe/common/error.h"
#include "tetraprobe/common/parallel.h"
#include "tetraprobe/scene/load.h"

namespace tetraprobe::cli {

namespace {

std::string trim(const std::string& s) {
  const size_t b = s.find_first_not_of(" \t\r");
  if (b == std::string::npos) return {};
  return s.substr(b, s.find_last_not_of(" \t\r") - b + 1);
}

struct RefPoint {
  glm::dvec3 position{0.0};
  glm::vec3 normal{0.0f};
};

// Lines x,y,z,nx,ny,nz (world metres, normal any non-zero length); blank and '#' lines skipped.
std::vector<RefPoint> readPoints(const std::string& file) {
  std::ifstream in(file);
  if (!in) throw InputError(file + ": cannot open");
  std::vector<RefPoint> points;
  std::string line;
  for (int lineNo = 1; std::getline(in, line); ++lineNo) {
    const std::string content = trim(line);
    if (content.empty() || content[0] == '#') continue;
    const std::string where = file + ":" + std::to_string(lineNo);
    std::stringstream ss(content);
    std::string cell;
    double v[6];
    int k = 0;
    while (std::getline(ss, cell, ',')) {
      if (k >= 6) throw InputError(where + ": expected x,y,z,nx,ny,nz (6 numbers), got more");
      try {
        v[k++] = parseNumber(trim(cell), "value");
      } catch (const UsageError& e) {
        throw InputError(where + ": " + e.what());
      }
    }
    if (k != 6) throw InputError(where + ": expected x,y,z,nx,ny,nz (6 numbers), got " + std::to_string(k));
    const glm::vec3 n{float(v[3]), float(v[4]), float(v[5])};
    const float len = glm::length(n);
    if (!(len > 0.0f) || !std::isfinite(len))
      throw InputError(where + ": normal must be a non-zero finite vector");
    points.push_back({glm::dvec3(v[0], v[1], v[2]), n / len});
  }
  if (in.bad()) throw InputError(file + ": read failed");
  return points;
}

// Per-line seed: the line's index in the file's points, mixed with --seed (SplitMix64 finaliser), so a
// line's answer does not depend on the thread that computes it or on the other lines.
uint64_t lineSeed(uint64_t seed, size_t index) {
  uint64_t x = seed * 0x9e3779b97f4a7c15ull + index + 1;
  x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ull;
  x = (x ^ (x >> 27)) * 0x94d049bb133111ebull;
  return x ^ (x >> 31);
}

}  // namespace

int cmdReference(int argc, char** argv) {
  Args args("tetraprobe reference SCENE --points FILE.csv [options]",
            "Path-traced reference irradiance E (W/m^2) at surface points: reads lines x,y,z,nx,ny,nz and\n"
            "prints one line r,g,b,stderr_r,stderr_g,stderr_b each, in input order. Each point is sampled\n"
            "until the standard error of its luminance is at most --rel-error x its luminance, or\n"
            "--max-samples. Deterministic: a line's result depends only on it, its index and --seed.",
            {{"--points", "", "FILE.csv", "points to evaluate (x,y,z,nx,ny,nz a line)", ""},
             {"--rel-error", "", "E", "target relative standard error of the luminance", "0.01"},
             {"--max-samples", "", "N", "sample cap per point", "65536"},
             {"--bounces", "", "N|unbounded",
              "path depth; unbounded = Russian roulette only (unbiased ground truth)", "unbounded"},
             {"--content", "", "default|all", "light content, as for bake", "default"},
             {"--seed", "", "N", "random seed", "1"},
             {"--threads", "", "N", "worker threads, 0 = all cores (never changes the output)", "0"}});
  if (!args.parse(argc, argv)) return 0;
  args.requirePositional(1, 1);
  if (!args.has("--points")) throw UsageError("missing --points FILE.csv");
  const double relError = args.number("--rel-error");
  const int maxSamples = args.integer("--max-samples");
  const int threads = args.integer("--threads");
  BakeOptions bake;
  bake.bounces = args.bounces("--bounces");
  bake.progress = false;
  if (!(relError >= 0.0)) throw UsageError("--rel-error must be >= 0");
  if (maxSamples < 1) throw UsageError("--max-samples must be at least 1");
  if (threads < 0) throw UsageError("--threads must be >= 0");
  const std::string content = args.str("--content");
  if (content == "default")
    bake.content = kContentDefault;
  else if (content == "all")
    bake.content = kContentAll;
  else
    throw UsageError("--content must be 'default' or 'all', not '" + content + "'");
  const uint64_t seed = args.u64("--seed");

  const std::vector<RefPoint> points = readPoints(args.str("--points"));
  const Scene scene = loadScene(args.positional()[0]);
  for (const auto& w : scene.warnings) std::fprintf(stderr, "tetraprobe reference: warning: %s\n", w.c_str());
  const SceneTracer tracer(scene);
  std::vector<ReferenceIrradiance> out(points.size());
  parallelFor(points.size(), threads, [&](size_t i) {
    out[i] = referenceIrradianceToError(tracer, points[i].position, points[i].normal, relError, maxSamples,
                                        lineSeed(seed, i), bake);
  });
  for (const ReferenceIrradiance& r : out)
    std::printf("%.9g,%.9g,%.9g,%.9g,%.9g,%.9g\n", r.irradiance.x, r.irradiance.y, r.irradiance.z,
                r.stderror.x, r.stderror.y, r.stderror.z);
  return 0;
}

}  // namespace tetraprobe::cli
