// Upload of a regular SH L2 grid into seven 3D textures (grid_texture.h): float or half texels, a staging
// buffer and one copy per texture, then the layout the compute pass samples in.
#include "grid_texture.h"

#include <cstring>
#include <limits>
#include <stdexcept>
#include <vector>

#include <glm/gtc/packing.hpp>

namespace tetraprobe::render_detail {

GridTextures createGridTextures(const VulkanContext& ctx, const RenderGrid& grid, const glm::dvec3& origin,
                                CleanupStack& cleanup) {
  const VkDevice device = ctx.device();
  GridTextures out;
  VkFormatProperties props;
  vkGetPhysicalDeviceFormatProperties(ctx.physicalDevice(), VK_FORMAT_R32G32B32A32_SFLOAT, &props);
  const bool full = (props.optimalTilingFeatures & VK_FORMAT_FEATURE_SAMPLED_IMAGE_FILTER_LINEAR_BIT) != 0;
  out.format = full ? VK_FORMAT_R32G32B32A32_SFLOAT : VK_FORMAT_R16G16B16A16_SFLOAT;
  const size_t texelBytes = full ? 16 : 8;
  const auto dims = glm::uvec3(grid.dims);
  const size_t nodes = size_t(dims.x) * dims.y * dims.z;
  out.bytes = uint64_t(kGridTextureCount) * nodes * texelBytes;

  // Staging: texture j's texels one after another, texture after texture.
  const VkMemoryPropertyFlags hostMem =
      VK_MEMORY_PROPERTY_HOST_VISIBLE_BIT | VK_MEMORY_PROPERTY_HOST_COHERENT_BIT;
  const GpuBuffer staging = ctx.createBuffer(out.bytes, VK_BUFFER_USAGE_TRANSFER_SRC_BIT, hostMem, cleanup);
  {
    void* mapped;
    vkCheck(vkMapMemory(device, staging.memory, 0, VK_WHOLE_SIZE, 0, &mapped), "vkMapMemory (grid staging)");
    auto* bytes = static_cast<char*>(mapped);
    for (size_t n = 0; n < nodes; ++n) {
      float f[4 * kGridTextureCount] = {};
      std::memcpy(f, &grid.sh[n], sizeof(ShRgb));
      for (int j = 0; j < kGridTextureCount; ++j) {
        char* dst = bytes + (size_t(j) * nodes + n) * texelBytes;
        if (full) {
          std::memcpy(dst, f + 4 * j, 16);
        } else {
          uint16_t h[4];
          for (int c = 0; c < 4; ++c) h[c] = glm::packHalf1x16(f[4 * j + c]);
          std::memcpy(dst, h, 8);
        }
      }
    }
    vkUnmapMemory(device, staging.memory);
  }
  for (auto& im : out.images)
    im = ctx.createImage3D(dims.x, dims.y, dims.z, out.format,
                           VK_IMAGE_USAGE_SAMPLED_BIT | VK_IMAGE_USAGE_TRANSFER_DST_BIT, cleanup);

  VkCommandBufferAllocateInfo alloc{VK_STRUCTURE_TYPE_COMMAND_BUFFER_ALLOCATE_INFO};
  alloc.commandPool = ctx.commandPool();
  alloc.level = VK_COMMAND_BUFFER_LEVEL_PRIMARY;
  alloc.commandBufferCount = 1;
  VkCommandBuffer cmd;
  vkCheck(vkAllocateCommandBuffers(device, &alloc, &cmd), "vkAllocateCommandBuffers (grid upload)");
  const VkCommandPool pool = ctx.commandPool();
  cleanup.push([device, pool, cmd] { vkFreeCommandBuffers(device, pool, 1, &cmd); });
  VkCommandBufferBeginInfo begin{VK_STRUCTURE_TYPE_COMMAND_BUFFER_BEGIN_INFO};
  begin.flags = VK_COMMAND_BUFFER_USAGE_ONE_TIME_SUBMIT_BIT;
  vkCheck(vkBeginCommandBuffer(cmd, &begin), "vkBeginCommandBuffer (grid upload)");
  for (int j = 0; j < kGridTextureCount; ++j) {
    VkImageMemoryBarrier b{VK_STRUCTURE_TYPE_IMAGE_MEMORY_BARRIER};
    b.dstAccessMask = VK_ACCESS_TRANSFER_WRITE_BIT;
    b.oldLayout = VK_IMAGE_LAYOUT_UNDEFINED;
    b.newLayout = VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL;
    b.srcQueueFamilyIndex = b.dstQueueFamilyIndex = VK_QUEUE_FAMILY_IGNORED;
    b.image = out.images[j].image;
    b.subresourceRange = {VK_IMAGE_ASPECT_COLOR_BIT, 0, 1, 0, 1};
    vkCmdPipelineBarrier(cmd, VK_PIPELINE_STAGE_TOP_OF_PIPE_BIT, VK_PIPELINE_STAGE_TRANSFER_BIT, 0, 0,
                         nullptr, 0, nullptr, 1, &b);
    VkBufferImageCopy region{};
    region.bufferOffset = VkDeviceSize(j) * nodes * texelBytes;
    region.imageSubresource = {VK_IMAGE_ASPECT_COLOR_BIT, 0, 0, 1};
    region.imageExtent = {dims.x, dims.y, dims.z};
    vkCmdCopyBufferToImage(cmd, staging.buffer, out.images[j].image, VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL, 1,
                           &region);
    b.srcAccessMask = VK_ACCESS_TRANSFER_WRITE_BIT;
    b.dstAccessMask = VK_ACCESS_SHADER_READ_BIT;
    b.oldLayout = VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL;
    b.newLayout = VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL;
    vkCmdPipelineBarrier(cmd, VK_PIPELINE_STAGE_TRANSFER_BIT, VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT, 0, 0,
                         nullptr, 0, nullptr, 1, &b);
  }
  vkCheck(vkEndCommandBuffer(cmd), "vkEndCommandBuffer (grid upload)");
  VkSubmitInfo submit{VK_STRUCTURE_TYPE_SUBMIT_INFO};
  submit.commandBufferCount = 1;
  submit.pCommandBuffers = &cmd;
  vkCheck(vkQueueSubmit(ctx.queue(), 1, &submit, VK_NULL_HANDLE), "vkQueueSubmit (grid upload)");
  vkCheck(vkQueueWaitIdle(ctx.queue()), "vkQueueWaitIdle (grid upload)");

  VkSamplerCreateInfo si{VK_STRUCTURE_TYPE_SAMPLER_CREATE_INFO};
  si.magFilter = si.minFilter = VK_FILTER_LINEAR;
  si.mipmapMode = VK_SAMPLER_MIPMAP_MODE_NEAREST;
  si.addressModeU = si.addressModeV = si.addressModeW = VK_SAMPLER_ADDRESS_MODE_CLAMP_TO_EDGE;
  si.maxLod = 0.0f;
  vkCheck(vkCreateSampler(device, &si, nullptr, &out.sampler), "vkCreateSampler (grid)");
  const VkSampler sampler = out.sampler;
  cleanup.push([device, sampler] { vkDestroySampler(device, sampler, nullptr); });

  struct Header {
    float min[4];
    float step[4];
    int32_t dims[4];
  } header{};
  static_assert(sizeof(Header) == 48, "lighting_grid_texture.comp header: vec4 min, vec4 step, ivec4 dims");
  const glm::vec3 localMin(grid.min - origin);
  for (int a = 0; a < 3; ++a) {
    header.min[a] = localMin[a];
    header.step[a] = float(grid.step);
    header.dims[a] = grid.dims[a];
  }
  out.header = ctx.createBuffer(sizeof header, VK_BUFFER_USAGE_STORAGE_BUFFER_BIT, hostMem, cleanup);
  void* mapped;
  vkCheck(vkMapMemory(device, out.header.memory, 0, VK_WHOLE_SIZE, 0, &mapped), "vkMapMemory (grid header)");
  std::memcpy(mapped, &header, sizeof header);
  vkUnmapMemory(device, out.header.memory);
  return out;
}

}  // namespace tetraprobe::render_detail
