// What loading a level costs now that the file stores tets without neighbours and no outer cells: the whole
// loadLevelFromMemory (parse, derive neighbours, validate), the neighbour derivation alone, the outer cells
// ProbeQuery builds, and peers in the same run: loading the same level written the old way (tets with their
// neighbours, TETS) and copying the file's bytes (the floor of any load). Rates are
// probes/s on a synthetic level (n^3 probes on a jittered 1 m grid, Delaunay tets, no cell grid).
#include <benchmark/benchmark.h>

#include <unistd.h>
#include <cstring>
#include <filesystem>
#include <map>
#include <memory>
#include <random>
#include <string>
#include <vector>

#include "tetraprobe/runtime/file_io.h"
#include "tetraprobe/runtime/level.h"
#include "tetraprobe/runtime/outer_cells.h"
#include "tetraprobe/runtime/sh_half.h"
#include "tetraprobe/runtime/tet_adjacency.h"
#include "tetraprobe/tetra/tetrahedralize.h"

namespace {

using namespace tetraprobe;

struct Fixture {
  Level level;
  std::vector<char> file;     // the level as saveLevel writes it (TETC: tets without neighbours)
  std::vector<char> oldFile;  // the same level as written before TETC (TETS: 32-byte tets with neighbours)
};

uint64_t getU(const std::vector<char>& b, size_t at, int n) {
  uint64_t v = 0;
  for (int i = 0; i < n; ++i) v |= uint64_t(uint8_t(b[at + size_t(i)])) << (8 * i);
  return v;
}
void putU(std::vector<char>& b, size_t at, uint64_t v, int n) {
  for (int i = 0; i < n; ++i) b[at + size_t(i)] = char(uint8_t(v >> (8 * i)));
}
uint32_t crc32(const char* p, size_t n) {  // the format's CRC-32 (zlib)
  uint32_t c = 0xFFFFFFFFu;
  for (size_t i = 0; i < n; ++i) {
    c ^= uint8_t(p[i]);
    for (int k = 0; k < 8; ++k) c = (c & 1u) ? 0xEDB88320u ^ (c >> 1) : c >> 1;
  }
  return c ^ 0xFFFFFFFFu;
}

// `file` with its TETC section replaced by TETS records of `tets` (docs/level_format.md), checksums fixed.
std::vector<char> withOldTets(const std::vector<char>& file, const std::vector<Tet>& tets) {
  const size_t n = size_t(getU(file, 72, 4)), tableEnd = 80 + 24 * n + 4;
  std::vector<char> b(file.begin(), file.begin() + std::ptrdiff_t(tableEnd));
  int64_t shift = 0;
  for (size_t i = 0; i < n; ++i) {
    const size_t e = 80 + 24 * i;
    const uint64_t offset = getU(file, e + 8, 8), size = getU(file, e + 16, 8);
    putU(b, e + 8, uint64_t(int64_t(offset) + shift), 8);
    if (std::memcmp(file.data() + e, "TETC", 4) == 0) {
      std::memcpy(b.data() + e, "TETS", 4);
      putU(b, e + 16, tets.size() * sizeof(Tet), 8);
      const char* p = reinterpret_cast<const char*>(tets.data());  // v[4], n[4] little-endian i32
      b.insert(b.end(), p, p + tets.size() * sizeof(Tet));
      shift += int64_t(tets.size() * sizeof(Tet)) - int64_t(size);
    } else {
      b.insert(b.end(), file.begin() + std::ptrdiff_t(offset), file.begin() + std::ptrdiff_t(offset + size));
    }
  }
  putU(b, tableEnd - 4, crc32(b.data() + 80, tableEnd - 84), 4);
  b.resize(b.size() + 4);
  putU(b, b.size() - 4, crc32(b.data() + 80, b.size() - 84), 4);
  return b;
}

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
  for (const auto& p : pts) {
    f->level.probes.push_back(glm::vec3(p));
    ShRgb sh;
    sh.c[0] = glm::vec3(float(1.0 + 0.1 * p.x), float(1.0 + 0.05 * p.y), 1.0f);
    f->level.sh.push_back(quantizeSh(sh));
  }
  f->level.tets = buildTetRecords(pts, tetrahedralizeDelaunay(pts), glm::dvec3(0.0));
  const std::string path = (std::filesystem::temp_directory_path() /
                            ("tetraprobe_bench_load_" + std::to_string(::getpid()) + ".tpb"))
                               .string();
  std::string error;
  if (!saveLevel(path, f->level) || !readFile(path, f->file, &error)) std::abort();
  std::filesystem::remove(path);
  f->oldFile = withOldTets(f->file, f->level.tets);
  return *f;
}

void BM_LoadLevelFromMemory(benchmark::State& state) {
  const Fixture& f = fixture(int(state.range(0)));
  for (auto _ : state) {
    Level out;
    if (!loadLevelFromMemory(f.file.data(), f.file.size(), "bench", out)) std::abort();
    benchmark::DoNotOptimize(out.tets.data());
  }
  state.SetItemsProcessed(state.iterations() * int64_t(f.level.probes.size()));
  state.counters["tets_per_probe"] = double(f.level.tets.size()) / double(f.level.probes.size());
}

void BM_LoadOldLevelWithNeighbours(benchmark::State& state) {  // the peer: neighbours read, not derived
  const Fixture& f = fixture(int(state.range(0)));
  for (auto _ : state) {
    Level out;
    if (!loadLevelFromMemory(f.oldFile.data(), f.oldFile.size(), "bench", out)) std::abort();
    benchmark::DoNotOptimize(out.tets.data());
  }
  state.SetItemsProcessed(state.iterations() * int64_t(f.level.probes.size()));
}

void BM_LinkTetNeighbours(benchmark::State& state) {
  const Fixture& f = fixture(int(state.range(0)));
  std::vector<Tet> tets = f.level.tets;
  for (auto _ : state) {
    if (!linkTetNeighbours(tets, f.level.probes.size()).empty()) std::abort();
    benchmark::DoNotOptimize(tets.data());
  }
  state.SetItemsProcessed(state.iterations() * int64_t(f.level.probes.size()));
}

void BM_BuildOuterCells(benchmark::State& state) {
  const Fixture& f = fixture(int(state.range(0)));
  for (auto _ : state) benchmark::DoNotOptimize(buildOuterCells(f.level.probes, f.level.tets).data());
  state.SetItemsProcessed(state.iterations() * int64_t(f.level.probes.size()));
}

void BM_CopyFileBytes(benchmark::State& state) {  // the peer: what moving the file's bytes costs
  const Fixture& f = fixture(int(state.range(0)));
  std::vector<char> copy(f.file.size());
  for (auto _ : state) {
    std::memcpy(copy.data(), f.file.data(), f.file.size());
    benchmark::DoNotOptimize(copy.data());
  }
  state.SetItemsProcessed(state.iterations() * int64_t(f.level.probes.size()));
}

BENCHMARK(BM_LoadLevelFromMemory)->Arg(16)->Arg(48)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_LoadOldLevelWithNeighbours)->Arg(16)->Arg(48)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_LinkTetNeighbours)->Arg(16)->Arg(48)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_BuildOuterCells)->Arg(16)->Arg(48)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_CopyFileBytes)->Arg(16)->Arg(48)->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
