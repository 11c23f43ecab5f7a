// gpu_level: what an engine owns for a level on the GPU, and how it fills and relights it with its own queue
// and command buffers (runtime/vulkan_upload.h).
// - Load: cmdUploadLevelBuffers records six vkCmdCopyBuffer from one staging buffer into six device-local
//   storage buffers, into the frame's command buffer; the staging buffer is freed once that frame's fence
//   has signalled.
// - Relight: setProbeSh on the CPU level, then cmdUpdateLevelSh recorded into the next frame's command
//   buffer (in place, nothing rebuilt; the barriers order it against the frames' shader reads).
// Left out: the shader that reads the buffers (tetraprobe.glsl; levelDescriptorBindings and
// writeLevelDescriptors bind them) and frames in flight (one command buffer, waited for each frame).
// Checks its own result: the probe buffer, copied back after the relight, equals packLevelBuffers of the
// relit level byte for byte.
#include "gpu_level.h"

#include "engine.h"

#include <cstddef>
#include <cstdio>
#include <cstring>
#include <string>
#include <vector>

#include <tetraprobe/runtime/probe_update.h>
#include <tetraprobe/runtime/vulkan_upload.h>

using namespace tetraprobe;

bool runGpuLevel(Level& level, const ProbeQuery& query) {
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

  // Relight: the first half of the probes twice as bright, recorded into the next frame.
  const size_t count = level.probes.size() / 2;
  std::vector<ShRgb> brighter(level.sh.begin(), level.sh.begin() + ptrdiff_t(count));
  for (ShRgb& sh : brighter)
    for (glm::vec3& c : sh.c) c *= 2.0f;
  bool ok = true;
  if (auto r = setProbeSh(level, 0, brighter); !r) {
    std::fprintf(stderr, "engine_integration: setProbeSh: %s\n", r.message.c_str());
    ok = false;
  }
  ok = ok && e.frame([&](VkCommandBuffer cmd) {
    return cmdUpdateLevelSh(cmd, buffers, level, 0, count, readers, &error);
  });
  if (!ok) std::fprintf(stderr, "engine_integration: relight failed: %s\n", error.c_str());

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
