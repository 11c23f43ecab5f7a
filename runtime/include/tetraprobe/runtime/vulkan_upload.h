// Vulkan upload of a loaded level: the five storage buffers shaders/tetraprobe.glsl reads, and the
// descriptor-set plumbing for them. Permissive: Vulkan, GLM and the standard library only.
//
// Memory: each buffer lives in its own HOST_VISIBLE | HOST_COHERENT allocation, written once through a
// mapping (no staging copy yet; on a discrete GPU the shader then reads over the bus; a later version may add
// a staging upload to DEVICE_LOCAL memory). Errors are returned as VkResult (no exceptions), with a one-line
// message when `error` is given.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include <vulkan/vulkan.h>

#include "tetraprobe/runtime/gpu_layout.h"
#include "tetraprobe/runtime/level.h"
#include "tetraprobe/runtime/query.h"
#include "tetraprobe/runtime/shader_variant.h"

namespace tetraprobe {

// The walk bound written into the grid header (tetraprobeMaxWalkSteps): kMaxWalkSteps of
// runtime/src/query.cpp.
inline constexpr int32_t kGpuDefaultMaxWalkSteps = 4096;

struct VulkanLevelBuffers {
  VkBuffer buffers[kGpuBindingCount] = {};  // indexed by GpuBinding
  VkDeviceMemory memory[kGpuBindingCount] = {};
  VkDeviceSize sizes[kGpuBindingCount] = {};  // bytes bound to each binding (at least 64, never 0)
};

// Creates and fills the buffers of `level` (tets, SH), `grid` (ProbeQuery::startGrid() of a query built
// on the same level) and `outerCells` (ProbeQuery::outerCells(); may be empty: outside answers are then the
// clamped hull tet's) and `cellGrid` (ProbeQuery::cellGrid(); may be empty: walks start from the start grid).
// Positions stay in the level's local frame. An empty level (no tets) gives valid buffers with tetCount 0,
// for which the shader returns E = 0. Every index the shader follows (tet probes and neighbours, start tets,
// one SH per probe) is checked first, O(tets + cells), since the shader reads without bounds checks: any out
// of range fails with VK_ERROR_INITIALIZATION_FAILED. A buffer over the device's maxStorageBufferRange
// (lavapipe: 128 MiB, about 1.6 M tets) or exhausted memory fails with VK_ERROR_OUT_OF_DEVICE_MEMORY. On
// failure nothing is left allocated and `out` is reset.
VkResult uploadLevelBuffers(VkPhysicalDevice physicalDevice, VkDevice device, const Level& level,
                            const StartGrid& grid, const std::vector<OuterCell>& outerCells,
                            const CellGrid& cellGrid, VulkanLevelBuffers& out, std::string* error = nullptr,
                            int32_t maxWalkSteps = kGpuDefaultMaxWalkSteps);

// Destroys the buffers and frees their memory (null handles are skipped); resets `buffers`. The device must
// no longer use them.
void destroyLevelBuffers(VkDevice device, VulkanLevelBuffers& buffers);

// Fills out[0..4] with the layout bindings for firstBinding + 0..4 (TETRAPROBE_BINDING in the shader):
// read-only storage buffers visible to `stages`. Append them to the engine's VkDescriptorSetLayoutCreateInfo.
void levelDescriptorBindings(VkShaderStageFlags stages, uint32_t firstBinding,
                             VkDescriptorSetLayoutBinding out[kGpuBindingCount]);

// Points bindings firstBinding + 0..4 of `set` at the buffers (one vkUpdateDescriptorSets call).
void writeLevelDescriptors(VkDevice device, VkDescriptorSet set, uint32_t firstBinding,
                           const VulkanLevelBuffers& buffers);

// The VkSpecializationInfo of a shader variant (shader_variant.h) for a pipeline whose shader includes
// tetraprobe.glsl: constant_id firstConstantId + 0..4 (TETRAPROBE_SPEC_ID in the shader, default 0), 4 bytes
// each. `info` points into this object, so it is neither copied nor moved: fill it in place with
// shaderSpecialization() and keep it alive until vkCreateComputePipelines / vkCreateGraphicsPipelines
// returns. Engines: shaderSpecialization(shaderVariantFor(level, query.outerCells(), query.cellGrid()), 0,
// spec); stageInfo.pSpecializationInfo = &spec.info.
struct ShaderSpecialization {
  VkSpecializationMapEntry entries[kShaderSpecConstantCount] = {};
  uint32_t data[kShaderSpecConstantCount] = {};
  VkSpecializationInfo info = {};

  ShaderSpecialization() = default;
  ShaderSpecialization(const ShaderSpecialization&) = delete;
  ShaderSpecialization& operator=(const ShaderSpecialization&) = delete;
};

// Fills `out` for `variant` (entries, data, and info pointing at them).
void shaderSpecialization(const ShaderVariant& variant, uint32_t firstConstantId, ShaderSpecialization& out);

}  // namespace tetraprobe
