// Query throughput of the CPU runtime on a synthetic level (jittered grid of probes, Delaunay tets): the tet
// lookup (start grid + walk), the same with a per-object cached tet (coherent order), and the nearest-probe
// baseline, all on the same points in one run. Reported as queries/s (items_per_second).
#include <benchmark/benchmark.h>

#include <cmath>
#include <cstdint>
#include <map>
#include <memory>
#include <random>
#include <vector>

#include <glm/geometric.hpp>

#include "tetraprobe/eval/nearest_probe.h"
#include "tetraprobe/runtime/query.h"
#include "tetraprobe/tetra/tetrahedralize.h"

namespace {

using namespace tetraprobe;

struct Fixture {
  Level level;
  std::unique_ptr<ProbeQuery> query;
  std::unique_ptr<NearestProbe> nearest;
  std::vector<glm::dvec3> random, coherent;
  glm::vec3 normal = glm::normalize(glm::vec3(0.3f, 0.9f, 0.1f));
};

// n^3 probes on a 1 m grid with +-0.2 m jitter; SH with a smooth gradient.
const Fixture& fixture(int n) {
  static std::map<int, std::unique_ptr<Fixture>> cache;
  auto& f = cache[n];
  if (f) return *f;
  f = std::make_unique<Fixture>();
  std::mt19937_64 rng(42);
  std::uniform_real_distribution<double> jitter(-0.2, 0.2);
  std::vector<glm::dvec3> pts;
  for (int z = 0; z < n; ++z)
    for (int y = 0; y < n; ++y)
      for (int x = 0; x < n; ++x) pts.emplace_back(x + jitter(rng), y + jitter(rng), z + jitter(rng));
  const TetMesh mesh = tetrahedralizeDelaunay(pts);
  f->level.origin = glm::dvec3(0.0);
  for (const auto& p : pts) {
    f->level.probes.push_back(glm::vec3(p));
    ShRgb sh;
    sh.c[0] = glm::vec3(float(1.0 + 0.1 * p.x), float(1.0 + 0.05 * p.y), 1.0f);
    sh.c[2] = glm::vec3(0.3f);
    f->level.sh.push_back(sh);
  }
  f->level.tets = buildTetRecords(pts, mesh, f->level.origin);
  f->query = std::make_unique<ProbeQuery>(f->level);
  f->nearest = std::make_unique<NearestProbe>(f->level);
  std::uniform_real_distribution<double> u(0.0, double(n - 1));
  for (int i = 0; i < 1 << 16; ++i) f->random.emplace_back(u(rng), u(rng), u(rng));
  // Coherent: a raster sweep over a plane through the level, like the pixels of a render.
  for (int j = 0; j < 256; ++j)
    for (int i = 0; i < 256; ++i)
      f->coherent.emplace_back((n - 1) * i / 255.0, (n - 1) * 0.5 + 0.3 * std::sin(i * 0.05),
                               (n - 1) * j / 255.0);
  return *f;
}

void BM_TetRandom(benchmark::State& state) {
  const Fixture& f = fixture(int(state.range(0)));
  size_t i = 0;
  for (auto _ : state) {
    benchmark::DoNotOptimize(f.query->irradiance(f.random[i], f.normal));
    i = (i + 1) & (f.random.size() - 1);
  }
  state.SetItemsProcessed(state.iterations());
}

void BM_TetCoherentCached(benchmark::State& state) {
  const Fixture& f = fixture(int(state.range(0)));
  size_t i = 0;
  int32_t cache = -1;
  for (auto _ : state) {
    benchmark::DoNotOptimize(f.query->irradiance(f.coherent[i], f.normal, &cache));
    i = (i + 1) & (f.coherent.size() - 1);
  }
  state.SetItemsProcessed(state.iterations());
}

void BM_NearestRandom(benchmark::State& state) {
  const Fixture& f = fixture(int(state.range(0)));
  size_t i = 0;
  for (auto _ : state) {
    const int32_t p = f.nearest->nearest(glm::vec3(f.random[i]));
    benchmark::DoNotOptimize(shIrradiance(f.level.sh[size_t(p)], f.normal));
    i = (i + 1) & (f.random.size() - 1);
  }
  state.SetItemsProcessed(state.iterations());
}

BENCHMARK(BM_TetRandom)->Arg(16)->Arg(48);
BENCHMARK(BM_TetCoherentCached)->Arg(16)->Arg(48);
BENCHMARK(BM_NearestRandom)->Arg(16)->Arg(48);

}  // namespace

BENCHMARK_MAIN();
