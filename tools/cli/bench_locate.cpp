// `tetraprobe bench locate`: point location plus SH interpolation and irradiance evaluation, in one run on
// the same queries, by the sparse cell grid + BSP (ProbeQuery::locate), the per-object cached walk, the walk
// from the coarse start grid (ProbeQuery::walkLocate), CGAL's Delaunay_triangulation_3::locate
// (Fast_location, and with the previous query's cell as hint; locate alone) and the brute-force scan on a
// subset. CGAL is GPL: this file belongs to the build-side CLI only.
#include <CGAL/Delaunay_triangulation_3.h>
#include <CGAL/Delaunay_triangulation_cell_base_3.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Triangulation_vertex_base_with_info_3.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <map>
#include <random>
#include <stdexcept>
#include <string>
#include <thread>
#include <utility>
#include <vector>

#include <glm/common.hpp>
#include <glm/geometric.hpp>
#include <nlohmann/json.hpp>

#include "args.h"
#include "commands.h"
#include "tetraprobe/common/error.h"
#include "tetraprobe/runtime/level.h"
#include "tetraprobe/runtime/outer_cells.h"
#include "tetraprobe/runtime/query.h"
#include "tetraprobe/runtime/sh.h"
#include "tetraprobe/tetra/tetrahedralize.h"

