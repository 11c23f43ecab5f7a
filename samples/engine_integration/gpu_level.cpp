// gpu_level: what an engine owns for a level on the GPU, and how it fills and relights it with its own queue
// and command buffers (runtime/vulkan_upload.h).
// - Load: cmdUploadLevelBuffers records six vkCmdCopyBuffer from one staging buffer into six device-local
//   storage buffers, into the frame's command buffer; the staging buffer is freed once that frame's fence
//   has signalled.
// - Relight: setProbeSh on the CPU level, then cmdUpdateLevelSh recorded into the next frame's command
//   buffer (in place, nothing rebuilt; the barriers order it against the frames' shader reads).
// - Shade: the engine's lighting pass (surface_lighting.h) runs tetraprobe.glsl per pixel over the sphere's
//   surface points, before and after the relight, bound with levelDescriptorBindings and
//   writeLevelDescriptors and specialized with the level's variant (shaderVariantFor).
// Left out: frames in flight (one command buffer, waited for each frame).
// Checks its own results: each pass's pixels against ProbeQuery::irradiance of the level as it then is
// (1e-4 relative per channel, the GPU-vs-CPU tolerance of tests/render/test_gpu_lookup.cpp), and the probe
// buffer, copied back after the relight, against packLevelBuffers of the relit level byte for byte.
#include "gpu_level.h"

#include "engine.h"
#include "surface_lighting.h"

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdio>
#include <cstring>
#include <string>
#include <vector>

#include <tetraprobe/runtime/probe_update.h>
#include <tetraprobe/runtime/shader_variant.h>
#include <tetraprobe/runtime/vulkan_upload.h>

using namespace tetraprobe;

namespace {

// The largest relative difference per channel between the pass's pixels and the CPU's answers (denominator
// at least 1e-6 W/m^2), and how many pixels reach 1e-4.
struct PassCheck {
  double worst = 0.0;
  size_t over = 0;
};

PassCheck checkPass(const SurfaceLighting& lighting, uint32_t output, const ProbeQuery& query,
                    const std::vector<glm::dvec3>& points, const std::vector<glm::vec3>& normals) {
  PassCheck out;
  for (size_t i = 0; i < points.size(); ++i) {
    const glm::vec3 cpu = query.irradiance(points[i], normals[i]);
    const glm::vec4 gpu = lighting.results(output)[i];
    double rel = 0.0;
    for (int c = 0; c < 3; ++c)
      rel = std::max(rel, std::abs(double(gpu[c]) - cpu[c]) / std::max(std::abs(double(cpu[c])), 1e-6));
    if (!(rel < 1e-4)) ++out.over;  // NaN counts
    out.worst = std::max(out.worst, rel);
  }
  return out;
}

}  // namespace

