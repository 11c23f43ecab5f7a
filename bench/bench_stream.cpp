// What loading a sector costs as more are loaded: the GPU sector pool (runtime/gpu_sector_pool.h: the
// sector's records written into slots, O(sector)) against its peer in the same run, StreamingLevel (the
// sector read, then the joined level and its query rebuilt from every loaded sector). Each iteration loads
// one sector into a set of `loaded` - 1 others and drops it again; rates are sectors/s (and tet references
// read/s). Synthetic streamed level: probes on a jittered 2 m grid over 160 x 6 x 160 m (10 x 1 x 10 sectors
// of 16 m, about 26 k probes), Delaunay tets, the default cell grid, one occlusion plane on every third tet.
#include <benchmark/benchmark.h>

#include <unistd.h>

#include <cstdio>
#include <filesystem>
#include <memory>
#include <random>
#include <string>
#include <vector>

#include "tetraprobe/runtime/cell_grid.h"
#include "tetraprobe/runtime/gpu_sector_pool.h"
#include "tetraprobe/runtime/level.h"
#include "tetraprobe/runtime/occlusion.h"
#include "tetraprobe/runtime/sh_half.h"
#include "tetraprobe/runtime/streaming.h"
#include "tetraprobe/tetra/stream_index.h"
#include "tetraprobe/tetra/tetrahedralize.h"

namespace {

using namespace tetraprobe;

// The streamed level's file, written once per process and removed at exit.
struct StreamedFile {
  std::string path;
  StreamedFile() {
    Level level;
    std::vector<glm::dvec3> world;
    std::mt19937 rng(7);
    std::uniform_real_distribution<double> j(-0.2, 0.2);
    for (int z = 0; z <= 80; ++z)
      for (int y = 0; y <= 3; ++y)
        for (int x = 0; x <= 80; ++x) {
          const glm::dvec3 p(2.0 * x + j(rng), 2.0 * y + j(rng), 2.0 * z + j(rng));
          world.push_back(p);
          level.probes.push_back(glm::vec3(p));
          ShRgb sh;
          sh.c[0] = glm::vec3(1.0f + 0.01f * float(x), 1.0f, 1.0f + 0.01f * float(z));
          level.sh.push_back(quantizeSh(sh));
        }
    level.tets = buildTetRecords(world, tetrahedralizeDelaunay(world), glm::dvec3(0.0));
    for (size_t t = 0; t < level.tets.size(); ++t) {
      if (t % 3 == 0) {
        level.occlusion.tets.push_back(
            makeTetOcclusion(kOcclusionPlanes, 1, uint32_t(level.occlusion.planes.size()), 0xE7u));
        level.occlusion.planes.push_back(makeOcclusionPlane(0.6, 0.8, 0.0, -double(t % 7)));
      } else {
        level.occlusion.tets.push_back(TetOcclusion{});
      }
    }
    level.cellGrid = buildCellGrid(level.probes, level.tets, 16.0f, 0);
    level.stream = buildStreamIndex(level);
    level.cellGrid = CellGrid{};
    path = (std::filesystem::temp_directory_path() /
            ("tetraprobe_bench_stream_" + std::to_string(::getpid()) + ".tpb"))
               .string();
    if (const LevelResult r = saveLevel(path, level); !r) {
      std::fprintf(stderr, "bench_stream: %s\n", r.message.c_str());
      path.clear();
    }
  }
  ~StreamedFile() {
    if (!path.empty()) std::filesystem::remove(path);
  }
};

const std::string& streamedPath() {
  static const StreamedFile file;
  return file.path;
}

// `loaded` - 1 sectors resident (the first ones in key order), then the next one loaded and dropped each
// iteration.
void BM_GpuSectorPoolLoad(benchmark::State& state) {
  const auto loaded = size_t(state.range(0));
  StreamingLevel st;
  std::vector<GpuSectorSizes> sizes;
  GpuSectorPool pool;
  if (streamedPath().empty()) {
    state.SkipWithError("no streamed level");
    return;
  }
  if (const LevelResult r = st.open(streamedPath()); !r) {
    state.SkipWithError(r.message.c_str());
    return;
  }
  std::string error;
  if (!measureSectors(st, sizes, &error) || st.sectors().size() <= loaded ||
      !(error = pool.init(st, gpuPoolCapacityFor(sizes, uint32_t(loaded)))).empty()) {
    state.SkipWithError(("pool: " + error).c_str());
    return;
  }
  for (size_t i = 0; i + 1 < loaded; ++i) (void)pool.load(st.sectors()[i]);
  const SectorKey key = st.sectors()[loaded - 1];
  for (auto _ : state) {
    if (!pool.load(key)) state.SkipWithError("load failed");
    pool.evict(key);
    benchmark::DoNotOptimize(pool.takeDirtyRanges());
  }
  state.SetItemsProcessed(int64_t(state.iterations()));
  state.counters["tet_refs/s"] = benchmark::Counter(
      double(sizes[loaded - 1].tets) * double(state.iterations()), benchmark::Counter::kIsRate);
}

void BM_StreamingLevelLoad(benchmark::State& state) {
  const auto loaded = size_t(state.range(0));
  StreamingLevel st;
  if (streamedPath().empty() || !st.open(streamedPath()) || st.sectors().size() <= loaded) {
    state.SkipWithError("no streamed level");
    return;
  }
  for (size_t i = 0; i + 1 < loaded; ++i) (void)st.load(st.sectors()[i]);
  const SectorKey key = st.sectors()[loaded - 1];
  for (auto _ : state) {
    if (!st.load(key)) state.SkipWithError("load failed");
    st.unload(key);
  }
  state.SetItemsProcessed(int64_t(state.iterations()));
}

}  // namespace

BENCHMARK(BM_GpuSectorPoolLoad)->Arg(1)->Arg(8)->Arg(32)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_StreamingLevelLoad)->Arg(1)->Arg(8)->Arg(32)->Unit(benchmark::kMillisecond);
BENCHMARK_MAIN();
