// Vulkan upload of a level's tets, SH, start grid, outer cells, start bricks (from the cell grid) and occlusion into the storage
// buffers shaders/tetraprobe_layout.glsl declares: packed on the host (gpu_layout.h), written into one
// host-visible staging buffer and copied by vkCmdCopyBuffer into buffers in device-local memory (one
// allocation per buffer), so the per-pixel reads stay on the GPU's own memory on a discrete GPU.
#include "tetraprobe/runtime/vulkan_upload.h"

#include "tetraprobe/runtime/face_blend.h"
#include "tetraprobe/runtime/gpu_tets.h"
#include "tetraprobe/runtime/oct_normal.h"
#include "tetraprobe/runtime/sh_half.h"
#include "tetraprobe/runtime/start_bricks.h"
#include "vulkan_staging.h"

#include <algorithm>
#include <climits>
#include <cstring>
#include <vector>

namespace tetraprobe {
namespace {

const char* bindingName(int i) {
  static const char* const kNames[kGpuBindingCount] = {"tets",        "probes",    "grid",
                                                       "outer cells", "cell grid", "occlusion"};
  return kNames[i];
}

// The memory types allowed by `typeBits` in the order they are tried: those with every flag of `prefer` in
// the device's order (the specification orders types so that the first match has the fewest extra
// properties), then those with every flag of `fallback`.
std::vector<uint32_t> memoryTypeCandidates(VkPhysicalDevice physicalDevice, uint32_t typeBits,
                                           VkMemoryPropertyFlags prefer, VkMemoryPropertyFlags fallback) {
  VkPhysicalDeviceMemoryProperties props;
  vkGetPhysicalDeviceMemoryProperties(physicalDevice, &props);
  std::vector<uint32_t> out;
  for (VkMemoryPropertyFlags want : {prefer, fallback})
    for (uint32_t i = 0; i < props.memoryTypeCount; ++i)
      if ((typeBits & (1u << i)) && (props.memoryTypes[i].propertyFlags & want) == want &&
          std::find(out.begin(), out.end(), i) == out.end())
        out.push_back(i);
  return out;
}

// Allocates and binds memory for `buffer` from the first candidate type that has room: a full heap
// (VK_ERROR_OUT_OF_DEVICE_MEMORY) moves on to the next type. `flags` gets the chosen type's properties.
VkResult allocateAndBind(VkPhysicalDevice physicalDevice, VkDevice device, VkBuffer buffer,
                         VkMemoryPropertyFlags prefer, VkMemoryPropertyFlags fallback, VkDeviceMemory* memory,
                         VkMemoryPropertyFlags* flags, std::string* what) {
  VkMemoryRequirements req;
  vkGetBufferMemoryRequirements(device, buffer, &req);
  const std::vector<uint32_t> types =
      memoryTypeCandidates(physicalDevice, req.memoryTypeBits, prefer, fallback);
  if (types.empty()) return *what = "no memory type fits", VK_ERROR_FEATURE_NOT_PRESENT;
  VkPhysicalDeviceMemoryProperties props;
  vkGetPhysicalDeviceMemoryProperties(physicalDevice, &props);
  VkResult r = VK_ERROR_OUT_OF_DEVICE_MEMORY;
  for (uint32_t type : types) {
    VkMemoryAllocateInfo alloc{VK_STRUCTURE_TYPE_MEMORY_ALLOCATE_INFO};
    alloc.allocationSize = req.size;
    alloc.memoryTypeIndex = type;
    r = vkAllocateMemory(device, &alloc, nullptr, memory);
    if (r == VK_ERROR_OUT_OF_DEVICE_MEMORY) continue;
    if (r != VK_SUCCESS) break;
    *flags = props.memoryTypes[type].propertyFlags;
    r = vkBindBufferMemory(device, buffer, *memory, 0);
    if (r != VK_SUCCESS) return *what = "vkBindBufferMemory failed", r;
    return VK_SUCCESS;
  }
  *memory = VK_NULL_HANDLE;
  return *what = "vkAllocateMemory failed", r;
}

VkResult createBuffer(VkDevice device, VkDeviceSize size, VkBufferUsageFlags usage, VkBuffer* buffer,
                      std::string* what) {
  VkBufferCreateInfo info{VK_STRUCTURE_TYPE_BUFFER_CREATE_INFO};
  info.size = size;
  info.usage = usage;
  info.sharingMode = VK_SHARING_MODE_EXCLUSIVE;
  const VkResult r = vkCreateBuffer(device, &info, nullptr, buffer);
  if (r != VK_SUCCESS) *what = "vkCreateBuffer failed";
  return r;
}

template <typename T>
void appendBytes(std::vector<char>& out, const T* data, size_t count) {
  const auto* p = reinterpret_cast<const char*>(data);
  out.insert(out.end(), p, p + sizeof(T) * count);
}

}  // namespace

namespace vulkan_detail {

VkResult createStagingBuffer(VkPhysicalDevice physicalDevice, VkDevice device, VkDeviceSize size,
                             const std::function<void(char*)>& fill, VulkanStagingBuffer& out,
                             std::string* what) {
  out = VulkanStagingBuffer{};
  const VkMemoryPropertyFlags host =
      VK_MEMORY_PROPERTY_HOST_VISIBLE_BIT | VK_MEMORY_PROPERTY_HOST_COHERENT_BIT;
  VkResult r = createBuffer(device, size, VK_BUFFER_USAGE_TRANSFER_SRC_BIT, &out.buffer, what);
  VkMemoryPropertyFlags flags = 0;
  if (r == VK_SUCCESS)
    r = allocateAndBind(physicalDevice, device, out.buffer, host, host, &out.memory, &flags, what);
  void* mapped = nullptr;
  if (r == VK_SUCCESS) {
    r = vkMapMemory(device, out.memory, 0, VK_WHOLE_SIZE, 0, &mapped);
    if (r != VK_SUCCESS) *what = "vkMapMemory failed";
  }
  if (r != VK_SUCCESS) {
    destroyStagingBuffer(device, out);
    *what = "staging buffer: " + *what;
    return r;
  }
  fill(static_cast<char*>(mapped));
  vkUnmapMemory(device, out.memory);
  out.size = size;
  return VK_SUCCESS;
}

VkResult submitAndWait(VkDevice device, VkQueue queue, VkCommandPool pool,
                       const std::function<void(VkCommandBuffer)>& record, std::string* what) {
  VkCommandBufferAllocateInfo cai{VK_STRUCTURE_TYPE_COMMAND_BUFFER_ALLOCATE_INFO};
  cai.commandPool = pool;
  cai.level = VK_COMMAND_BUFFER_LEVEL_PRIMARY;
  cai.commandBufferCount = 1;
  VkCommandBuffer cmd = VK_NULL_HANDLE;
  VkResult r = vkAllocateCommandBuffers(device, &cai, &cmd);
  if (r != VK_SUCCESS) return *what = "vkAllocateCommandBuffers failed", r;
  VkFence fence = VK_NULL_HANDLE;
  VkCommandBufferBeginInfo begin{VK_STRUCTURE_TYPE_COMMAND_BUFFER_BEGIN_INFO};
  begin.flags = VK_COMMAND_BUFFER_USAGE_ONE_TIME_SUBMIT_BIT;
  r = vkBeginCommandBuffer(cmd, &begin);
  if (r != VK_SUCCESS) {
    *what = "vkBeginCommandBuffer failed";
  } else {
    record(cmd);
    r = vkEndCommandBuffer(cmd);
    if (r != VK_SUCCESS) *what = "vkEndCommandBuffer failed";
  }
  if (r == VK_SUCCESS) {
    VkFenceCreateInfo fci{VK_STRUCTURE_TYPE_FENCE_CREATE_INFO};
    r = vkCreateFence(device, &fci, nullptr, &fence);
    if (r != VK_SUCCESS) *what = "vkCreateFence failed";
  }
  if (r == VK_SUCCESS) {
    VkSubmitInfo submit{VK_STRUCTURE_TYPE_SUBMIT_INFO};
    submit.commandBufferCount = 1;
    submit.pCommandBuffers = &cmd;
    r = vkQueueSubmit(queue, 1, &submit, fence);
    if (r != VK_SUCCESS) *what = "vkQueueSubmit failed";
  }
  if (r == VK_SUCCESS) {
    r = vkWaitForFences(device, 1, &fence, VK_TRUE, UINT64_MAX);
    if (r != VK_SUCCESS) *what = "vkWaitForFences failed";
  }
  if (fence != VK_NULL_HANDLE) vkDestroyFence(device, fence, nullptr);
  vkFreeCommandBuffers(device, pool, 1, &cmd);
  return r;
}

}  // namespace vulkan_detail

bool levelBuffersDeviceLocal(const VulkanLevelBuffers& buffers) {
  for (int i = 0; i < int(kGpuBindingCount); ++i)
    if (buffers.buffers[i] == VK_NULL_HANDLE ||
        !(buffers.memoryFlags[i] & VK_MEMORY_PROPERTY_DEVICE_LOCAL_BIT))
      return false;
  return true;
}

void destroyStagingBuffer(VkDevice device, VulkanStagingBuffer& staging) {
  if (staging.buffer != VK_NULL_HANDLE) vkDestroyBuffer(device, staging.buffer, nullptr);
  if (staging.memory != VK_NULL_HANDLE) vkFreeMemory(device, staging.memory, nullptr);
  staging = VulkanStagingBuffer{};
}

bool packLevelBuffers(const Level& level, const StartGrid& grid, const std::vector<OuterCell>& outerCells,
                      const CellGrid& cellGrid, PackedLevelBuffers& out, std::string* error,
                      int32_t maxWalkSteps) {
  out = PackedLevelBuffers{};
  const auto fail = [&] {
    out = PackedLevelBuffers{};
    return false;
  };
  const size_t cells =
      size_t(std::max(grid.dims.x, 0)) * size_t(std::max(grid.dims.y, 0)) * size_t(std::max(grid.dims.z, 0));
  if (!level.tets.empty() && (cells == 0 || grid.startTet.size() != cells)) {
    if (error) *error = "start grid does not match its dims (build it with ProbeQuery on this level)";
    return fail();
  }

  // The shader indexes with these without bounds checks: an index out of range would read outside a buffer.
  const auto tetCount = int64_t(level.tets.size()), probeCount = int64_t(level.probes.size());
  if (level.sh.size() != level.probes.size()) {
    if (error)
      *error = "level has " + std::to_string(level.sh.size()) + " SH for " + std::to_string(probeCount) +
               " probes";
    return fail();
  }
  for (int64_t t = 0; t < tetCount; ++t) {
    const Tet& tet = level.tets[size_t(t)];
    for (int i = 0; i < 4; ++i) {
      if (tet.v[i] < 0 || tet.v[i] >= probeCount || tet.n[i] < -1 || tet.n[i] >= tetCount) {
        if (error) *error = "tet " + std::to_string(t) + " has a probe or neighbour index out of range";
        return fail();
      }
    }
  }
  for (int32_t s : grid.startTet) {
    if (s < 0 || s >= tetCount) {
      if (error) *error = "start grid names tet " + std::to_string(s) + " of " + std::to_string(tetCount);
      return fail();
    }
  }

  const auto cellCount = int64_t(outerCells.size());
  for (int64_t k = 0; k < cellCount; ++k) {
    const OuterCell& c = outerCells[size_t(k)];
    bool ok = c.tet >= 0 && c.tet < tetCount && c.face >= 0 && c.face < 4;
    for (int i = 0; i < 3; ++i)
      ok = ok && c.v[i] >= 0 && c.v[i] < probeCount && c.n[i] >= -1 && c.n[i] < cellCount;
    if (!ok) {
      if (error) *error = "outer cell " + std::to_string(k) + " has an index out of range";
      return fail();
    }
  }

  // The cell grid: every root, child and leaf entry the brick build descends, in range and acyclic (it is not
  // uploaded, but buildStartBricks descends it).
  {
    const auto nodeCount = int64_t(cellGrid.nodes.size());
    const auto validLeaf = [&](int32_t code) { return code == kEmptyLeaf || int64_t(~code) < tetCount; };
    const auto validChild = [&](int32_t c) { return c >= 0 ? c < nodeCount : validLeaf(c); };
    bool ok = cellGrid.slots.empty() || (cellGrid.slots.size() & (cellGrid.slots.size() - 1)) == 0;
    for (const CellSlot& s : cellGrid.slots) ok = ok && (s.key[0] == INT32_MIN || validChild(s.root));
    // A child node's index is larger than its parent's (cell_grid.h): the descent ends.
    for (int64_t i = 0; i < nodeCount; ++i)
      for (const int32_t c : cellGrid.nodes[size_t(i)].child) ok = ok && validChild(c) && (c < 0 || c > i);
    if (!ok) {
      if (error) *error = "cell grid has an index out of range";
      return fail();
    }
  }
  // The start bricks (start_bricks.h) from the cell grid's cells: every brick index and start tet the shader
  // follows, in range.
  const StartBricks bricks = buildStartBricks(level, grid, cellGrid);
  {
    const bool tableOk = cellGrid.slots.empty() || (cellGrid.slots.size() & (cellGrid.slots.size() - 1)) == 0;
    const size_t perBrick = size_t(bricks.dim) * size_t(bricks.dim) * size_t(bricks.dim);
    const auto brickCount = int64_t(perBrick == 0 ? 0 : bricks.startTet.size() / perBrick);
    bool ok = tableOk;
    for (const CellSlot& s : bricks.slots)
      ok = ok && (s.key[0] == INT32_MIN || (s.root >= 0 && s.root < brickCount));
    for (int32_t t : bricks.startTet) ok = ok && t >= 0 && t < tetCount;
    // The shader addresses the packed start tets' bits in 32 bits.
    ok = ok && uint64_t(bricks.startTet.size()) * bitsFor(level.tets.size()) < (uint64_t(1) << 32);
    if (!ok || bricks.slots.size() + bricks.startTet.size() > size_t(INT32_MAX / 4)) {
      if (error) *error = "cell grid has an index out of range";
      return fail();
    }
  }

  std::vector<char>* data = out.bytes;
  {
    const GpuTetPacking packing = gpuTetPacking(level.probes.size(), level.tets.size());
    GpuTetHeader tetHeader{};
    tetHeader.vertexBits = packing.vertexBits;
    tetHeader.neighbourBits = packing.neighbourBits;
    tetHeader.strideUints = packing.strideUints;
    tetHeader.count = uint32_t(level.tets.size());
    std::vector<uint32_t> records(level.tets.size() * packing.strideUints + kGpuTetTailUints, 0u);
    for (size_t t = 0; t < level.tets.size(); ++t)
      packGpuTet(level.tets[t], packing, records.data() + t * packing.strideUints);
    appendBytes(data[kGpuBindingTets], &tetHeader, 1);
    appendBytes(data[kGpuBindingTets], records.data(), records.size());
  }
  appendBytes(data[kGpuBindingProbes], level.probes.data(), level.probes.size());
  std::vector<ShHalf> shHalf(level.sh.size());
  for (size_t p = 0; p < level.sh.size(); ++p)
    if (!encodeShHalf(level.sh[p], &shHalf[p])) {
      if (error)
        *error = "probe " + std::to_string(p) +
                 " has an SH coefficient that is not finite or beyond half "
                 "precision's range (|c| > 2.1e9)";
      return fail();
    }
  appendBytes(data[kGpuBindingProbes], shHalf.data(), shHalf.size());
  GpuGridHeader header{};
  for (int i = 0; i < 3; ++i) {
    header.min[i] = grid.min[i];
    header.cellSize[i] = grid.cellSize[i];
    header.dims[i] = grid.dims[i];
  }
  header.tetCount = int32_t(level.tets.size());
  header.probeCount = int32_t(level.probes.size());
  header.maxWalkSteps = maxWalkSteps;
  appendBytes(data[kGpuBindingGrid], &header, 1);
  appendBytes(data[kGpuBindingGrid], grid.startTet.data(), grid.startTet.size());
  GpuOuterHeader outerHeader{};
  outerHeader.count = int32_t(cellCount);
  appendBytes(data[kGpuBindingOuterCells], &outerHeader, 1);
  for (const OuterCell& c : outerCells) {
    const GpuOuterCell g = gpuOuterCell(c);
    appendBytes(data[kGpuBindingOuterCells], &g, 1);
  }
  GpuCellGridHeader cellHeader{};
  for (int i = 0; i < 3; ++i) cellHeader.min[i] = bricks.min[i];
  cellHeader.cellSize = bricks.cellSize;
  cellHeader.slotMask = bricks.slots.empty() ? 0u : uint32_t(bricks.slots.size() - 1);
  cellHeader.maxProbe = bricks.slots.empty() ? 0u : bricks.maxProbe;
  cellHeader.brickOffset = int32_t(4 * bricks.slots.size());
  cellHeader.brickDim = bricks.dim;
  appendBytes(data[kGpuBindingCells], &cellHeader, 1);
  appendBytes(data[kGpuBindingCells], bricks.slots.data(), bricks.slots.size());
  {
    // The start tets at the tets' neighbour width (gpu_tets.h), then a zero word (the shader reads the next
    // word of every field).
    const uint32_t bits = bitsFor(level.tets.size());
    std::vector<uint32_t> packedStarts(packedFieldWords(bricks.startTet.size(), bits), 0u);
    for (size_t e = 0; e < bricks.startTet.size(); ++e)
      putBits(packedStarts.data(), uint64_t(e) * bits, bits, uint32_t(bricks.startTet[e]));
    if (!bricks.startTet.empty())
      appendBytes(data[kGpuBindingCells], packedStarts.data(), packedStarts.size());
  }

  const LevelOcclusion& occ = level.occlusion;
  GpuOcclusionHeader occHeader{};
  if (!occ.empty() && occ.tets.size() == level.tets.size()) {
    // Headers, then the plane tets' blocks (cells word and planes) in tet order, then the shadow maps.
    std::vector<uint32_t> headers(occ.tets.size()), planeBlocks;
    const std::vector<uint8_t> masks = faceBlendMasks(level, occ);  // one a tet (sizes equal: above)
    for (size_t t = 0; t < occ.tets.size(); ++t) {
      const TetOcclusion& rec = occ.tets[t];
      uint32_t offset = rec.offset();
      if (rec.kind() == kOcclusionPlanes) {
        if (size_t(rec.offset()) + rec.planeCount() > occ.planes.size()) {
          if (error) *error = "tet " + std::to_string(t) + "'s occlusion planes lie beyond the level's";
          return fail();
        }
        offset = uint32_t(std::min<size_t>(planeBlocks.size(), kGpuOccMaxOffset + size_t(1)));
        planeBlocks.push_back(rec.cells);
        for (uint32_t k = 0; k < rec.planeCount(); ++k) {
          const OcclusionPlane& p = occ.planes[size_t(rec.offset()) + k];
          planeBlocks.push_back(uint32_t(uint16_t(p.c[0])) | uint32_t(uint16_t(p.c[1])) << 16);
          planeBlocks.push_back(uint32_t(uint16_t(p.c[2])) | uint32_t(uint16_t(p.c[3])) << 16);
        }
      }
      if (offset > kGpuOccMaxOffset) {
        if (error)
          *error = "tet " + std::to_string(t) + "'s occlusion offset is beyond the GPU record's 2^24";
        return fail();
      }
      headers[t] = gpuOcclusionHeader(rec, masks[t], offset);
    }
    occHeader.tetCount = uint32_t(occ.tets.size());
    occHeader.planeOffset = uint32_t(headers.size());
    occHeader.shadowOffset = uint32_t(headers.size() + planeBlocks.size());
    appendBytes(data[kGpuBindingOcclusion], &occHeader, 1);
    appendBytes(data[kGpuBindingOcclusion], headers.data(), headers.size());
    appendBytes(data[kGpuBindingOcclusion], planeBlocks.data(), planeBlocks.size());
    appendBytes(data[kGpuBindingOcclusion], occ.shadowMaps.data(), occ.shadowMaps.size());
  } else {
    appendBytes(data[kGpuBindingOcclusion], &occHeader, 1);
  }

  // Never zero-sized (Vulkan forbids it); zero-padded to a multiple of 64 bytes.
  for (std::vector<char>& bytes : out.bytes)
    bytes.resize(std::max<size_t>(64, (bytes.size() + 63) / 64 * 64));
  return true;
}

VkResult cmdUploadLevelBuffers(VkPhysicalDevice physicalDevice, VkDevice device, VkCommandBuffer cmd,
                               const Level& level, const StartGrid& grid,
                               const std::vector<OuterCell>& outerCells, const CellGrid& cellGrid,
                               VkPipelineStageFlags shaderStages, VulkanLevelBuffers& out,
                               VulkanStagingBuffer& staging, std::string* error, int32_t maxWalkSteps) {
  out = VulkanLevelBuffers{};
  staging = VulkanStagingBuffer{};
  PackedLevelBuffers packed;
  if (!packLevelBuffers(level, grid, outerCells, cellGrid, packed, error, maxWalkSteps))
    return VK_ERROR_INITIALIZATION_FAILED;
  return cmdUploadPackedLevelBuffers(physicalDevice, device, cmd, packed, shaderStages, out, staging, error);
}

VkResult cmdUploadPackedLevelBuffers(VkPhysicalDevice physicalDevice, VkDevice device, VkCommandBuffer cmd,
                                     const PackedLevelBuffers& packed, VkPipelineStageFlags shaderStages,
                                     VulkanLevelBuffers& out, VulkanStagingBuffer& staging,
                                     std::string* error) {
  out = VulkanLevelBuffers{};
  staging = VulkanStagingBuffer{};
  for (int i = 0; i < int(kGpuBindingCount); ++i)
    if (packed.bytes[i].empty() || packed.bytes[i].size() % 64 != 0) {
      if (error) *error = std::string(bindingName(i)) + " buffer: packed bytes not a positive multiple of 64";
      return VK_ERROR_INITIALIZATION_FAILED;
    }

  VkPhysicalDeviceProperties props;
  vkGetPhysicalDeviceProperties(physicalDevice, &props);
  VkDeviceSize offsets[kGpuBindingCount] = {}, total = 0;
  for (int i = 0; i < int(kGpuBindingCount); ++i) {
    const VkDeviceSize size = packed.bytes[i].size();
    if (size > props.limits.maxStorageBufferRange) {
      if (error)
        *error = std::string(bindingName(i)) + " buffer needs " + std::to_string(size) +
                 " bytes, over the device's maxStorageBufferRange " +
                 std::to_string(props.limits.maxStorageBufferRange);
      return VK_ERROR_OUT_OF_DEVICE_MEMORY;
    }
    offsets[i] = total;  // multiples of 64, as every size is
    total += size;
  }

  // The level buffers first (they may fall back to host-visible memory), then the staging buffer.
  const VkBufferUsageFlags usage = VK_BUFFER_USAGE_STORAGE_BUFFER_BIT | VK_BUFFER_USAGE_TRANSFER_DST_BIT |
                                   VK_BUFFER_USAGE_TRANSFER_SRC_BIT;
  for (int i = 0; i < int(kGpuBindingCount); ++i) {
    std::string what;
    VkResult r = createBuffer(device, packed.bytes[i].size(), usage, &out.buffers[i], &what);
    if (r == VK_SUCCESS)
      r = allocateAndBind(physicalDevice, device, out.buffers[i], VK_MEMORY_PROPERTY_DEVICE_LOCAL_BIT,
                          VK_MEMORY_PROPERTY_HOST_VISIBLE_BIT, &out.memory[i], &out.memoryFlags[i], &what);
    if (r != VK_SUCCESS) {
      destroyLevelBuffers(device, out);
      if (error)
        *error = std::string(bindingName(i)) + " buffer: " + what + " (VkResult " + std::to_string(r) + ")";
      return r;
    }
    out.sizes[i] = packed.bytes[i].size();
  }
  std::string what;
  const VkResult r = vulkan_detail::createStagingBuffer(
      physicalDevice, device, total,
      [&](char* mapped) {
        for (int i = 0; i < int(kGpuBindingCount); ++i)
          std::memcpy(mapped + offsets[i], packed.bytes[i].data(), packed.bytes[i].size());
      },
      staging, &what);
  if (r != VK_SUCCESS) {
    destroyLevelBuffers(device, out);
    if (error) *error = what + " (VkResult " + std::to_string(r) + ")";
    return r;
  }

  for (int i = 0; i < int(kGpuBindingCount); ++i) {
    const VkBufferCopy region{offsets[i], 0, out.sizes[i]};
    vkCmdCopyBuffer(cmd, staging.buffer, out.buffers[i], 1, &region);
    out.stagedBytes += out.sizes[i];
  }
  // The copies before the shader's reads and before later transfer writes (cmdUpdateLevelSh, writeLevelSh).
  VkMemoryBarrier barrier{VK_STRUCTURE_TYPE_MEMORY_BARRIER};
  barrier.srcAccessMask = VK_ACCESS_TRANSFER_WRITE_BIT;
  barrier.dstAccessMask =
      VK_ACCESS_SHADER_READ_BIT | VK_ACCESS_TRANSFER_READ_BIT | VK_ACCESS_TRANSFER_WRITE_BIT;
  vkCmdPipelineBarrier(cmd, VK_PIPELINE_STAGE_TRANSFER_BIT, shaderStages | VK_PIPELINE_STAGE_TRANSFER_BIT, 0,
                       1, &barrier, 0, nullptr, 0, nullptr);
  return VK_SUCCESS;
}

VkResult uploadLevelBuffers(VkPhysicalDevice physicalDevice, VkDevice device, VkQueue queue,
                            VkCommandPool pool, const Level& level, const StartGrid& grid,
                            const std::vector<OuterCell>& outerCells, const CellGrid& cellGrid,
                            VulkanLevelBuffers& out, std::string* error, int32_t maxWalkSteps) {
  out = VulkanLevelBuffers{};
  PackedLevelBuffers packed;
  if (!packLevelBuffers(level, grid, outerCells, cellGrid, packed, error, maxWalkSteps))
    return VK_ERROR_INITIALIZATION_FAILED;
  return uploadPackedLevelBuffers(physicalDevice, device, queue, pool, packed, out, error);
}

VkResult uploadPackedLevelBuffers(VkPhysicalDevice physicalDevice, VkDevice device, VkQueue queue,
                                  VkCommandPool pool, const PackedLevelBuffers& packed,
                                  VulkanLevelBuffers& out, std::string* error) {
  out = VulkanLevelBuffers{};
  VulkanStagingBuffer staging;
  VkResult recorded = VK_SUCCESS;
  std::string what;
  const VkResult r = vulkan_detail::submitAndWait(
      device, queue, pool,
      [&](VkCommandBuffer cmd) {
        recorded = cmdUploadPackedLevelBuffers(physicalDevice, device, cmd, packed,
                                               VK_PIPELINE_STAGE_ALL_COMMANDS_BIT, out, staging, error);
      },
      &what);
  destroyStagingBuffer(device, staging);
  if (recorded != VK_SUCCESS) return recorded;  // `error` set, nothing allocated
  if (r != VK_SUCCESS) {
    destroyLevelBuffers(device, out);
    if (error) *error = "level upload: " + what + " (VkResult " + std::to_string(r) + ")";
    return r;
  }
  return VK_SUCCESS;
}

VkResult cmdWriteLevelBufferRanges(VkPhysicalDevice physicalDevice, VkDevice device, VkCommandBuffer cmd,
                                   const VulkanLevelBuffers& buffers, const PackedLevelBuffers& packed,
                                   const std::vector<GpuBufferRange>& ranges,
                                   VkPipelineStageFlags shaderStages, VulkanStagingBuffer& staging,
                                   std::string* error) {
  staging = VulkanStagingBuffer{};
  VkDeviceSize total = 0;
  for (const GpuBufferRange& r : ranges) {
    if (r.binding >= kGpuBindingCount || r.offset + r.bytes > packed.bytes[r.binding].size() ||
        r.offset + r.bytes > buffers.sizes[r.binding] || r.offset % 4 != 0 || r.bytes % 4 != 0) {
      if (error) *error = "buffer range outside its buffer, or not 4-byte aligned";
      return VK_ERROR_INITIALIZATION_FAILED;
    }
    total += r.bytes;
  }
  if (total == 0) return VK_SUCCESS;
  std::string what;
  const VkResult res = vulkan_detail::createStagingBuffer(
      physicalDevice, device, total,
      [&](char* mapped) {
        VkDeviceSize at = 0;
        for (const GpuBufferRange& r : ranges) {
          std::memcpy(mapped + at, packed.bytes[r.binding].data() + r.offset, size_t(r.bytes));
          at += r.bytes;
        }
      },
      staging, &what);
  if (res != VK_SUCCESS) {
    if (error) *error = what + " (VkResult " + std::to_string(res) + ")";
    return res;
  }
  // Earlier reads of the buffers finish before the copies write (frames in flight), and the copies are
  // visible to later reads.
  VkMemoryBarrier before{VK_STRUCTURE_TYPE_MEMORY_BARRIER};
  before.srcAccessMask = VK_ACCESS_SHADER_READ_BIT;
  before.dstAccessMask = VK_ACCESS_TRANSFER_WRITE_BIT;
  vkCmdPipelineBarrier(cmd, shaderStages, VK_PIPELINE_STAGE_TRANSFER_BIT, 0, 1, &before, 0, nullptr, 0,
                       nullptr);
  std::vector<VkDeviceSize> source(ranges.size());  // each range's place in the staging buffer, in order
  for (size_t i = 1; i < ranges.size(); ++i) source[i] = source[i - 1] + ranges[i - 1].bytes;
  for (uint32_t b = 0; b < kGpuBindingCount; ++b) {
    std::vector<VkBufferCopy> regions;
    for (size_t i = 0; i < ranges.size(); ++i)
      if (ranges[i].binding == b)
        regions.push_back(VkBufferCopy{source[i], ranges[i].offset, ranges[i].bytes});
    if (!regions.empty())
      vkCmdCopyBuffer(cmd, staging.buffer, buffers.buffers[b], uint32_t(regions.size()), regions.data());
  }
  VkMemoryBarrier after{VK_STRUCTURE_TYPE_MEMORY_BARRIER};
  after.srcAccessMask = VK_ACCESS_TRANSFER_WRITE_BIT;
  after.dstAccessMask = VK_ACCESS_SHADER_READ_BIT | VK_ACCESS_TRANSFER_WRITE_BIT;
  vkCmdPipelineBarrier(cmd, VK_PIPELINE_STAGE_TRANSFER_BIT, shaderStages | VK_PIPELINE_STAGE_TRANSFER_BIT, 0,
                       1, &after, 0, nullptr, 0, nullptr);
  return VK_SUCCESS;
}

void destroyLevelBuffers(VkDevice device, VulkanLevelBuffers& buffers) {
  for (int i = 0; i < int(kGpuBindingCount); ++i) {
    if (buffers.buffers[i] != VK_NULL_HANDLE) vkDestroyBuffer(device, buffers.buffers[i], nullptr);
    if (buffers.memory[i] != VK_NULL_HANDLE) vkFreeMemory(device, buffers.memory[i], nullptr);
  }
  buffers = VulkanLevelBuffers{};
}

void levelDescriptorBindings(VkShaderStageFlags stages, uint32_t firstBinding,
                             VkDescriptorSetLayoutBinding out[kGpuBindingCount]) {
  for (uint32_t i = 0; i < kGpuBindingCount; ++i) {
    out[i] = VkDescriptorSetLayoutBinding{};
    out[i].binding = firstBinding + i;
    out[i].descriptorType = VK_DESCRIPTOR_TYPE_STORAGE_BUFFER;
    out[i].descriptorCount = 1;
    out[i].stageFlags = stages;
  }
}

void writeLevelDescriptors(VkDevice device, VkDescriptorSet set, uint32_t firstBinding,
                           const VulkanLevelBuffers& buffers) {
  VkDescriptorBufferInfo infos[kGpuBindingCount];
  VkWriteDescriptorSet writes[kGpuBindingCount];
  for (uint32_t i = 0; i < kGpuBindingCount; ++i) {
    infos[i] = VkDescriptorBufferInfo{buffers.buffers[i], 0, buffers.sizes[i]};
    writes[i] = VkWriteDescriptorSet{VK_STRUCTURE_TYPE_WRITE_DESCRIPTOR_SET};
    writes[i].dstSet = set;
    writes[i].dstBinding = firstBinding + i;
    writes[i].descriptorCount = 1;
    writes[i].descriptorType = VK_DESCRIPTOR_TYPE_STORAGE_BUFFER;
    writes[i].pBufferInfo = &infos[i];
  }
  vkUpdateDescriptorSets(device, kGpuBindingCount, writes, 0, nullptr);
}

void shaderSpecialization(const ShaderVariant& variant, uint32_t firstConstantId, ShaderSpecialization& out) {
  static_assert(sizeof(VkBool32) == sizeof(uint32_t), "tetraprobe.glsl's bool constants are 4 bytes");
  variant.specValues(out.data);
  for (uint32_t i = 0; i < kShaderSpecConstantCount; ++i)
    out.entries[i] = {firstConstantId + i, uint32_t(i * sizeof(uint32_t)), sizeof(uint32_t)};
  out.info.mapEntryCount = kShaderSpecConstantCount;
  out.info.pMapEntries = out.entries;
  out.info.dataSize = sizeof(out.data);
  out.info.pData = out.data;
}

}  // namespace tetraprobe
