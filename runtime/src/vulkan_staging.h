// Internal to runtime_vulkan: the staging buffer and the one-shot submission shared by the level upload
// (vulkan_upload.cpp) and the staged SH write (vulkan_sh_update.cpp). Defined in vulkan_upload.cpp.
#pragma once

#include <functional>
#include <string>

#include <vulkan/vulkan.h>

#include "tetraprobe/runtime/vulkan_upload.h"

namespace tetraprobe::vulkan_detail {

// Creates a HOST_VISIBLE | HOST_COHERENT buffer of `size` bytes (TRANSFER_SRC) and calls fill(mapping) with
// its memory mapped; unmaps it after. On failure `out` is left empty and `what` says which call failed.
VkResult createStagingBuffer(VkPhysicalDevice physicalDevice, VkDevice device, VkDeviceSize size,
                             const std::function<void(char*)>& fill, VulkanStagingBuffer& out,
                             std::string* what);

// Allocates a primary command buffer from `pool`, records `record` into it (between begin and end), submits
// it to `queue` with a fence and waits; frees the command buffer and the fence. `what` names a failed call.
VkResult submitAndWait(VkDevice device, VkQueue queue, VkCommandPool pool,
                       const std::function<void(VkCommandBuffer)>& record, std::string* what);

}  // namespace tetraprobe::vulkan_detail
