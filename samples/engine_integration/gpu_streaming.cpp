// gpu_streaming: a camera flies a loop over a streamed level (`tetraprobe stream`) while the GPU holds only
// the sectors nearest it, in a pool of fixed size (runtime/gpu_sector_pool.h) within a memory budget, and the
// engine's lighting pass shades what the camera sees from that pool.
// - Start: measureSectors reads every sector once for its size; the window (how many sectors are resident)
//   is the largest count of sectors any of which the pool holds at once within the budget (a share of the full
//   level's GPU bytes, packLevelBuffers); neighbouring sectors share tets, so more usually fit;
//   the pool's six buffers are uploaded once (cmdUploadPackedLevelBuffers), the coarse set in them.
// - Each frame: the sectors whose cell centres lie nearest the camera are loaded nearest first while they fit
//   (at least the window; up to twice it), the others evicted; a load reads the sector from the file and
//   writes it into free slots, and only the bytes those writes changed are copied to the GPU
//   (cmdWriteLevelBufferRanges, one staged copy recorded into the frame's command buffer). Then, in the same
//   command buffer, the engine's lighting pass (surface_lighting.h: its own compute shader including
//   tetraprobe.glsl, specialized with the pool's variant()) shades the frame's pixels from the pool: the
//   pool answers as the full level wherever a loaded sector holds the point, from the coarse set elsewhere.
// - The sample draws no meshes: its G-buffer is the floor (a plane 1 m above the level's lowest probe) seen
//   from the camera, 96 x 54 pixels looking along the flight, pitched down 30 degrees.
// Prints a line per frame (sectors loaded and evicted, GPU bytes held against the budget, bytes uploaded,
// the time the loads took, pixels shaded from loaded sectors) and checks: every pixel the pool answers from
// loaded sectors (GpuSectorPool::answersFromLoaded) is the same bytes as the same pass over the whole level
// uploaded beside it (a reference only: an engine would not hold it; it is not counted in the budget), and
// the others are finite; the GPU's buffers, read back at the end, equal the pool's bytes; the pool never
// exceeds the budget; and the flight loads and evicts at least 20 sectors each when the level has more
// sectors than the window.
#include "gpu_streaming.h"

#include "engine.h"
#include "surface_lighting.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <map>
#include <numbers>
#include <string>
#include <vector>

#include <glm/common.hpp>
#include <glm/geometric.hpp>

#include <tetraprobe/runtime/gpu_sector_pool.h>
#include <tetraprobe/runtime/query.h>
#include <tetraprobe/runtime/shader_variant.h>
#include <tetraprobe/runtime/streaming.h>
#include <tetraprobe/runtime/vulkan_upload.h>

using namespace tetraprobe;

namespace {

// The `count` sectors whose cell centres lie nearest the camera (local frame), nearest first, ties by key.
std::vector<SectorKey> nearestSectors(const StreamingLevel& st, const glm::dvec3& local, size_t count) {
  const CellGrid& g = st.sectorGrid();
  std::vector<std::pair<double, SectorKey>> byDistance;
  for (const SectorKey& k : st.sectors()) {
    const glm::dvec3 centre = glm::dvec3(g.min) + (glm::dvec3(k.x, k.y, k.z) + 0.5) * double(g.cellSize);
    const glm::dvec3 d = centre - local;
    byDistance.emplace_back(glm::dot(d, d), k);
  }
  std::sort(byDistance.begin(), byDistance.end());
  std::vector<SectorKey> out;
  for (size_t i = 0; i < byDistance.size() && i < count; ++i) out.push_back(byDistance[i].second);
  return out;
}

constexpr int kViewWidth = 96, kViewHeight = 54;
constexpr double kPitch = -30.0 * std::numbers::pi / 180.0;  // the view looks down by 30 degrees

glm::dvec3 viewDirection(const glm::dvec3& forward) {
  return std::cos(kPitch) * forward + std::sin(kPitch) * glm::dvec3(0.0, 1.0, 0.0);
}

// The frame's G-buffer: the plane y = floorY seen from `camera` (local frame) looking along `forward`
// (horizontal, unit) pitched down 30 degrees, 60 degrees of vertical field of view; a pixel whose ray meets the
// plane farther than `far` (or not at all) is sky. Normals point up.
std::vector<SurfacePoint> floorView(const glm::dvec3& camera, const glm::dvec3& forward, double floorY,
                                    double far) {
  const double halfFov = 30.0 * std::numbers::pi / 180.0;
  const glm::dvec3 up(0.0, 1.0, 0.0), right = glm::normalize(glm::cross(forward, up));
  const glm::dvec3 view = viewDirection(forward);
  const glm::dvec3 viewUp = glm::cross(right, view);
  const double aspect = double(kViewWidth) / double(kViewHeight), t = std::tan(halfFov);
  std::vector<SurfacePoint> out;
  for (int y = 0; y < kViewHeight; ++y)
    for (int x = 0; x < kViewWidth; ++x) {
      const double u = (2.0 * (x + 0.5) / kViewWidth - 1.0) * t * aspect;
      const double v = (1.0 - 2.0 * (y + 0.5) / kViewHeight) * t;
      const glm::dvec3 d = glm::normalize(view + u * right + v * viewUp);
      const double s = d.y < 0.0 ? (floorY - camera.y) / d.y : -1.0;
      SurfacePoint p;
      p.normal = glm::vec3(0.0f, 1.0f, 0.0f);
      p.sky = s <= 0.0 || s > far;
      p.local = glm::vec3(p.sky ? camera : camera + s * d);
      out.push_back(p);
    }
  return out;
}

// Where the view looks: the point of the floor its centre ray meets, at most `far` / 2 ahead. The sectors
// nearest it are the ones the frame needs.
glm::dvec3 viewFocus(const glm::dvec3& camera, const glm::dvec3& forward, double floorY, double far) {
  const glm::dvec3 view = viewDirection(forward);
  const double s = (floorY - camera.y) / view.y;
  return camera + std::clamp(s, 0.0, 0.5 * far) * view;
}

}  // namespace

