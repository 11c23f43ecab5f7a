// GPU streaming by sector (runtime/gpu_sector_pool.h): a camera flies over a level of many 16 m sectors
// while a pool a fraction of the level's GPU size loads the sectors around it and evicts the rest; each
// frame is rendered from the pool's buffers and from the full level's, and every pixel the streamed level
// answers from loaded sectors (StreamingLevel::answersFromLoaded with the same sectors) must be the same
// bytes. The incremental uploads (takeDirtyRanges) must rebuild the pool's buffers byte for byte.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <random>
#include <set>

#include "lookup_scene.h"
#include "tetraprobe/runtime/cell_grid.h"
#include "tetraprobe/runtime/gpu_sector_pool.h"
#include "tetraprobe/runtime/streaming.h"
#include "tetraprobe/runtime/vulkan_upload.h"
#include "tetraprobe/tetra/stream_index.h"

namespace tetraprobe::test {
namespace {

// A 132 x 6 x 132 m level of jittered probes at 3 m (9 x 1 x 9 sectors), distinct SH, synthetic occlusion,
// streamed; and a mesh of ground and blocks inside it.
struct StreamedScene {
  std::string path;  // the streamed level file, removed with the scene
  Level full;
  RenderMesh mesh;
  StreamedScene() = default;
  StreamedScene(StreamedScene&&) = default;
  ~StreamedScene() {
    if (!path.empty()) std::filesystem::remove(path);
  }
};

StreamedScene makeStreamedScene() {
  StreamedScene s;
  Level& level = s.full;
  level.origin = kOrigin;
  std::vector<glm::dvec3> world;
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> j(-0.3, 0.3);
  for (int z = 0; z <= 44; ++z)
    for (int y = 0; y <= 2; ++y)
      for (int x = 0; x <= 44; ++x) {
        const glm::dvec3 local(3.0 * x + j(rng), 3.0 * y + j(rng), 3.0 * z + j(rng));
        world.push_back(kOrigin + local);
        level.probes.push_back(glm::vec3(local));
        const glm::vec3 p(local);
        ShRgb sh;
        sh.c[0] = glm::vec3(2.0f + 0.03f * p.x, 1.5f + 0.1f * p.y, 1.0f + 0.02f * p.z);
        sh.c[1] = glm::vec3(0.2f * std::sin(p.x), -0.1f, 0.05f);
        sh.c[2] = glm::vec3(-0.15f, 0.1f * std::cos(p.z), 0.2f);
        sh.c[3] = glm::vec3(0.1f, 0.05f, -0.1f * std::sin(p.y + p.x));
        level.sh.push_back(quantizeSh(sh));
      }
  const TetMesh mesh = tetrahedralizeDelaunay(world);
  level.tets = buildTetRecords(world, mesh, kOrigin);
  level.occlusion = syntheticOcclusion(level);
  level.cellGrid = buildCellGrid(level.probes, level.tets, 16.0f, 2);
  StreamIndexOptions options;
  options.coarseSpacing = 12.0;
  Level streamed = level;
  streamed.stream = buildStreamIndex(level, options);
  streamed.cellGrid = CellGrid{};
  s.path =
      (std::filesystem::temp_directory_path() / ("tetraprobe_pool_" + std::to_string(::getpid()) + ".tpb"))
          .string();
  if (!saveLevel(s.path, streamed)) throw std::runtime_error("cannot write " + s.path);
  // Ground at y = 1 and blocks of 2-5 m on it, every 9 m.
  addQuad(s.mesh, {1.0f, 1.0f, 131.0f}, {131.0f, 1.0f, 131.0f}, {131.0f, 1.0f, 1.0f}, {1.0f, 1.0f, 1.0f},
          {0.7f, 0.7f, 0.6f});
  for (int bz = 0; bz < 14; ++bz)
    for (int bx = 0; bx < 14; ++bx) {
      const float x0 = 3.0f + 9.0f * bx, z0 = 3.0f + 9.0f * bz, h = 2.0f + float((bx * 3 + bz * 5) % 4);
      const float x1 = x0 + 3.0f, z1 = z0 + 3.0f, y0 = 1.0f, y1 = 1.0f + h;
      const glm::vec3 c(0.3f + 0.08f * bx, 0.5f, 0.3f + 0.08f * bz);
      addQuad(s.mesh, {x0, y0, z1}, {x1, y0, z1}, {x1, y1, z1}, {x0, y1, z1}, c);  // +z
      addQuad(s.mesh, {x1, y0, z0}, {x0, y0, z0}, {x0, y1, z0}, {x1, y1, z0}, c);  // -z
      addQuad(s.mesh, {x1, y0, z1}, {x1, y0, z0}, {x1, y1, z0}, {x1, y1, z1}, c);  // +x
      addQuad(s.mesh, {x0, y0, z0}, {x0, y0, z1}, {x0, y1, z1}, {x0, y1, z0}, c);  // -x
      addQuad(s.mesh, {x0, y1, z1}, {x1, y1, z1}, {x1, y1, z0}, {x0, y1, z0}, c);  // top
    }
  return s;
}

// The sectors of the 2 x 2 cells nearest a local point (the streaming window), those the file has.
std::set<SectorKey> windowAt(const StreamingLevel& st, const glm::dvec3& world) {
  std::set<SectorKey> out;
  const CellGrid& g = st.sectorGrid();
  const glm::dvec3 local = world - st.origin();
  const glm::dvec3 c = (local - glm::dvec3(g.min)) / double(g.cellSize);
  const int x0 = int(std::floor(c.x - 0.5)), z0 = int(std::floor(c.z - 0.5)), y = int(std::floor(c.y));
  for (int dz = 0; dz < 2; ++dz)
    for (int dx = 0; dx < 2; ++dx)
      for (int dy = -1; dy <= 0; ++dy)
        if (const SectorKey k{x0 + dx, y + dy, z0 + dz}; st.hasSector(k)) out.insert(k);
  return out;
}

TEST(GpuSectorPool, StreamedFlyThroughRendersTheFullLevelsPixelsWhereLoaded) {
  const StreamedScene scene = makeStreamedScene();
  Level full;
  ASSERT_TRUE(loadLevel(scene.path, full));
  const ProbeQuery whole(full);
  StreamingLevel st, cpu;
  ASSERT_TRUE(st.open(scene.path));
  ASSERT_TRUE(cpu.open(scene.path));
  ASSERT_GE(st.sectors().size(), 20u);

  std::vector<GpuSectorSizes> sizes;
  ASSERT_TRUE(measureSectors(st, sizes));
  const GpuPoolCapacity cap = gpuPoolCapacityFor(sizes, 4);
  GpuSectorPool pool;
  ASSERT_EQ(pool.init(st, cap), "");
  PackedLevelBuffers fullBytes;
  ASSERT_TRUE(packLevelBuffers(full, whole.startGrid(), whole.outerCells(), whole.cellGrid(), fullBytes));
  size_t fullSize = 0;
  for (const auto& b : fullBytes.bytes) fullSize += b.size();
  EXPECT_EQ(pool.bytes(), gpuPoolBytes(st, cap));
  EXPECT_LE(pool.bytes(), fullSize / 4) << "the pool stays within a quarter of the level's GPU bytes";

  // The GPU copy as the engine keeps it: the first upload (every byte dirty), then each frame's ranges.
  PackedLevelBuffers gpu;
  for (int b = 0; b < int(kGpuBindingCount); ++b) gpu.bytes[b].assign(pool.buffers().bytes[b].size(), 0);
  auto applyRanges = [&] {
    for (const GpuBufferRange& r : pool.takeDirtyRanges())
      std::memcpy(gpu.bytes[r.binding].data() + r.offset, pool.buffers().bytes[r.binding].data() + r.offset,
                  size_t(r.bytes));
    for (int b = 0; b < int(kGpuBindingCount); ++b)
      ASSERT_EQ(std::memcmp(gpu.bytes[b].data(), pool.buffers().bytes[b].data(), gpu.bytes[b].size()), 0)
          << "binding " << b << ": the dirty ranges left a byte out";
  };
  applyRanges();

  // A loop at 14 m over the level, looking ahead and down, the window following the view's target.
  const int frames = 14;
  int loads = 0, evictions = 0;
  size_t compared = 0, coarsePixels = 0;
  for (int f = 0; f < frames; ++f) {
    const double angle = 2.0 * 3.14159265358979 * double(f) / double(frames);
    const glm::dvec3 eye =
        kOrigin + glm::dvec3(66.0 + 40.0 * std::cos(angle), 14.0, 66.0 + 40.0 * std::sin(angle));
    const glm::dvec3 target = eye + glm::dvec3(-6.0 * std::sin(angle), -12.0, 6.0 * std::cos(angle));
    const std::set<SectorKey> want = windowAt(st, target);
    std::vector<SectorKey> drop;
    for (const auto& [key, tets] : pool.loadedTets())
      if (!want.count(key)) drop.push_back(key);
    for (const SectorKey& k : drop) {
      pool.evict(k);
      cpu.unload(k);
      ++evictions;
    }
    for (const SectorKey& k : want) {
      if (pool.isLoaded(k)) continue;
      const LevelResult r = pool.load(k);
      ASSERT_TRUE(r) << r.message;
      ASSERT_TRUE(cpu.load(k));
      ++loads;
    }
    EXPECT_LE(pool.bytesInUse(), pool.bytes());
    std::printf(
        "[          ] frame %2d: %zu sectors loaded, GPU bytes in use %zu of the pool's %zu (the level: "
        "%zu)\n",
        f, pool.loadedSectors(), pool.bytesInUse(), pool.bytes(), fullSize);
    applyRanges();

    RenderView view = makeView(RenderMode::kIrradiance, 160, 96);
    view.eye = glm::vec3(eye);
    view.target = glm::vec3(target);
    RenderResult a, b;
    std::string skip;
    if (!render(scene.mesh, full, whole, view, a, skip)) TETRAPROBE_SKIP_MISSING(skip);
    RenderOptions options;
    options.levelBuffers = &pool.buffers();
    options.variant = pool.variant();
    ASSERT_TRUE(render(scene.mesh, full, whole, view, b, skip, options)) << skip;
    const size_t pixels = size_t(view.width) * size_t(view.height);
    for (size_t i = 0; i < pixels; ++i) {
      if (a.position.rgba[4 * i + 3] == 0.0f) continue;
      const glm::dvec3 p = full.origin + glm::dvec3(px3(a.position, i));
      const glm::vec3 ea = px3(a.color, i), eb = px3(b.color, i);
      ASSERT_TRUE(std::isfinite(eb.x) && std::isfinite(eb.y) && std::isfinite(eb.z)) << f << " " << i;
      if (cpu.answersFromLoaded(p)) {
        ++compared;
        ASSERT_EQ(std::memcmp(&ea, &eb, sizeof ea), 0)
            << "frame " << f << " pixel " << i << ": " << ea.x << " against the pool's " << eb.x;
      } else {
        ++coarsePixels;
      }
    }
  }
  EXPECT_GE(loads, 20);
  EXPECT_GE(evictions, 20);
  EXPECT_GT(compared, size_t(frames) * 2000) << "most geometry pixels lie in loaded sectors";
  std::printf(
      "[          ] %d loads, %d evictions; %zu pixels compared, %zu from the coarse set; pool %zu "
      "of the level's %zu GPU bytes\n",
      loads, evictions, compared, coarsePixels, pool.bytes(), fullSize);

  // Evicting everything frees every slot: the pool is back to the coarse set.
  std::vector<SectorKey> all;
  for (const auto& [key, tets] : pool.loadedTets()) all.push_back(key);
  for (const SectorKey& k : all) pool.evict(k);
  EXPECT_EQ(pool.residentTets(), 0u);
  EXPECT_EQ(pool.residentProbes(), 0u);
  applyRanges();
}

// A sector that does not fit in the free slots is refused (kTooLarge) and writes nothing; evicting and
// loading again leaks no slot.
TEST(GpuSectorPool, ALoadThatDoesNotFitChangesNothingAndReloadsLeakNoSlot) {
  const StreamedScene scene = makeStreamedScene();
  StreamingLevel st;
  ASSERT_TRUE(st.open(scene.path));
  std::vector<GpuSectorSizes> sizes;
  ASSERT_TRUE(measureSectors(st, sizes));
  GpuSectorPool pool;
  ASSERT_EQ(pool.init(st, gpuPoolCapacityFor(sizes, 2)), "");
  const SectorKey a = st.sectors()[0], b = st.sectors()[1], c = st.sectors()[2];
  ASSERT_TRUE(pool.load(a));
  ASSERT_TRUE(pool.load(b));
  const PackedLevelBuffers two = pool.buffers();
  pool.takeDirtyRanges();
  const LevelResult refused = pool.load(c);
  EXPECT_EQ(refused.status, LevelStatus::kTooLarge) << refused.message;
  EXPECT_FALSE(pool.isLoaded(c));
  EXPECT_TRUE(pool.takeDirtyRanges().empty());
  for (int i = 0; i < int(kGpuBindingCount); ++i) EXPECT_EQ(pool.buffers().bytes[i], two.bytes[i]) << i;
  // Out and back in: no slot leaks (the same sectors take the same number of slots), and the pool is back
  // to the coarse set alone in between.
  const size_t inUse = pool.bytesInUse();
  const uint32_t tets = pool.residentTets(), probes = pool.residentProbes();
  pool.evict(b);
  pool.evict(a);
  EXPECT_EQ(pool.loadedSectors(), 0u);
  EXPECT_EQ(pool.residentTets(), 0u);
  EXPECT_LT(pool.bytesInUse(), inUse);
  ASSERT_TRUE(pool.load(b));
  ASSERT_TRUE(pool.load(a));
  EXPECT_EQ(pool.residentTets(), tets);
  EXPECT_EQ(pool.residentProbes(), probes);
  EXPECT_EQ(pool.bytesInUse(), inUse);
}

}  // namespace
}  // namespace tetraprobe::test
