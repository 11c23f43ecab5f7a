// Vulkan upload of a loaded level: the five storage buffers shaders/tetraprobe.glsl reads, and the
// descriptor-set plumbing for them. Permissive: Vulkan, GLM and the standard library only.
//
// Memory: each buffer lives in its own HOST_VISIBLE | HOST_COHERENT allocation, written through a mapping
// at upload (no staging copy yet; on a discrete GPU the shader then reads over the bus; a later version may
// add a staging upload to DEVICE_LOCAL memory). Usage STORAGE | TRANSFER_DST: run-time SH updates (below)
// write the probe buffer in place, by mapping or vkCmdUpdateBuffer. Errors are returned as VkResult (no exceptions), with a one-line
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
// Positions stay in the level's local frame. SH are stored as ShHalf (sh_half.h, 56 bytes a probe): a level
// read by loadLevel or updated by setProbeSh already holds exactly those values, so GPU and CPU lookups agree
// bit for bit; for SH set by hand, quantizeSh them first to get the same. SH that are not finite or beyond
// half precision's range (|c| > 2.1e9) fail with VK_ERROR_INITIALIZATION_FAILED. An empty level (no tets) gives valid buffers with tetCount 0,
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

// Run-time SH updates of an uploaded level (after setProbeSh, probe_update.h, on the CPU copy): both encode
// level.sh[first, first + count) as ShHalf (sh_half.h) into the probe buffer (binding + 1) at the offsets
// gpu_layout.h gives (uints 3 * probes + 14 * probe ...), nothing else. `level` must be the level `buffers` were uploaded from (same
// probe count; checked against the buffer size). Lookups that read the buffer afterwards see the new SH,
// bit-identical to an upload of a level holding them (tests/render/test_sh_update.cpp).
//
// writeLevelSh writes through a mapping of the buffer's host-visible coherent memory, at once, on the calling
// thread. Sync contract: no submitted work that reads `buffers` may still be executing (wait for its fence,
// or vkQueueWaitIdle); then no flush and no barrier are needed, since a vkQueueSubmit made after the call
// makes host writes to coherent memory visible to the device. The memory must not be mapped elsewhere.
// Returns VK_ERROR_INITIALIZATION_FAILED (nothing written) when the range lies outside the level or the
// buffer is too small for the level, or vkMapMemory's error; `error` gets one line.
VkResult writeLevelSh(VkDevice device, const VulkanLevelBuffers& buffers, const Level& level, size_t first,
                      size_t count, std::string* error = nullptr);

// cmdUpdateLevelSh records the same copy into `cmd` (vkCmdUpdateBuffer, at most 65536 bytes each, so the SH
// are copied into the command buffer when recorded, 56 bytes a probe: meant for updates of up to some
// thousands of probes a frame; larger ones are better served by writeLevelSh), between two barriers: reads by
// `shaderStages` recorded or submitted earlier to the same queue finish before the transfer writes (no
// write-after-read race with frames in flight), and the writes are visible to reads by `shaderStages`
// recorded or submitted after (TRANSFER_WRITE -> SHADER_READ). Other queues need the engine's semaphores. Must be recorded outside a render pass. Returns false (nothing recorded,
// `error` set) on the same range and size checks as writeLevelSh; count 0 records nothing.
bool cmdUpdateLevelSh(VkCommandBuffer cmd, const VulkanLevelBuffers& buffers, const Level& level,
                      size_t first, size_t count, VkPipelineStageFlags shaderStages,
                      std::string* error = nullptr);

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