bool runGpuStreaming(const std::string& path, double budgetShare, int frames) {
  StreamingLevel st;
  if (LevelResult r = st.open(path); !r) {
    std::fprintf(stderr, "engine_integration: %s\n", r.message.c_str());
    return false;
  }
  // The budget's base: what the whole level takes on the GPU (a tool computes this once, offline). The same
  // packing is uploaded as the lighting check's reference (below).
  Level full;
  if (LevelResult r = loadLevel(path, full); !r) {
    std::fprintf(stderr, "engine_integration: %s\n", r.message.c_str());
    return false;
  }
  const ProbeQuery fullQuery(full);
  PackedLevelBuffers fullPacked;
  size_t fullBytes = 0;
  {
    std::string error;
    if (!packLevelBuffers(full, fullQuery.startGrid(), fullQuery.outerCells(), fullQuery.cellGrid(),
                          fullPacked, &error)) {
      std::fprintf(stderr, "engine_integration: %s\n", error.c_str());
      return false;
    }
    for (const std::vector<char>& b : fullPacked.bytes) fullBytes += b.size();
  }
  const auto budget = size_t(budgetShare * double(fullBytes));
  std::vector<GpuSectorSizes> sizes;
  std::string error;
  if (!measureSectors(st, sizes, &error)) {
    std::fprintf(stderr, "engine_integration: %s\n", error.c_str());
    return false;
  }
  // Slots for any `n` sectors at once, and bricks (8.7 KB each) for twice as many: neighbours share tets.
  const auto capacityFor = [&](uint32_t n) {
    GpuPoolCapacity c = gpuPoolCapacityFor(sizes, n);
    c.sectors = uint32_t(std::min<size_t>(2 * size_t(n), sizes.size()));
    return c;
  };
  uint32_t window = 0;
  for (uint32_t n = 1; n <= uint32_t(sizes.size()); ++n)
    if (gpuPoolBytes(st, capacityFor(n)) <= budget) window = n;
  if (window == 0) {
    std::fprintf(stderr, "engine_integration: not even one sector fits in %zu bytes\n", budget);
    return false;
  }
  const GpuPoolCapacity cap = capacityFor(window);
  std::printf(
      "streaming: %zu sectors of %g m; full level %zu GPU bytes, budget %.0f %% = %zu bytes: a window of "
      "%u sectors (pool %zu bytes)\n",
      st.sectors().size(), double(st.sectorGrid().cellSize), fullBytes, 100.0 * budgetShare, budget, window,
      gpuPoolBytes(st, cap));

  Engine e;
  if (!e.start()) {
    std::printf("streaming: no Vulkan device, skipped\n");
    return true;
  }
  const VkPipelineStageFlags readers =
      VK_PIPELINE_STAGE_FRAGMENT_SHADER_BIT | VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT;
  GpuSectorPool pool;
  if (std::string err = pool.init(st, cap); !err.empty()) {
    std::fprintf(stderr, "engine_integration: %s\n", err.c_str());
    return false;
  }
  VulkanLevelBuffers buffers;
  VulkanStagingBuffer staging;
  bool ok = e.frame([&](VkCommandBuffer cmd) {
    return cmdUploadPackedLevelBuffers(e.physical, e.device, cmd, pool.buffers(), readers, buffers, staging,
                                       &error) == VK_SUCCESS;
  });
  destroyStagingBuffer(e.device, staging);
  pool.takeDirtyRanges();  // the upload copied every byte
  if (!ok) {
    std::fprintf(stderr, "engine_integration: pool upload failed: %s\n", error.c_str());
    destroyLevelBuffers(e.device, buffers);
    return false;
  }
  // The reference: the whole level uploaded as an engine without streaming would, shaded by the same pass.
  VulkanLevelBuffers fullBuffers;
  ok = e.frame([&](VkCommandBuffer cmd) {
    return cmdUploadPackedLevelBuffers(e.physical, e.device, cmd, fullPacked, readers, fullBuffers, staging,
                                       &error) == VK_SUCCESS;
  });
  destroyStagingBuffer(e.device, staging);
  SurfaceLighting lighting;
  const int poolPass = ok && lighting.init(e, kViewWidth * kViewHeight, 2, &error)
                           ? lighting.addLevel(pool.variant(), buffers, &error)
                           : -1;
  const int fullPass =
      poolPass < 0 ? -1
                   : lighting.addLevel(shaderVariantFor(full, fullQuery.outerCells(), fullQuery.cellGrid()),
                                       fullBuffers, &error);
  if (fullPass < 0) {
    std::fprintf(stderr, "engine_integration: %s\n", error.c_str());
    destroyLevelBuffers(e.device, fullBuffers);
    destroyLevelBuffers(e.device, buffers);
    return false;
  }
  float floorY = full.probes.empty() ? 0.0f : full.probes[0].y;
  for (const glm::vec3& p : full.probes) floorY = std::min(floorY, p.y);
  floorY += 1.0f;
  const double far = 2.0 * double(st.sectorGrid().cellSize);  // the view's depth: two sectors

  // A loop over the sectors' extent at mid height: an ellipse through 80 % of it in x and z.
  const CellGrid& g = st.sectorGrid();
  glm::dvec3 lo(1e300), hi(-1e300);
  for (const SectorKey& k : st.sectors()) {
    const glm::dvec3 c = glm::dvec3(g.min) + (glm::dvec3(k.x, k.y, k.z) + 0.5) * double(g.cellSize);
    lo = glm::min(lo, c);
    hi = glm::max(hi, c);
  }
  const glm::dvec3 mid = 0.5 * (lo + hi), radius = 0.4 * (hi - lo) + 0.25 * double(g.cellSize);
  int loads = 0, evictions = 0;
  size_t peakInUse = 0, geometryPixels = 0, loadedPixels = 0, differing = 0, notFinite = 0;
  for (int f = 0; f < frames && ok; ++f) {
    const double a = 2.0 * std::numbers::pi * double(f) / double(frames);
    const glm::dvec3 camera(mid.x + radius.x * std::cos(a), mid.y, mid.z + radius.z * std::sin(a));
    const glm::dvec3 forward =
        glm::normalize(glm::dvec3(-radius.x * std::sin(a), 0.0, radius.z * std::cos(a)));
    // The pool's capacity holds any `window` sectors; neighbouring sectors share tets, so more usually fit.
    // Nearest first, up to twice the window: a load that finds no room evicts the farthest loaded sector
    // behind it, and past the window a load that still finds none ends the frame's loading.
    const std::vector<SectorKey> order =
        nearestSectors(st, viewFocus(camera, forward, floorY, far), 2 * size_t(window));
    std::map<SectorKey, size_t> rank;
    for (size_t i = 0; i < order.size(); ++i) rank[order[i]] = i;
    int in = 0, out = 0;
    const auto t0 = std::chrono::steady_clock::now();
    std::vector<SectorKey> drop;
    for (const auto& [key, tets] : pool.loadedTets())
      if (!rank.count(key)) drop.push_back(key);
    for (const SectorKey& k : drop) pool.evict(k), ++out;
    for (size_t i = 0; i < order.size() && ok; ++i) {
      if (pool.isLoaded(order[i])) continue;
      LevelResult r = pool.load(order[i]);
      while (r.status == LevelStatus::kTooLarge) {
        bool found = false;
        SectorKey farthest;
        for (const auto& [key, tets] : pool.loadedTets())
          if (rank.at(key) > i && (!found || rank.at(key) > rank.at(farthest))) farthest = key, found = true;
        if (!found) break;
        pool.evict(farthest), ++out;
        r = pool.load(order[i]);
      }
      if (r.status == LevelStatus::kTooLarge && i >= window) break;  // the pool is full past the window
      if (!r) {
        std::fprintf(stderr, "engine_integration: %s\n", r.message.c_str());
        ok = false;
        break;
      }
      ++in;
    }
    const double ms =
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
    const std::vector<GpuBufferRange> ranges = pool.takeDirtyRanges();
    uint64_t uploaded = 0;
    for (const GpuBufferRange& r : ranges) uploaded += r.bytes;
    // The frame: the changed bytes copied, then the lighting pass from the pool (and the reference's).
    const std::vector<SurfacePoint> pixels = floorView(camera, forward, floorY, far);
    lighting.setPoints(pixels);
    ok = ok && e.frame([&](VkCommandBuffer cmd) {
      if (cmdWriteLevelBufferRanges(e.physical, e.device, cmd, buffers, pool.buffers(), ranges, readers,
                                    staging, &error) != VK_SUCCESS)
        return false;
      lighting.cmdShade(cmd, poolPass, 0);
      lighting.cmdShade(cmd, fullPass, 1);
      return true;
    });
    destroyStagingBuffer(e.device, staging);
    size_t frameLoaded = 0;
    for (size_t i = 0; i < pixels.size() && ok; ++i) {
      if (pixels[i].sky) continue;
      ++geometryPixels;
      const glm::vec4 fromPool = lighting.results(0)[i], fromFull = lighting.results(1)[i];
      if (!std::isfinite(fromPool.x) || !std::isfinite(fromPool.y) || !std::isfinite(fromPool.z)) ++notFinite;
      if (!pool.answersFromLoaded(st.origin() + glm::dvec3(pixels[i].local))) continue;
      ++frameLoaded;
      if (std::memcmp(&fromPool, &fromFull, sizeof(glm::vec3)) != 0) ++differing;
    }
    loadedPixels += frameLoaded;
    loads += in;
    evictions += out;
    peakInUse = std::max(peakInUse, pool.bytesInUse());
    ok = ok && pool.bytes() <= budget;
    std::printf(
        "frame %3d  camera (%7.1f, %5.1f, %7.1f)  sectors %2zu (+%d -%d)  GPU %zu of %zu bytes (%.1f %% "
        "of the level), in use %zu  uploaded %llu bytes in %zu ranges  loads %.1f ms  pixels from loaded "
        "sectors %zu\n",
        f, camera.x, camera.y, camera.z, pool.loadedSectors(), in, out, pool.bytes(), budget,
        100.0 * double(pool.bytes()) / double(fullBytes), pool.bytesInUse(),
        static_cast<unsigned long long>(uploaded), ranges.size(), ms, frameLoaded);
  }
  if (!ok) std::fprintf(stderr, "engine_integration: streaming failed: %s\n", error.c_str());

  // Check: every GPU buffer equals the pool's bytes after the last frame's ranges.
  bool same = ok;
  for (int i = 0; i < int(kGpuBindingCount) && same; ++i) {
    std::vector<char> gpu;
    same = readBuffer(e, buffers.buffers[i], buffers.sizes[i], gpu) &&
           gpu.size() == pool.buffers().bytes[i].size() &&
           std::memcmp(gpu.data(), pool.buffers().bytes[i].data(), gpu.size()) == 0;
  }
  destroyLevelBuffers(e.device, buffers);
  destroyLevelBuffers(e.device, fullBuffers);
  const bool enough = st.sectors().size() <= window || (loads >= 20 && evictions >= 20);
  std::printf(
      "streaming: %d loads, %d evictions over %d frames; GPU %zu bytes (%.1f %% of the level, budget "
      "%.0f %%), at most %zu in use; GPU buffers equal the pool's bytes: %s\n",
      loads, evictions, frames, pool.bytes(), 100.0 * double(pool.bytes()) / double(fullBytes),
      100.0 * budgetShare, peakInUse, same ? "yes" : "NO");
  std::printf(
      "streaming: lighting pass: %zu of %zu geometry pixels shaded from loaded sectors, %zu of them differ "
      "from the whole level's; %zu pixels not finite\n",
      loadedPixels, geometryPixels, differing, notFinite);
  const bool lit = loadedPixels > 0 && differing == 0 && notFinite == 0;
  if (!enough) std::fprintf(stderr, "engine_integration: fewer than 20 loads and evictions\n");
  if (!lit) std::fprintf(stderr, "engine_integration: the lighting pass from the pool is not the level's\n");
  return ok && same && enough && lit;
}
