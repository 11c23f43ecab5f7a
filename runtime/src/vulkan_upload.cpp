// Vulkan upload of a level's tets, SH and start grid into the storage buffers shaders/tetraprobe_layout.glsl
// declares (host-visible coherent memory, one allocation per buffer).
#include "tetraprobe/runtime/vulkan_upload.h"

#include "tetraprobe/runtime/sh_half.h"

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

bool findHostMemoryType(VkPhysicalDevice physicalDevice, uint32_t typeBits, uint32_t* index) {
  VkPhysicalDeviceMemoryProperties props;
  vkGetPhysicalDeviceMemoryProperties(physicalDevice, &props);
  const VkMemoryPropertyFlags want =
      VK_MEMORY_PROPERTY_HOST_VISIBLE_BIT | VK_MEMORY_PROPERTY_HOST_COHERENT_BIT;
  for (uint32_t i = 0; i < props.memoryTypeCount; ++i) {
    if ((typeBits & (1u << i)) && (props.memoryTypes[i].propertyFlags & want) == want) {
      *index = i;
      return true;
    }
  }
  return false;
}

// Creates one buffer holding `bytes` (zero-padded to `size`).
VkResult createFilledBuffer(VkPhysicalDevice physicalDevice, VkDevice device, const std::vector<char>& bytes,
                            VkDeviceSize size, VkBuffer* buffer, VkDeviceMemory* memory, std::string* what) {
  VkBufferCreateInfo info{VK_STRUCTURE_TYPE_BUFFER_CREATE_INFO};
  info.size = size;
  // TRANSFER_DST: cmdUpdateLevelSh (vulkan_sh_update.cpp) writes the SH with vkCmdUpdateBuffer.
  info.usage = VK_BUFFER_USAGE_STORAGE_BUFFER_BIT | VK_BUFFER_USAGE_TRANSFER_DST_BIT;
  info.sharingMode = VK_SHARING_MODE_EXCLUSIVE;
  VkResult r = vkCreateBuffer(device, &info, nullptr, buffer);
  if (r != VK_SUCCESS) return *what = "vkCreateBuffer failed", r;
  VkMemoryRequirements req;
  vkGetBufferMemoryRequirements(device, *buffer, &req);
  VkMemoryAllocateInfo alloc{VK_STRUCTURE_TYPE_MEMORY_ALLOCATE_INFO};
  alloc.allocationSize = req.size;
  if (!findHostMemoryType(physicalDevice, req.memoryTypeBits, &alloc.memoryTypeIndex))
    return *what = "no host-visible coherent memory type", VK_ERROR_FEATURE_NOT_PRESENT;
  r = vkAllocateMemory(device, &alloc, nullptr, memory);
  if (r != VK_SUCCESS) return *what = "vkAllocateMemory failed", r;
  r = vkBindBufferMemory(device, *buffer, *memory, 0);
  if (r != VK_SUCCESS) return *what = "vkBindBufferMemory failed", r;
  void* mapped = nullptr;
  r = vkMapMemory(device, *memory, 0, VK_WHOLE_SIZE, 0, &mapped);
  if (r != VK_SUCCESS) return *what = "vkMapMemory failed", r;
  std::memset(mapped, 0, size_t(size));
  if (!bytes.empty()) std::memcpy(mapped, bytes.data(), bytes.size());
  vkUnmapMemory(device, *memory);
  return VK_SUCCESS;
}

template <typename T>
void appendBytes(std::vector<char>& out, const T* data, size_t count) {
  const auto* p = reinterpret_cast<const char*>(data);
  out.insert(out.end(), p, p + sizeof(T) * count);
}

}  // namespace