bool runGpuLevel(Level& level, const ProbeQuery& query, const std::vector<glm::dvec3>& points,
                 const std::vector<glm::vec3>& normals) {
  Engine e;
  if (!e.start()) {
    std::printf("GPU: no Vulkan device, skipped\n");
    return true;
  }
  const VkPipelineStageFlags readers =
      VK_PIPELINE_STAGE_FRAGMENT_SHADER_BIT | VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT;

  // Load: the upload is recorded into the frame's command buffer; staging is freed after its fence.
  VulkanLevelBuffers buffers;
  VulkanStagingBuffer staging;
  std::string error;
  const bool uploaded = e.frame([&](VkCommandBuffer cmd) {
    return cmdUploadLevelBuffers(e.physical, e.device, cmd, level, query.startGrid(), query.outerCells(),
                                 query.cellGrid(), readers, buffers, staging, &error) == VK_SUCCESS;
  });
  destroyStagingBuffer(e.device, staging);
  if (!uploaded) {
    std::fprintf(stderr, "engine_integration: GPU upload failed: %s\n", error.c_str());
    destroyLevelBuffers(e.device, buffers);
    return false;
  }
  static const char* const kNames[kGpuBindingCount] = {"tets",        "probes",    "start grid",
                                                       "outer cells", "cell grid", "occlusion"};
  std::printf("GPU (%s): the engine owns %d storage buffers for this level:\n", e.name.c_str(),
              int(kGpuBindingCount));
  VkDeviceSize total = 0;
  for (int i = 0; i < int(kGpuBindingCount); ++i) {
    std::printf(
        "  binding %d  %-11s %10llu bytes  %s\n", i, kNames[i],
        static_cast<unsigned long long>(buffers.sizes[i]),
        buffers.memoryFlags[i] & VK_MEMORY_PROPERTY_DEVICE_LOCAL_BIT ? "device-local" : "host-visible");
    total += buffers.sizes[i];
  }
  std::printf(
      "  total %llu bytes, all filled by a staged copy of %llu bytes (staging freed after the fence)\n",
      static_cast<unsigned long long>(total), static_cast<unsigned long long>(buffers.stagedBytes));

  // Shade: the sphere's surface points as the engine's G-buffer (local frame: world - origin, in double).
  std::vector<SurfacePoint> pixels(points.size());
  for (size_t i = 0; i < points.size(); ++i) pixels[i] = {glm::vec3(points[i] - level.origin), normals[i]};
  SurfaceLighting lighting;
  const int pass =
      lighting.init(e, uint32_t(pixels.size()), 2, &error)
          ? lighting.addLevel(shaderVariantFor(level, query.outerCells(), query.cellGrid()), buffers, &error)
          : -1;
  if (pass < 0) {
    std::fprintf(stderr, "engine_integration: %s\n", error.c_str());
    destroyLevelBuffers(e.device, buffers);
    return false;
  }
  lighting.setPoints(pixels);
  bool ok = e.frame([&](VkCommandBuffer cmd) {
    lighting.cmdShade(cmd, pass, 0);
    return true;
  });
  const PassCheck before = checkPass(lighting, 0, query, points, normals);
  std::printf(
      "GPU: lighting pass (tetraprobe.glsl) over %zu surface points: largest difference from the CPU's "
      "%.1e relative, %zu at 1e-4 or more\n",
      points.size(), before.worst, before.over);
  ok = ok && before.over == 0;

  // Relight: the first half of the probes twice as bright, recorded into the next frame, and shaded after.
  const size_t count = level.probes.size() / 2;
  std::vector<ShRgb> brighter(level.sh.begin(), level.sh.begin() + ptrdiff_t(count));
  for (ShRgb& sh : brighter)
    for (glm::vec3& c : sh.c) c *= 2.0f;
  if (auto r = setProbeSh(level, 0, brighter); !r) {
    std::fprintf(stderr, "engine_integration: setProbeSh: %s\n", r.message.c_str());
    ok = false;
  }
  ok = ok && e.frame([&](VkCommandBuffer cmd) {
    if (!cmdUpdateLevelSh(cmd, buffers, level, 0, count, readers, &error)) return false;
    lighting.cmdShade(cmd, pass, 1);
    return true;
  });
  if (!ok) std::fprintf(stderr, "engine_integration: relight failed: %s\n", error.c_str());
  const PassCheck after = checkPass(lighting, 1, query, points, normals);
  size_t brighterPixels = 0;
  for (size_t i = 0; i < points.size(); ++i)
    brighterPixels += lighting.results(1)[i].x > lighting.results(0)[i].x;
  std::printf(
      "GPU: after the relight, in the same frame: %zu of %zu pixels brighter; largest difference from the "
      "relit level's CPU answers %.1e relative, %zu at 1e-4 or more\n",
      brighterPixels, points.size(), after.worst, after.over);
  ok = ok && after.over == 0;

  // Check: the GPU's probe buffer is the packing of the relit level.
  PackedLevelBuffers packed;
  std::vector<char> gpu;
  ok = ok &&
       packLevelBuffers(level, query.startGrid(), query.outerCells(), query.cellGrid(), packed, &error) &&
       readBuffer(e, buffers.buffers[kGpuBindingProbes], buffers.sizes[kGpuBindingProbes], gpu);
  const std::vector<char>& want = packed.bytes[kGpuBindingProbes];
  const bool same = ok && gpu.size() == want.size() && std::memcmp(gpu.data(), want.data(), want.size()) == 0;
  std::printf("GPU: relit %zu probes in place; probe buffer equals the relit level: %s\n", count,
              same ? "yes" : "NO");
  destroyLevelBuffers(e.device, buffers);
  return same;
}
