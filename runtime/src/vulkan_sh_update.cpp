// Run-time SH updates of an uploaded level's probe buffer (vulkan_upload.h): a recorded vkCmdUpdateBuffer
// for frames in flight, and a staged vkCmdCopyBuffer submitted and waited for, for large relights. Both
// write Level::sh as packLevelBuffers laid it out (gpu_layout.h): positions first, then one ShHalf (56
// bytes) a probe, between the same two barriers, and neither maps the (device-local) probe buffer.
#include "tetraprobe/runtime/vulkan_upload.h"

#include "tetraprobe/runtime/sh_half.h"
#include "vulkan_staging.h"

#include <algorithm>
#include <cstring>
#include <string>
#include <vector>

namespace tetraprobe {
namespace {

constexpr VkDeviceSize kShBytes = sizeof(ShHalf);

// The half-precision records of probes [first, first + count); false (error set) for SH it cannot hold.
bool encodeRange(const Level& level, size_t first, size_t count, std::vector<ShHalf>& out,
                 std::string* error) {
  out.resize(count);
  for (size_t i = 0; i < count; ++i)
    if (!encodeShHalf(level.sh[first + i], &out[i])) {
      if (error)
        *error = "probe " + std::to_string(first + i) +
                 " has an SH coefficient that is not finite or beyond half precision's range (|c| > 2.1e9)";
      return false;
    }
  return true;
}
constexpr VkDeviceSize kUpdateChunk = 65536;  // vkCmdUpdateBuffer's limit on dataSize

// Checks the range against the level and the level against the buffer; sets `offset` to the first byte.
bool checkRange(const VulkanLevelBuffers& buffers, const Level& level, size_t first, size_t count,
                VkDeviceSize* offset, std::string* error) {
  const size_t probes = level.probes.size();
  if (level.sh.size() != probes || first > probes || count > probes - first) {
    if (error)
      *error = "SH update of probes [" + std::to_string(first) + ", " + std::to_string(first) + " + " +
               std::to_string(count) + ") outside the level's " + std::to_string(level.sh.size()) + " SH";
    return false;
  }
  const VkDeviceSize needed = VkDeviceSize(probes) * (kGpuPositionFloatsPerProbe * sizeof(float) + kShBytes);
  if (buffers.buffers[kGpuBindingProbes] == VK_NULL_HANDLE || buffers.sizes[kGpuBindingProbes] < needed) {
    if (error)
      *error = "probe buffer of " + std::to_string(buffers.sizes[kGpuBindingProbes]) + " bytes cannot hold " +
               std::to_string(probes) + " probes (upload this level first)";
    return false;
  }
  *offset =
      VkDeviceSize(probes) * kGpuPositionFloatsPerProbe * sizeof(float) + VkDeviceSize(first) * kShBytes;
  return true;
}

// Records barrier, write(cmd), barrier: earlier reads by `shaderStages` finish before the transfer writes
// [offset, offset + bytes) of `buffer` (an execution dependency suffices for write-after-read), and the
// writes are visible to later accesses `dstAccess` by `shaderStages`.
template <typename Write>
void recordBetweenBarriers(VkCommandBuffer cmd, VkBuffer buffer, VkDeviceSize offset, VkDeviceSize bytes,
                           VkPipelineStageFlags shaderStages, VkAccessFlags dstAccess, const Write& write) {
  vkCmdPipelineBarrier(cmd, shaderStages, VK_PIPELINE_STAGE_TRANSFER_BIT, 0, 0, nullptr, 0, nullptr, 0,
                       nullptr);
  write(cmd);
  VkBufferMemoryBarrier barrier{VK_STRUCTURE_TYPE_BUFFER_MEMORY_BARRIER};
  barrier.srcAccessMask = VK_ACCESS_TRANSFER_WRITE_BIT;
  barrier.dstAccessMask = dstAccess;
  barrier.srcQueueFamilyIndex = VK_QUEUE_FAMILY_IGNORED;
  barrier.dstQueueFamilyIndex = VK_QUEUE_FAMILY_IGNORED;
  barrier.buffer = buffer;
  barrier.offset = offset;
  barrier.size = bytes;
  vkCmdPipelineBarrier(cmd, VK_PIPELINE_STAGE_TRANSFER_BIT, shaderStages, 0, 0, nullptr, 1, &barrier, 0,
                       nullptr);
}

}  // namespace

bool cmdUpdateLevelSh(VkCommandBuffer cmd, const VulkanLevelBuffers& buffers, const Level& level,
                      size_t first, size_t count, VkPipelineStageFlags shaderStages, std::string* error) {
  VkDeviceSize offset = 0;
  if (!checkRange(buffers, level, first, count, &offset, error)) return false;
  if (count == 0) return true;
  std::vector<ShHalf> records;
  if (!encodeRange(level, first, count, records, error)) return false;
  const VkBuffer buffer = buffers.buffers[kGpuBindingProbes];
  const VkDeviceSize bytes = VkDeviceSize(count) * kShBytes;
  // Whole probes per chunk (56 bytes each, a multiple of 4 as vkCmdUpdateBuffer requires; the data is copied
  // into the command buffer at record time, so `records` may go).
  const VkDeviceSize chunk = kUpdateChunk / kShBytes * kShBytes;
  const auto* src = reinterpret_cast<const char*>(records.data());
  recordBetweenBarriers(
      cmd, buffer, offset, bytes, shaderStages, VK_ACCESS_SHADER_READ_BIT, [&](VkCommandBuffer c) {
        for (VkDeviceSize done = 0; done < bytes; done += chunk)
          vkCmdUpdateBuffer(c, buffer, offset + done, std::min(chunk, bytes - done), src + done);
      });
  return true;
}

VkResult writeLevelSh(VkPhysicalDevice physicalDevice, VkDevice device, VkQueue queue, VkCommandPool pool,
                      const VulkanLevelBuffers& buffers, const Level& level, size_t first, size_t count,
                      std::string* error) {
  VkDeviceSize offset = 0;
  if (!checkRange(buffers, level, first, count, &offset, error)) return VK_ERROR_INITIALIZATION_FAILED;
  if (count == 0) return VK_SUCCESS;
  std::vector<ShHalf> records;
  if (!encodeRange(level, first, count, records, error)) return VK_ERROR_INITIALIZATION_FAILED;
  const VkDeviceSize bytes = VkDeviceSize(count) * kShBytes;
  VulkanStagingBuffer staging;
  std::string what;
  VkResult r = vulkan_detail::createStagingBuffer(
      physicalDevice, device, bytes,
      [&](char* mapped) { std::memcpy(mapped, records.data(), size_t(bytes)); }, staging, &what);
  if (r == VK_SUCCESS) {
    const VkBuffer buffer = buffers.buffers[kGpuBindingProbes];
    r = vulkan_detail::submitAndWait(
        device, queue, pool,
        [&](VkCommandBuffer cmd) {
          // Any later access on the queue: lookups, further SH writes, a read-back copy.
          recordBetweenBarriers(cmd, buffer, offset, bytes, VK_PIPELINE_STAGE_ALL_COMMANDS_BIT,
                                VK_ACCESS_MEMORY_READ_BIT | VK_ACCESS_MEMORY_WRITE_BIT,
                                [&](VkCommandBuffer c) {
                                  const VkBufferCopy region{0, offset, bytes};
                                  vkCmdCopyBuffer(c, staging.buffer, buffer, 1, &region);
                                });
        },
        &what);
  }
  destroyStagingBuffer(device, staging);
  if (r != VK_SUCCESS && error) *error = "SH write: " + what + " (VkResult " + std::to_string(r) + ")";
  return r;
}

}  // namespace tetraprobe
