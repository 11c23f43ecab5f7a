// Probe bake throughput against bare Embree on a procedural level: a closed room (emissive ceiling panel)
// filled with a grid of crates, each made of finely split quads (~100k triangles in all). BM_BakeProbes bakes
// a fixed set of probes (rays/s and probes/s); BM_EmbreeReplay traces exactly the rays that bake traced for
// a subset of the probes with bare rtcIntersect1/rtcOccluded1. The ratio of their rays/s is the share of
// Embree's rate the baker keeps (issue #5's goal: >= 70 %). Single-threaded, both.
#include <benchmark/benchmark.h>

#include <memory>
#include <string>
#include <vector>

#include "test_scenes.h"
#include "tetraprobe/bake/bake.h"
#include "tetraprobe/bake/bench_rays.h"
#include "tetraprobe/bake/tracer.h"

namespace {

using namespace tetraprobe;
// The procedural scene is built with the bake tests' helpers (tests/bake/test_scenes.h).
using test::addBox;
using test::addMaterial;
using test::addQuad;

struct Fixture {
  Scene scene;
  std::unique_ptr<SceneTracer> tracer;
  std::vector<glm::dvec3> probes;
  std::vector<RecordedRay> rays;  // of the first kRecorded probes
  BakeOptions options;
};

constexpr int kProbes = 64;
constexpr int kRecorded = 16;

const Fixture& fixture() {
  static std::unique_ptr<Fixture> f;
  if (f) return *f;
  f = std::make_unique<Fixture>();
  Scene& s = f->scene;
  const uint32_t wall = addMaterial(s, glm::vec3(0.7f, 0.65f, 0.6f));
  const uint32_t crate = addMaterial(s, glm::vec3(0.5f, 0.3f, 0.2f));
  const uint32_t lamp = addMaterial(s, glm::vec3(0.8f), glm::vec3(20.0f, 18.0f, 15.0f));
  addBox(s, {-10, 0, -10}, {10, 5, 10}, true, wall, 40);  // 19,200 triangles
  for (int z = 0; z < 8; ++z)
    for (int x = 0; x < 8; ++x) {  // 64 crates x 1,200 triangles
      const glm::vec3 c(-8.75f + 2.5f * x, 0.0f, -8.75f + 2.5f * z);
      addBox(s, c + glm::vec3(-0.5f, 0.0f, -0.5f), c + glm::vec3(0.5f, 0.5f + 0.25f * ((x + z) % 4), 0.5f),
             false, crate, 10);
    }
  addQuad(s, {-2, 4.99f, 2}, {2, 4.99f, 2}, {2, 4.99f, -2}, {-2, 4.99f, -2}, lamp, 4);  // faces down
  f->tracer = std::make_unique<SceneTracer>(s);
  for (int i = 0; i < kProbes; ++i)
    f->probes.push_back({-9.0 + 18.0 * ((i * 37) % kProbes) / kProbes, 2.5 + 2.0 * ((i * 11) % 7) / 7.0 - 1.0,
                         -9.0 + 18.0 * ((i * 53) % kProbes) / kProbes + 0.1});
  f->options.samplesPerProbe = 128;
  f->options.bounces = 2;
  f->options.threads = 1;
  f->options.progress = false;
  std::vector<glm::dvec3> subset(f->probes.begin(), f->probes.begin() + kRecorded);
  std::vector<size_t> indices(kRecorded);
  for (int i = 0; i < kRecorded; ++i) indices[size_t(i)] = size_t(i);
  f->rays = recordBakeRays(*f->tracer, subset, indices, f->options);
  return *f;
}

void BM_BakeProbes(benchmark::State& state) {
  const Fixture& f = fixture();
  uint64_t rays = 0, probes = 0;
  for (auto _ : state) {
    BakeStats stats;
    benchmark::DoNotOptimize(bakeProbes(*f.tracer, f.probes, f.options, &stats));
    rays += stats.rays();
    probes += f.probes.size();
  }
  state.counters["rays_per_s"] = benchmark::Counter(double(rays), benchmark::Counter::kIsRate);
  state.counters["probes_per_s"] = benchmark::Counter(double(probes), benchmark::Counter::kIsRate);
  state.counters["triangles"] = double(f.scene.triangles.size());
}
BENCHMARK(BM_BakeProbes)->Unit(benchmark::kMillisecond)->UseRealTime();

void BM_EmbreeReplay(benchmark::State& state) {
  const Fixture& f = fixture();
  uint64_t rays = 0, mismatches = 0;
  for (auto _ : state) {
    const ReplayResult r = replayRays(*f.tracer, f.rays, 1, 0.0);
    rays += r.rays;
    mismatches += r.mismatches;
  }
  state.counters["rays_per_s"] = benchmark::Counter(double(rays), benchmark::Counter::kIsRate);
  state.counters["mismatches"] = double(mismatches);
  state.counters["rays_per_pass"] = double(f.rays.size());
}
BENCHMARK(BM_EmbreeReplay)->Unit(benchmark::kMillisecond)->UseRealTime();

}  // namespace

BENCHMARK_MAIN();
