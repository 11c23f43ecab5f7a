// Build-side throughput: adaptive voxel placement (probes/s) and tetrahedralization (probes/s, tets/s) at
// 100k and 1M probes, CGAL and TetGen side by side, with a bare CGAL Delaunay_triangulation_3 insert of the
// same points as the peer (the project's validation, extraction and Morton ordering must cost <= 30 % on
// top of it). Shows rates only; leaves out push-out (needs the Embree tracer) and sliver fillers.
#include <benchmark/benchmark.h>

#include <cmath>
#include <map>
#include <random>
#include <vector>

#include <CGAL/Delaunay_triangulation_3.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Triangulation_vertex_base_with_info_3.h>

#include "tetraprobe/scene/scene.h"
#include "tetraprobe/tetra/placement.h"
#include "tetraprobe/tetra/tetrahedralize.h"

namespace {

using namespace tetraprobe;

// A jittered lattice of about n points (cube root rounded), 1 m apart, +-0.25 m jitter: what voxel
// placement gives after push-out, without its exact cospherical ties.
const std::vector<glm::dvec3>& points(int n) {
  static std::map<int, std::vector<glm::dvec3>> cache;
  auto& pts = cache[n];
  if (!pts.empty()) return pts;
  const int side = int(std::lround(std::cbrt(double(n))));
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> j(-0.25, 0.25);
  for (int z = 0; z < side; ++z)
    for (int y = 0; y < side; ++y)
      for (int x = 0; x < side; ++x) pts.emplace_back(x + j(rng), y + j(rng), z + j(rng));
  return pts;
}

// Rolling terrain, 200 m x 200 m in 2 m quads (20k triangles), with a row of 10 m boxes on it.
const Scene& terrain() {
  static Scene s;
  if (!s.triangles.empty()) return s;
  const int n = 100;
  for (int z = 0; z <= n; ++z)
    for (int x = 0; x <= n; ++x) {
      const float fx = 2.0f * float(x), fz = 2.0f * float(z);
      s.positions.emplace_back(fx, 3.0f * std::sin(fx * 0.05f) * std::cos(fz * 0.07f), fz);
    }
  for (int z = 0; z < n; ++z)
    for (int x = 0; x < n; ++x) {
      const uint32_t a = uint32_t(z * (n + 1) + x), b = a + 1, c = a + uint32_t(n + 1), d = c + 1;
      s.triangles.push_back({a, c, b});
      s.triangles.push_back({b, c, d});
    }
  s.triangleMaterial.assign(s.triangles.size(), 0);
  s.materials.push_back({});
  return s;
}

void BM_PlaceVoxel(benchmark::State& state) {
  // Surface probes ~ 2 x area / spacing^2 (one layer each side): 100k at 0.9 m, 1M at 0.28 m.
  const double spacing = state.range(0) == 100'000 ? 0.9 : 0.28;
  VoxelPlacementOptions opt;
  opt.spacing = spacing;
  opt.maxSpacing = 10.0;
  opt.threads = 1;
  size_t probes = 0;
  for (auto _ : state) {
    const PlacedProbes p = placeVoxelProbes(terrain(), opt);
    probes = p.size();
    benchmark::DoNotOptimize(p.positions.data());
  }
  state.counters["probes"] = double(probes);
  state.counters["spacing_m"] = spacing;
  state.SetItemsProcessed(int64_t(state.iterations()) * int64_t(probes));
}

void BM_TetrahedralizeCgal(benchmark::State& state) {
  const auto& pts = points(int(state.range(0)));
  size_t tets = 0;
  for (auto _ : state) {
    const TetMesh m = tetrahedralizeDelaunay(pts);
    tets = m.tets.size();
    benchmark::DoNotOptimize(m.tets.data());
  }
  state.counters["tets_per_s"] =
      benchmark::Counter(double(tets) * double(state.iterations()), benchmark::Counter::kIsRate);
  state.SetItemsProcessed(int64_t(state.iterations()) * int64_t(pts.size()));
}

void BM_TetrahedralizeTetGen(benchmark::State& state) {
  const auto& pts = points(int(state.range(0)));
  size_t tets = 0;
  for (auto _ : state) {
    const TetGenResult r = tetrahedralizeTetGen(pts);
    tets = r.mesh.tets.size();
    benchmark::DoNotOptimize(r.mesh.tets.data());
  }
  state.counters["tets_per_s"] =
      benchmark::Counter(double(tets) * double(state.iterations()), benchmark::Counter::kIsRate);
  state.SetItemsProcessed(int64_t(state.iterations()) * int64_t(pts.size()));
}

// The peer: CGAL's own spatially sorted insert of (point, index) pairs, nothing else.
void BM_BareCgalDelaunay(benchmark::State& state) {
  using K = CGAL::Exact_predicates_inexact_constructions_kernel;
  using Vb = CGAL::Triangulation_vertex_base_with_info_3<int32_t, K>;
  using Tds = CGAL::Triangulation_data_structure_3<Vb>;
  using Dt = CGAL::Delaunay_triangulation_3<K, Tds>;
  const auto& pts = points(int(state.range(0)));
  size_t tets = 0;
  for (auto _ : state) {
    std::vector<std::pair<K::Point_3, int32_t>> in;
    in.reserve(pts.size());
    for (size_t i = 0; i < pts.size(); ++i)
      in.emplace_back(K::Point_3(pts[i].x, pts[i].y, pts[i].z), int32_t(i));
    Dt dt(in.begin(), in.end());
    tets = dt.number_of_finite_cells();
    benchmark::DoNotOptimize(tets);
  }
  state.counters["tets_per_s"] =
      benchmark::Counter(double(tets) * double(state.iterations()), benchmark::Counter::kIsRate);
  state.SetItemsProcessed(int64_t(state.iterations()) * int64_t(pts.size()));
}

BENCHMARK(BM_PlaceVoxel)->Arg(100'000)->Arg(1'000'000)->Unit(benchmark::kMillisecond)->Iterations(1);
BENCHMARK(BM_BareCgalDelaunay)->Arg(100'000)->Arg(1'000'000)->Unit(benchmark::kMillisecond)->Iterations(1);
BENCHMARK(BM_TetrahedralizeCgal)->Arg(100'000)->Arg(1'000'000)->Unit(benchmark::kMillisecond)->Iterations(1);
BENCHMARK(BM_TetrahedralizeTetGen)
    ->Arg(100'000)
    ->Arg(1'000'000)
    ->Unit(benchmark::kMillisecond)
    ->Iterations(1);

}  // namespace

BENCHMARK_MAIN();
