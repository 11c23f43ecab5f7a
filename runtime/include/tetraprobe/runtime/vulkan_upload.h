// Vulkan upload of a loaded level: the six storage buffers shaders/tetraprobe.glsl reads, and the
// descriptor-set plumbing for them. Permissive: Vulkan, GLM and the standard library only.
//
// What an engine owns per level: one VulkanLevelBuffers (six VkBuffers, each in its own VkDeviceMemory, in a
// DEVICE_LOCAL memory type when the device has one that fits; usage STORAGE | TRANSFER_DST | TRANSFER_SRC),
// and, while an upload is in flight, one VulkanStagingBuffer (HOST_VISIBLE | HOST_COHERENT, TRANSFER_SRC)
// that holds every buffer's bytes back to back. The level buffers are never mapped: they are filled by
// vkCmdCopyBuffer from the staging buffer, and run-time SH updates (below) write them by vkCmdUpdateBuffer or
// by a staged copy, so the shader reads device memory on a discrete GPU. Errors are returned as VkResult (no
// exceptions), with a one-line message when `error` is given.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include <vulkan/vulkan.h>

#include "tetraprobe/runtime/gpu_layout.h"
#include "tetraprobe/runtime/gpu_sector_pool.h"
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
  // The property flags of the memory type each buffer was allocated from: DEVICE_LOCAL unless the device
  // had no device-local type the buffer may use, or that heap was full (then a HOST_VISIBLE type).
  VkMemoryPropertyFlags memoryFlags[kGpuBindingCount] = {};
  // Bytes the upload recorded as vkCmdCopyBuffer from its staging buffer into these buffers (the sum of
  // `sizes`: every byte of every buffer, padding included, comes from the staging copy, none from a
  // mapping of the level's memory).
  VkDeviceSize stagedBytes = 0;
};

// True when every buffer of `buffers` lives in a DEVICE_LOCAL memory type.
bool levelBuffersDeviceLocal(const VulkanLevelBuffers& buffers);

// A host-visible coherent buffer holding an upload's source bytes. It must stay alive until the submission
// that copies from it has completed; then destroyStagingBuffer frees it.
struct VulkanStagingBuffer {
  VkBuffer buffer = VK_NULL_HANDLE;
  VkDeviceMemory memory = VK_NULL_HANDLE;
  VkDeviceSize size = 0;
};

// Destroys the staging buffer and frees its memory (null handles are skipped); resets `staging`.
void destroyStagingBuffer(VkDevice device, VulkanStagingBuffer& staging);

// Validates and packs `level` (tets, SH), `grid` (ProbeQuery::startGrid() of a query built on the same level)
// and `outerCells` (ProbeQuery::outerCells(); may be empty: outside answers are then the clamped hull tet's)
// and `cellGrid` (ProbeQuery::cellGrid(); may be empty: walks start from the start grid; uploaded as the start
// bricks buildStartBricks makes from it, start_bricks.h, not as its BSP). Positions stay in
// the level's local frame. SH are stored as ShHalf (sh_half.h, 56 bytes a probe): a level read by loadLevel
// or updated by setProbeSh already holds exactly those values, so GPU and CPU lookups agree bit for bit; for
// SH set by hand, quantizeSh them first to get the same. SH that are not finite or beyond half precision's
// range (|c| > 2.1e9) are refused. An empty level (no tets) packs valid buffers with tetCount 0, for which
// the shader returns E = 0. Every index the shader follows (tet probes and neighbours, start tets, one SH per
// probe, outer-cell and cell-grid links) is checked, O(tets + cells), since the shader reads without bounds
// checks. Returns false (`out` emptied, `error` set to one line) on any of these; allocates only `out`.
bool packLevelBuffers(const Level& level, const StartGrid& grid, const std::vector<OuterCell>& outerCells,
                      const CellGrid& cellGrid, PackedLevelBuffers& out, std::string* error = nullptr,
                      int32_t maxWalkSteps = kGpuDefaultMaxWalkSteps);