VkResult uploadLevelBuffers(VkPhysicalDevice physicalDevice, VkDevice device, const Level& level,
                            const StartGrid& grid, const std::vector<OuterCell>& outerCells,
                            const CellGrid& cellGrid, VulkanLevelBuffers& out, std::string* error,
                            int32_t maxWalkSteps) {
  out = VulkanLevelBuffers{};
  const size_t cells =
      size_t(std::max(grid.dims.x, 0)) * size_t(std::max(grid.dims.y, 0)) * size_t(std::max(grid.dims.z, 0));
  if (!level.tets.empty() && (cells == 0 || grid.startTet.size() != cells)) {
    if (error) *error = "start grid does not match its dims (build it with ProbeQuery on this level)";
    return VK_ERROR_INITIALIZATION_FAILED;
  }

  // The shader indexes with these without bounds checks: an index out of range would read outside a buffer.
  const auto tetCount = int64_t(level.tets.size()), probeCount = int64_t(level.probes.size());
  if (level.sh.size() != level.probes.size()) {
    if (error)
      *error = "level has " + std::to_string(level.sh.size()) + " SH for " + std::to_string(probeCount) +
               " probes";
    return VK_ERROR_INITIALIZATION_FAILED;
  }
  for (int64_t t = 0; t < tetCount; ++t) {
    const Tet& tet = level.tets[size_t(t)];
    for (int i = 0; i < 4; ++i) {
      if (tet.v[i] < 0 || tet.v[i] >= probeCount || tet.n[i] < -1 || tet.n[i] >= tetCount) {
        if (error) *error = "tet " + std::to_string(t) + " has a probe or neighbour index out of range";
        return VK_ERROR_INITIALIZATION_FAILED;
      }
    }
  }
  for (int32_t s : grid.startTet) {
    if (s < 0 || s >= tetCount) {
      if (error) *error = "start grid names tet " + std::to_string(s) + " of " + std::to_string(tetCount);
      return VK_ERROR_INITIALIZATION_FAILED;
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
      return VK_ERROR_INITIALIZATION_FAILED;
    }
  }

  // The cell grid: every root, child and leaf entry the shader follows, in range.
  {
    const auto nodeCount = int64_t(cellGrid.nodes.size());
    const auto validLeaf = [&](int32_t code) { return code == kEmptyLeaf || int64_t(~code) < tetCount; };
    const auto validChild = [&](int32_t c) { return c >= 0 ? c < nodeCount : validLeaf(c); };
    bool ok = cellGrid.slots.empty() || (cellGrid.slots.size() & (cellGrid.slots.size() - 1)) == 0;
    for (const CellSlot& s : cellGrid.slots) ok = ok && (s.key[0] == INT32_MIN || validChild(s.root));
    for (const BspNode& n : cellGrid.nodes) ok = ok && validChild(n.child[0]) && validChild(n.child[1]);
    if (!ok) {
      if (error) *error = "cell grid has an index out of range";
      return VK_ERROR_INITIALIZATION_FAILED;
    }
  }

  std::vector<char> data[kGpuBindingCount];
  appendBytes(data[kGpuBindingTets], level.tets.data(), level.tets.size());
  appendBytes(data[kGpuBindingProbes], level.probes.data(), level.probes.size());
  std::vector<ShHalf> shHalf(level.sh.size());
  for (size_t p = 0; p < level.sh.size(); ++p)
    if (!encodeShHalf(level.sh[p], &shHalf[p])) {
      if (error)
        *error = "probe " + std::to_string(p) +
                 " has an SH coefficient that is not finite or beyond half "
                 "precision's range (|c| > 2.1e9)";
      return VK_ERROR_INITIALIZATION_FAILED;
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
    GpuOuterCell g{};
    for (int i = 0; i < 3; ++i) {
      for (int a = 0; a < 3; ++a) g.n[3 * i + a] = c.normal[i][a];
      g.v[i] = c.v[i];
      g.link[i] = c.n[i];
    }
    g.v[3] = c.tet;
    g.link[3] = c.face;
    appendBytes(data[kGpuBindingOuterCells], &g, 1);
  }
  GpuCellGridHeader cellHeader{};
  for (int i = 0; i < 3; ++i) cellHeader.min[i] = cellGrid.min[i];
  cellHeader.cellSize = cellGrid.cellSize;
  cellHeader.slotMask = cellGrid.slots.empty() ? 0u : uint32_t(cellGrid.slots.size() - 1);
  cellHeader.maxProbe = cellGrid.slots.empty() ? 0u : cellGrid.maxProbe;
  cellHeader.nodeOffset = int32_t(4 * cellGrid.slots.size());
  appendBytes(data[kGpuBindingCells], &cellHeader, 1);
  appendBytes(data[kGpuBindingCells], cellGrid.slots.data(), cellGrid.slots.size());
  appendBytes(data[kGpuBindingCells], cellGrid.nodes.data(), cellGrid.nodes.size());

  const LevelOcclusion& occ = level.occlusion;
  GpuOcclusionHeader occHeader{};
  if (!occ.empty() && occ.tets.size() == level.tets.size()) {
    occHeader.tetCount = uint32_t(occ.tets.size());
    occHeader.planeOffset = uint32_t(2 * occ.tets.size());
    occHeader.shadowOffset = uint32_t(occHeader.planeOffset + 2 * occ.planes.size());
  }
  appendBytes(data[kGpuBindingOcclusion], &occHeader, 1);
  if (occHeader.tetCount > 0) {
    appendBytes(data[kGpuBindingOcclusion], occ.tets.data(), occ.tets.size());
    appendBytes(data[kGpuBindingOcclusion], occ.planes.data(), occ.planes.size());
    appendBytes(data[kGpuBindingOcclusion], occ.shadowMaps.data(), occ.shadowMaps.size());
  }

  VkPhysicalDeviceProperties props;
  vkGetPhysicalDeviceProperties(physicalDevice, &props);
  for (int i = 0; i < int(kGpuBindingCount); ++i) {
    // Never zero-sized (Vulkan forbids it); rounded up to 64 bytes.
    const VkDeviceSize size = std::max<VkDeviceSize>(64, (data[i].size() + 63) / 64 * 64);
    if (size > props.limits.maxStorageBufferRange) {
      destroyLevelBuffers(device, out);
      if (error)
        *error = std::string(bindingName(i)) + " buffer needs " + std::to_string(size) +
                 " bytes, over the device's maxStorageBufferRange " +
                 std::to_string(props.limits.maxStorageBufferRange);
      return VK_ERROR_OUT_OF_DEVICE_MEMORY;
    }
    std::string what;
    const VkResult r =
        createFilledBuffer(physicalDevice, device, data[i], size, &out.buffers[i], &out.memory[i], &what);
    if (r != VK_SUCCESS) {
      destroyLevelBuffers(device, out);
      if (error)
        *error = std::string(bindingName(i)) + " buffer: " + what + " (VkResult " + std::to_string(r) + ")";
      return r;
    }
    out.sizes[i] = size;
  }
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
