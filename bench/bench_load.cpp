// What loading a level costs now that the file stores what the load can derive: tets without neighbours
// (TETM, probe indices packed against the last ones named), no outer cells, BSP nodes as a varint stream of
// the tet faces of their planes (CGR4) and packed occlusion (OCC2). Measured: the whole loadLevelFromMemory (parse, derive neighbours, recompute planes,
// validate), the neighbour derivation alone, the outer cells ProbeQuery builds, and peers in the same run:
// loading the same level written the session-12 way (TETS tets with neighbours, CGR2 float planes, OCCL
// fixed records) and copying the file's bytes (the floor of any load). Rates are probes/s on a synthetic
// level (n^3 probes on a jittered 1 m grid, Delaunay tets, the default cell grid, one occlusion plane on
// every third tet).
#include <benchmark/benchmark.h>

#include <unistd.h>
#include <cstring>
#include <filesystem>
#include <map>
#include <memory>
#include <random>
#include <string>
#include <vector>

#include "tetraprobe/runtime/crc32.h"
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
  std::vector<char> oldFile;  // the same level as written in session 12 (TETS, CGR2, OCCL)
};

uint64_t getU(const std::vector<char>& b, size_t at, int n) {
  uint64_t v = 0;
  for (int i = 0; i < n; ++i) v |= uint64_t(uint8_t(b[at + size_t(i)])) << (8 * i);
  return v;
}
void putU(std::vector<char>& b, size_t at, uint64_t v, int n) {
  for (int i = 0; i < n; ++i) b[at + size_t(i)] = char(uint8_t(v >> (8 * i)));
}

template <class T>
void append(std::string& out, const T& v) {
  out.append(reinterpret_cast<const char*>(&v), sizeof(v));  // little-endian, as the format stores it
}

// The sections of the session-12 format (docs/level_format.md) for `level`: TETS, CGR2 and OCCL payloads.
std::map<std::string, std::pair<std::string, std::string>> oldSections(const Level& level) {
  std::string tets(reinterpret_cast<const char*>(level.tets.data()), level.tets.size() * sizeof(Tet));
  std::string grid;
  const CellGrid& g = level.cellGrid;
  for (int a = 0; a < 3; ++a) append(grid, g.min[a]);
  append(grid, g.cellSize);
  append(grid, g.maxProbe);
  append(grid, g.maxDepth);
  append(grid, g.meanDepth);
  for (uint64_t v :
       {uint64_t(g.leaves), uint64_t(g.unprovenLeaves), uint64_t(g.slots.size()), uint64_t(g.nodes.size())})
    append(grid, v);
  for (const CellSlot& slot : g.slots) grid.append(reinterpret_cast<const char*>(&slot), sizeof(slot));
  for (const BspNode& node : g.nodes) grid.append(reinterpret_cast<const char*>(&node), sizeof(node));
  std::string occ;
  const LevelOcclusion& o = level.occlusion;
  for (uint64_t v : {uint64_t(o.tets.size()), uint64_t(o.planes.size()),
                     uint64_t(o.shadowMaps.size() / kShadowMapBlockBytes)})
    append(occ, v);
  occ.append(reinterpret_cast<const char*>(o.tets.data()), o.tets.size() * sizeof(TetOcclusion));
  occ.append(reinterpret_cast<const char*>(o.planes.data()), o.planes.size() * sizeof(OcclusionPlane));
  return {{"TETM", {"TETS", tets}}, {"CGR4", {"CGR2", grid}}, {"OCC2", {"OCCL", occ}}};
}

// `file` with its TETM, CGR4 and OCC2 sections replaced by the session-12 ones, checksums fixed.
std::vector<char> withOldSections(const std::vector<char>& file, const Level& level) {
  const auto replaced = oldSections(level);
  const size_t n = size_t(getU(file, 72, 4)), tableEnd = 80 + 24 * n + 4;
  std::vector<char> b(file.begin(), file.begin() + std::ptrdiff_t(tableEnd));
  int64_t shift = 0;
  for (size_t i = 0; i < n; ++i) {
    const size_t e = 80 + 24 * i;
    const uint64_t offset = getU(file, e + 8, 8), size = getU(file, e + 16, 8);
    putU(b, e + 8, uint64_t(int64_t(offset) + shift), 8);
    if (const auto it = replaced.find(std::string(file.data() + e, 4)); it != replaced.end()) {
      const auto& [tag, bytes] = it->second;
      std::memcpy(b.data() + e, tag.data(), 4);
      putU(b, e + 4, tag == "TETS" ? 1 : 0, 4);  // flags: of the old three only TETS is required
      putU(b, e + 16, bytes.size(), 8);
      b.insert(b.end(), bytes.begin(), bytes.end());
      shift += int64_t(bytes.size()) - int64_t(size);
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
  f->level.cellGrid = buildCellGrid(f->level.probes, f->level.tets);
  LevelOcclusion& occ = f->level.occlusion;
  for (size_t t = 0; t < f->level.tets.size(); ++t) {
    if (t % 3 != 0) {
      occ.tets.push_back({});
      continue;
    }
    occ.tets.push_back(makeTetOcclusion(kOcclusionPlanes, 1, uint32_t(occ.planes.size()), 0x1Fu));
    occ.planes.push_back(makeOcclusionPlane(1.0, -0.5, 0.25, -1.0));
  }
  const std::string path = (std::filesystem::temp_directory_path() /
                            ("tetraprobe_bench_load_" + std::to_string(::getpid()) + ".tpb"))
                               .string();
  std::string error;
  if (!saveLevel(path, f->level) || !readFile(path, f->file, &error)) std::abort();
  std::filesystem::remove(path);
  f->oldFile = withOldSections(f->file, f->level);
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