// Upload, recorded into the engine's command buffer: packs the level (packLevelBuffers; its failures return
// VK_ERROR_INITIALIZATION_FAILED), creates the six level buffers (DEVICE_LOCAL preferred, see
// VulkanLevelBuffers::memoryFlags) and one staging buffer holding their bytes, and records into `cmd` (in
// the recording state, outside a render pass, on a queue with transfer support: any graphics or compute
// queue) one vkCmdCopyBuffer per buffer, then a barrier making the copies visible to reads by
// `shaderStages` and to later transfers (cmdUpdateLevelSh) recorded or submitted after it on that queue.
// The engine submits `cmd`, and once that submission has completed (its fence) calls
// destroyStagingBuffer(device, staging). A buffer over the device's maxStorageBufferRange (lavapipe:
// 128 MiB, about 1.6 M tets) or exhausted memory fails with VK_ERROR_OUT_OF_DEVICE_MEMORY. On failure
// nothing is recorded, nothing is left allocated and `out` and `staging` are reset.
VkResult cmdUploadLevelBuffers(VkPhysicalDevice physicalDevice, VkDevice device, VkCommandBuffer cmd,
                               const Level& level, const StartGrid& grid,
                               const std::vector<OuterCell>& outerCells, const CellGrid& cellGrid,
                               VkPipelineStageFlags shaderStages, VulkanLevelBuffers& out,
                               VulkanStagingBuffer& staging, std::string* error = nullptr,
                               int32_t maxWalkSteps = kGpuDefaultMaxWalkSteps);

// cmdUploadLevelBuffers from bytes already packed (packLevelBuffers, or a GpuSectorPool's buffers()): the
// same buffers, staging copy and barrier. Each packed buffer must be a positive multiple of 64 bytes.
VkResult cmdUploadPackedLevelBuffers(VkPhysicalDevice physicalDevice, VkDevice device, VkCommandBuffer cmd,
                                     const PackedLevelBuffers& packed, VkPipelineStageFlags shaderStages,
                                     VulkanLevelBuffers& out, VulkanStagingBuffer& staging,
                                     std::string* error = nullptr);

// Streaming (gpu_sector_pool.h): records copies of `ranges` of `packed` (a pool's buffers() after its loads
// and evictions; ranges from takeDirtyRanges()) into `buffers` (uploaded from the same pool), through one
// staging buffer holding just those bytes, between two barriers: reads by `shaderStages` recorded or
// submitted earlier finish before the copies write, and later reads see them. The engine submits `cmd` and
// frees `staging` once it has completed. An empty range list records nothing. A range outside its buffer or
// not 4-byte aligned: VK_ERROR_INITIALIZATION_FAILED, nothing recorded.
VkResult cmdWriteLevelBufferRanges(VkPhysicalDevice physicalDevice, VkDevice device, VkCommandBuffer cmd,
                                   const VulkanLevelBuffers& buffers, const PackedLevelBuffers& packed,
                                   const std::vector<GpuBufferRange>& ranges,
                                   VkPipelineStageFlags shaderStages, VulkanStagingBuffer& staging,
                                   std::string* error = nullptr);

// Upload, submitted and waited for: cmdUploadLevelBuffers into a command buffer allocated from `pool` (of
// `queue`'s family; the pool must not be used by another thread meanwhile), submitted to `queue` with a
// fence, waited for, then the command buffer, fence and staging buffer are freed. On return the buffers
// are filled and visible to any later submission to `queue`. Same failures as cmdUploadLevelBuffers, plus
// the VkResult of a failed allocation, submit or wait (nothing left allocated).
VkResult uploadLevelBuffers(VkPhysicalDevice physicalDevice, VkDevice device, VkQueue queue,
                            VkCommandPool pool, const Level& level, const StartGrid& grid,
                            const std::vector<OuterCell>& outerCells, const CellGrid& cellGrid,
                            VulkanLevelBuffers& out, std::string* error = nullptr,
                            int32_t maxWalkSteps = kGpuDefaultMaxWalkSteps);