namespace tetraprobe::cli {
namespace {

using K = CGAL::Exact_predicates_inexact_constructions_kernel;
using Vb = CGAL::Triangulation_vertex_base_with_info_3<int32_t, K>;
using Cb = CGAL::Delaunay_triangulation_cell_base_3<K>;
using Tds = CGAL::Triangulation_data_structure_3<Vb, Cb>;
using Delaunay = CGAL::Delaunay_triangulation_3<K, Tds>;
using DelaunayFast = CGAL::Delaunay_triangulation_3<K, Tds, CGAL::Fast_location>;

double seconds(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

// Runs fn(begin, end) over [0, count) on `threads` threads in contiguous chunks (each chunk keeps the
// queries' order, so coherent runs stay coherent per thread).
template <typename Fn>
void runChunks(size_t count, int threads, Fn fn) {
  std::vector<std::thread> pool;
  const size_t n = size_t(std::max(1, threads)), chunk = (count + n - 1) / n;
  for (size_t k = 1; k < n; ++k)
    pool.emplace_back(fn, std::min(count, k * chunk), std::min(count, (k + 1) * chunk));
  fn(size_t(0), std::min(count, chunk));
  for (std::thread& t : pool) t.join();
}

glm::vec3 irradianceOf(const Level& level, const Location& loc, const glm::vec3& normal) {
  if (loc.tet < 0) return glm::vec3(0.0f);
  const Tet& t = level.tets[size_t(loc.tet)];
  const ShRgb* probes[4];
  float w[4];
  for (int i = 0; i < 4; ++i) {
    probes[i] = &level.sh[size_t(t.v[i])];
    w[i] = loc.weights[i];
  }
  return shIrradiance(shBlend(probes, w, 4), normal);
}

bool sameIrradiance(const glm::vec3& a, const glm::vec3& b) {
  for (int c = 0; c < 3; ++c)
    if (std::abs(a[c] - b[c]) > 1e-4f * (std::abs(b[c]) + 1e-3f)) return false;
  return true;
}

// A synthetic level of n probes at about one per cubic metre, random SH, outer cells: uniformly random
// positions (the worst case for the BSP: long thin Delaunay tets), or a 1 m lattice (what voxel placement
// makes: cospherical everywhere), filled x fastest.
Level syntheticLevel(size_t n, uint64_t seed, bool lattice) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::uniform_real_distribution<float> sh(-0.2f, 0.2f);
  const double side = std::cbrt(double(n));
  const auto cells = size_t(std::ceil(side));
  Level level;
  level.origin = glm::dvec3(1000.0, 0.0, -2000.0);
  std::vector<glm::dvec3> world(n);
  for (size_t i = 0; i < n; ++i)
    world[i] = level.origin + (lattice ? glm::dvec3(double(i % cells), double((i / cells) % cells),
                                                    double(i / (cells * cells)))
                                       : side * glm::dvec3(u(rng), u(rng), u(rng)));
  for (const glm::dvec3& p : world) {
    level.probes.push_back(glm::vec3(p - level.origin));
    ShRgb s;
    for (auto& c : s.c) c = glm::vec3(sh(rng), sh(rng), sh(rng));
    s.c[0] += glm::vec3(1.0f);
    level.sh.push_back(s);
  }
  level.tets = buildTetRecords(world, tetrahedralizeDelaunay(world), level.origin);
  level.outerCells = buildOuterCells(level.probes, level.tets);
  level.generator = "tetraprobe bench locate --synthetic";
  return level;
}

}  // namespace

int benchLocate(int argc, char** argv) {
  Args args(
      "tetraprobe bench locate [LEVEL.tpb] [--synthetic N [--layout random|lattice]] [--queries N] [--order "
      "random|coherent] "
      "[--threads T] [--json]",
      "Locates the same query points (and interpolates their SH irradiance) with every method in one run:\n"
      "grid_bsp (sparse cell grid + BSP, ProbeQuery::irradianceBatch), grid_bsp_single (the same, one\n"
      "irradiance() call a query; mismatches: answers not bit-identical to the batch's), walk_cached "
      "(per-query hint: the previous\n"
      "query's tet, Unity style), walk (from the coarse start grid), cgal_fast_location and cgal_hint\n"
      "(CGAL Delaunay_triangulation_3::locate on the level's probes, locate alone, one thread), brute\n"
      "(full scan, on a subset). mismatches: answers whose irradiance differs from grid_bsp's by > 1e-4\n"
      "relative (CGAL: a different cell where grid_bsp's point is clearly inside its tet;\n"
      "mismatches_not_a_cgal_cell: those where the level's tet is no cell of CGAL's triangulation of the\n"
      "float-rounded probes). Occlusion is off: every method locates, blends and evaluates, nothing more.\n"
      "Queries: random = uniform in the probe bounds; coherent = a 2-D raster (pixel order) over a slanted\n"
      "plane through the bounds.",
      {{"--synthetic", "", "N", "bench on N random probes (one per m^3) instead of LEVEL", "0"},
       {"--layout", "", "random|lattice", "--synthetic: probe positions (lattice: 1 m, as voxel placement)",
        "random"},
       {"--queries", "", "N", "query points", "1000000"},
       {"--order", "", "random|coherent", "query order", "random"},
       {"--threads", "", "N", "threads for the runtime methods, 0 = all cores", "0"},
       {"--brute", "", "N", "queries checked by the brute-force scan", "200"},
       {"--cell-size", "", "M", "cell grid cell size, metres", "16"},
       {"--leaf-tets", "", "N",
        "rebuild the cell grid stopping at N tets a leaf (1: the leaf tet is the answer; 0: the level's own "
        "grid, else the default " +
            std::to_string(kDefaultLeafTets) + ")",
        "0"},
       {"--seed", "", "N", "random seed", "1"},
       {"--no-cgal", "", "", "skip the CGAL methods (and their builds): quicker runs while tuning", ""},
       {"--save", "", "PATH", "write the level (with its cell grid) to PATH, to bench it again faster", ""},
       {"--json", "", "", "print the figures as one JSON object", ""}});
  if (!args.parse(argc, argv)) return 0;
  args.requirePositional(0, 1);
  const int synthetic = args.integer("--synthetic");
  const int queryCount = args.integer("--queries");
  const std::string order = args.str("--order");
  int threads = args.integer("--threads");
  const int bruteCount = args.integer("--brute");
  const auto cellSize = float(args.number("--cell-size"));
  const auto seed = args.u64("--seed");
  if (queryCount < 1) throw UsageError("--queries must be at least 1");
  if (order != "random" && order != "coherent") throw UsageError("--order must be random or coherent");
  if (threads < 0) throw UsageError("--threads must be >= 0");
  if (!(cellSize > 0.0f)) throw UsageError("--cell-size must be positive");
  const int leafTets = args.integer("--leaf-tets");
  if (leafTets < 0) throw UsageError("--leaf-tets must be >= 0");
  if (threads == 0) threads = int(std::max(1u, std::thread::hardware_concurrency()));
  if ((synthetic > 0) == !args.positional().empty())
    throw UsageError("give either LEVEL.tpb or --synthetic N (N >= 4)");

  Level level;
  std::string source;
  auto t0 = std::chrono::steady_clock::now();
  if (synthetic > 0) {
    const std::string layout = args.str("--layout");
    if (layout != "random" && layout != "lattice") throw UsageError("--layout must be random or lattice");
    level = syntheticLevel(size_t(synthetic), seed, layout == "lattice");
    source = "synthetic:" + std::to_string(synthetic) + (layout == "lattice" ? ":lattice" : "");
  } else {
    source = args.positional()[0];
    if (LevelResult r = loadLevel(source, level); !r) throw InputError(r.message);
  }
  const double levelSeconds = seconds(t0);
  if (level.tets.empty()) throw InputError(source + ": the level has no tets");

  t0 = std::chrono::steady_clock::now();
  if (leafTets > 0) level.cellGrid = buildCellGrid(level.probes, level.tets, cellSize, threads, leafTets);
  ProbeQuery query(level, cellSize, threads);
  const double querySeconds = seconds(t0);
  // Every method does the same work (locate, blend, evaluate): the level's occlusion, which only grid_bsp's
  // irradiance() would apply, is off.
  query.setUseOcclusion(false);
  if (const std::string save = args.str("--save"); !save.empty()) {
    Level copy = level;
    copy.cellGrid = query.cellGrid();
    copy.outerCells = query.outerCells();
    if (LevelResult r = saveLevel(save, copy); !r) throw std::runtime_error(r.message);
  }

  // Query points (world) and normals.
  glm::dvec3 lo(1e300), hi(-1e300);
  for (const glm::vec3& p : level.probes) {
    lo = glm::min(lo, glm::dvec3(p));
    hi = glm::max(hi, glm::dvec3(p));
  }
  const size_t n = size_t(queryCount);
  std::vector<glm::dvec3> world(n);
  std::vector<glm::vec3> normal(n);
  std::mt19937_64 rng(seed + 17);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::normal_distribution<float> g(0.0f, 1.0f);
  if (order == "random") {
    for (glm::dvec3& x : world) x = level.origin + lo + (hi - lo) * glm::dvec3(u(rng), u(rng), u(rng));
  } else {
    const auto w = size_t(std::ceil(std::sqrt(double(n))));
    for (size_t i = 0; i < n; ++i) {
      const double s = (double(i % w) + 0.5) / double(w), t = (double(i / w) + 0.5) / double(w);
      const glm::dvec3 local(lo.x + (hi.x - lo.x) * s, lo.y + (hi.y - lo.y) * (0.2 + 0.6 * t),
                             lo.z + (hi.z - lo.z) * (0.9 - 0.8 * t + 0.05 * std::sin(20.0 * s)));
      world[i] = level.origin + local;
    }
  }
  for (glm::vec3& v : normal)
    v = glm::normalize(glm::vec3(g(rng), g(rng), g(rng)) + glm::vec3(0.0f, 1e-3f, 0.0f));

  struct Method {
    std::string name;
    double rate = 0.0;
    size_t mismatches = 0, queries = 0;
    int threads = 1;
    // CGAL only: mismatches where the level's tet is not a cell of CGAL's triangulation at all (CGAL
    // triangulates the float-rounded local positions, the level the double world positions they came from;
    // near-cospherical probes can be joined differently).
    size_t otherTriangulation = 0;
    bool cgal() const { return name.rfind("cgal", 0) == 0; }
  };
  std::vector<Method> methods;

  // grid_bsp: the batch call (interleaved, prefetching; the previous item's tet first), the reference the
  // others are compared with; grid_bsp_single: the same answers, one irradiance() call a query.
  std::vector<glm::vec3> reference(n);
  std::vector<Location> refLoc(n);
  // Both best of three runs: the first touches the level's pages (and a shared machine is noisy).
  double best = 0.0;
  for (int run = 0; run < 3; ++run) {
    t0 = std::chrono::steady_clock::now();
    query.irradianceBatch(world.data(), normal.data(), reference.data(), n, threads);
    best = std::max(best, double(n) / seconds(t0));
  }
  methods.push_back({"grid_bsp", best, 0, n, threads});
  {
    std::vector<glm::vec3> out(n);
    best = 0.0;
    for (int run = 0; run < 3; ++run) {
      t0 = std::chrono::steady_clock::now();
      runChunks(n, threads, [&](size_t b, size_t e) {
        for (size_t i = b; i < e; ++i) out[i] = query.irradiance(world[i], normal[i]);
      });
      best = std::max(best, double(n) / seconds(t0));
    }
    Method m{"grid_bsp_single", best, 0, n, threads};
    for (size_t i = 0; i < n; ++i) m.mismatches += out[i] != reference[i];  // must be bit-identical
    methods.push_back(m);
  }
  for (size_t i = 0; i < n; ++i) refLoc[i] = query.locate(world[i]);

  // walk_cached: each thread's previous tet as hint (an object moving through the level).
  {
    std::vector<glm::vec3> out(n);
    t0 = std::chrono::steady_clock::now();
    runChunks(n, threads, [&](size_t b, size_t e) {
      int32_t cache = -1;
      for (size_t i = b; i < e; ++i) out[i] = query.irradiance(world[i], normal[i], &cache);
    });
    Method m{"walk_cached", double(n) / seconds(t0), 0, n, threads};
    for (size_t i = 0; i < n; ++i) m.mismatches += !sameIrradiance(out[i], reference[i]);
    methods.push_back(m);
  }
  // walk: from the coarse start grid.
  {
    std::vector<glm::vec3> out(n);
    t0 = std::chrono::steady_clock::now();
    runChunks(n, threads, [&](size_t b, size_t e) {
      for (size_t i = b; i < e; ++i) out[i] = irradianceOf(level, query.walkLocate(world[i]), normal[i]);
    });
    Method m{"walk", double(n) / seconds(t0), 0, n, threads};
    for (size_t i = 0; i < n; ++i) m.mismatches += !sameIrradiance(out[i], reference[i]);
    methods.push_back(m);
  }
  // CGAL, on the level's probes (local frame), vertex info = probe index.
  double cgalBuildSeconds = 0.0;
  if (!args.has("--no-cgal")) {
    std::vector<std::pair<K::Point_3, int32_t>> points;
    points.reserve(level.probes.size());
    for (size_t p = 0; p < level.probes.size(); ++p)
      points.emplace_back(K::Point_3(level.probes[p].x, level.probes[p].y, level.probes[p].z), int32_t(p));
    std::vector<K::Point_3> q(n);
    for (size_t i = 0; i < n; ++i) {
      const glm::dvec3 x = world[i] - level.origin;
      q[i] = K::Point_3(x.x, x.y, x.z);
    }
    // Mismatches, and how many of them are of a level tet that is not a CGAL cell.
    const auto countMismatches =
        [&](const auto& dt, const std::vector<typename std::decay_t<decltype(dt)>::Cell_handle>& cells) {
          using Dt = std::decay_t<decltype(dt)>;
          std::vector<typename Dt::Vertex_handle> byProbe(level.probes.size());
          for (auto v : dt.finite_vertex_handles()) byProbe[size_t(v->info())] = v;
          std::pair<size_t, size_t> bad{0, 0};
          for (size_t i = 0; i < n; ++i) {
            const Location& r = refLoc[i];
            if (!r.inside || std::min({r.weights[0], r.weights[1], r.weights[2], r.weights[3]}) < 1e-5f)
              continue;
            int32_t a[4], b[4];
            for (int k = 0; k < 4; ++k) {
              a[k] = dt.is_infinite(cells[i]) ? -1 : cells[i]->vertex(k)->info();
              b[k] = level.tets[size_t(r.tet)].v[k];
            }
            std::sort(a, a + 4);
            std::sort(b, b + 4);
            if (std::equal(a, a + 4, b)) continue;
            ++bad.first;
            typename Dt::Cell_handle c;
            const Tet& t = level.tets[size_t(r.tet)];
            bad.second += !dt.is_cell(byProbe[size_t(t.v[0])], byProbe[size_t(t.v[1])],
                                      byProbe[size_t(t.v[2])], byProbe[size_t(t.v[3])], c);
          }
          return bad;
        };
    {
      t0 = std::chrono::steady_clock::now();
      DelaunayFast dt(points.begin(), points.end());
      cgalBuildSeconds += seconds(t0);
      std::vector<DelaunayFast::Cell_handle> cells(n);
      t0 = std::chrono::steady_clock::now();
      for (size_t i = 0; i < n; ++i) cells[i] = dt.locate(q[i]);
      const double rate = double(n) / seconds(t0);
      const auto [bad, other] = countMismatches(dt, cells);
      methods.push_back({"cgal_fast_location", rate, bad, n, 1, other});
    }
    {
      t0 = std::chrono::steady_clock::now();
      Delaunay dt(points.begin(), points.end());
      cgalBuildSeconds += seconds(t0);
      std::vector<Delaunay::Cell_handle> cells(n);
      t0 = std::chrono::steady_clock::now();
      Delaunay::Cell_handle hint;
      for (size_t i = 0; i < n; ++i) hint = cells[i] = dt.locate(q[i], hint);
      const double rate = double(n) / seconds(t0);
      const auto [bad, other] = countMismatches(dt, cells);
      methods.push_back({"cgal_hint", rate, bad, n, 1, other});
    }
  }
  // brute: the full scan on a subset.
  {
    const size_t m = std::min(n, size_t(std::max(0, bruteCount)));
    Method b{"brute", 0.0, 0, m, 1};
    t0 = std::chrono::steady_clock::now();
    for (size_t i = 0; i < m; ++i)
      b.mismatches +=
          !sameIrradiance(irradianceOf(level, query.bruteForceLocate(world[i]), normal[i]), reference[i]);
    b.rate = m > 0 ? double(m) / seconds(t0) : 0.0;
    methods.push_back(b);
  }

  const CellGrid& grid = query.cellGrid();
  const size_t cells = occupiedCells(grid);
  const double gridBytes = double(cellGridBytes(grid));
  // How often the leaf's tet is the answer itself (the walk accepts it without a step), over the queries
  // inside the hull.
  size_t insideQueries = 0, leafIsAnswer = 0;
  for (size_t i = 0; i < n; ++i) {
    if (!refLoc[i].inside) continue;
    ++insideQueries;
    leafIsAnswer += cellGridLeaf(grid, world[i] - level.origin) == refLoc[i].tet;
  }
  const double leafHitRate = insideQueries > 0 ? double(leafIsAnswer) / double(insideQueries) : 0.0;
  const double bytesPerTet = gridBytes / double(level.tets.size());
  double cgalFast = 0.0;
  for (const Method& m : methods)
    if (m.name == "cgal_fast_location") cgalFast = m.rate;
  const double speedup = cgalFast > 0.0 ? methods[0].rate / cgalFast : 0.0;

  if (args.has("--json")) {
    nlohmann::json list = nlohmann::json::array();
    for (const Method& m : methods) {
      list.push_back({{"name", m.name},
                      {"queries_per_s", m.rate},
                      {"mismatches", m.mismatches},
                      {"queries", m.queries},
                      {"threads", m.threads}});
      if (m.cgal()) list.back()["mismatches_not_a_cgal_cell"] = m.otherTriangulation;
    }
    const nlohmann::json j = {{"level", source},
                              {"probes", level.probes.size()},
                              {"tets", level.tets.size()},
                              {"outer_cells", query.outerCells().size()},
                              {"queries", n},
                              {"order", order},
                              {"threads", threads},
                              {"methods", list},
                              {"bsp",
                               {{"max_depth", grid.maxDepth},
                                {"mean_depth", grid.meanDepth},
                                {"nodes", grid.nodes.size()},
                                {"cells", cells},
                                {"cell_size_m", grid.cellSize},
                                {"hash_slots", grid.slots.size()},
                                {"hash_max_probe", grid.maxProbe},
                                {"leaves", grid.leaves},
                                {"unproven_leaves", grid.unprovenLeaves},
                                {"node_bytes", sizeof(BspNode)},
                                {"leaf_tet_is_answer", leafHitRate}}},
                              {"bytes_per_tet", bytesPerTet},
                              {"grid_bsp_vs_cgal_fast_location", speedup},
                              {"level_seconds", levelSeconds},
                              {"query_build_seconds", querySeconds},
                              {"cgal_build_seconds", cgalBuildSeconds}};
    std::printf("%s\n", j.dump(2).c_str());
  } else {
    std::printf("tetraprobe bench locate: %s, %zu probes, %zu tets, %zu queries (%s), %d threads\n",
                source.c_str(), level.probes.size(), level.tets.size(), n, order.c_str(), threads);
    for (const Method& m : methods)
      std::printf(
          "  %-20s %12.0f queries/s  %zu mismatches of %zu (%d threads)%s\n", m.name.c_str(), m.rate,
          m.mismatches, m.queries, m.threads,
          m.cgal() ? (", " + std::to_string(m.otherTriangulation) + " of them not a CGAL cell").c_str() : "");
    std::printf(
        "  bsp: depth max %d mean %.2f, %zu nodes, %zu leaves (%zu unproven), %zu cells, %.1f bytes/tet, "
        "leaf tet is the answer for %.4f of inside queries; grid_bsp / cgal_fast_location %.1fx\n",
        grid.maxDepth, grid.meanDepth, grid.nodes.size(), grid.leaves, grid.unprovenLeaves, cells,
        bytesPerTet, leafHitRate, speedup);
  }
  return 0;
}

}  // namespace tetraprobe::cli