// uploadLevelBuffers from bytes already packed (cmdUploadPackedLevelBuffers, submitted and waited for).
VkResult uploadPackedLevelBuffers(VkPhysicalDevice physicalDevice, VkDevice device, VkQueue queue,
                                  VkCommandPool pool, const PackedLevelBuffers& packed,
                                  VulkanLevelBuffers& out, std::string* error = nullptr);

// Destroys the buffers and frees their memory (null handles are skipped); resets `buffers`. The device must
// no longer use them.
void destroyLevelBuffers(VkDevice device, VulkanLevelBuffers& buffers);

// Fills out[0..5] with the layout bindings for firstBinding + 0..5 (TETRAPROBE_BINDING in the shader):
// read-only storage buffers visible to `stages`. Append them to the engine's VkDescriptorSetLayoutCreateInfo.
void levelDescriptorBindings(VkShaderStageFlags stages, uint32_t firstBinding,
                             VkDescriptorSetLayoutBinding out[kGpuBindingCount]);

// Points bindings firstBinding + 0..5 of `set` at the buffers (one vkUpdateDescriptorSets call).
void writeLevelDescriptors(VkDevice device, VkDescriptorSet set, uint32_t firstBinding,
                           const VulkanLevelBuffers& buffers);

// Run-time SH updates of an uploaded level (after setProbeSh, probe_update.h, on the CPU copy): both encode
// level.sh[first, first + count) as ShHalf (sh_half.h) into the probe buffer (binding + 1) at the offsets
// gpu_layout.h gives (uints 3 * probes + 14 * probe ...), nothing else, and neither maps the level's memory,
// so both work on device-local buffers. `level` must be the level `buffers` were uploaded from (same probe
// count; checked against the buffer size). Lookups that read the buffer afterwards see the new SH,
// bit-identical to an upload of a level holding them (tests/render/test_sh_update.cpp).
//
// cmdUpdateLevelSh records the write into `cmd` (vkCmdUpdateBuffer, at most 65536 bytes each, so the SH are
// copied into the command buffer when recorded, 56 bytes a probe: meant for updates of up to some thousands
// of probes a frame; larger ones are better served by writeLevelSh), between two barriers: reads by
// `shaderStages` recorded or submitted earlier to the same queue finish before the transfer writes (no
// write-after-read race with frames in flight), and the writes are visible to reads by `shaderStages`
// recorded or submitted after (TRANSFER_WRITE -> SHADER_READ). Other queues need the engine's semaphores.
// Must be recorded outside a render pass. Returns false (nothing recorded, `error` set) when the range lies
// outside the level, the buffer is too small for the level or an SH cannot be encoded; count 0 records
// nothing.
bool cmdUpdateLevelSh(VkCommandBuffer cmd, const VulkanLevelBuffers& buffers, const Level& level,
                      size_t first, size_t count, VkPipelineStageFlags shaderStages,
                      std::string* error = nullptr);

// writeLevelSh is the staged, blocking form, for large relights (a whole level): the records go into a
// host-visible staging buffer of count * 56 bytes, and one vkCmdCopyBuffer into the probe buffer is
// submitted to `queue` in a command buffer from `pool` (of `queue`'s family, not used by another thread
// meanwhile), between the same two barriers as cmdUpdateLevelSh (all stages before, all stages after), and
// waited for; the staging buffer is freed before return. So work submitted earlier to `queue` finishes
// before the copy writes, and work submitted after the call sees the new SH; work on other queues that reads
// `buffers` must have completed. Returns VK_ERROR_INITIALIZATION_FAILED (nothing written) on the checks of
// cmdUpdateLevelSh, or the VkResult of a failed allocation, submit or wait; `error` gets one line. count 0
// writes nothing and submits nothing.
VkResult writeLevelSh(VkPhysicalDevice physicalDevice, VkDevice device, VkQueue queue, VkCommandPool pool,
                      const VulkanLevelBuffers& buffers, const Level& level, size_t first, size_t count,
                      std::string* error = nullptr);

// The VkSpecializationInfo of a shader variant (shader_variant.h) for a pipeline whose shader includes
// tetraprobe.glsl: constant_id firstConstantId + 0..7 (TETRAPROBE_SPEC_ID in the shader, default 0), 4 bytes
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
