// A headless Vulkan instance + device + queue for the renderer, and the few buffer/image helpers it needs.
// Internal to the render module.
#pragma once

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include <vulkan/vulkan.h>

namespace tetraprobe::render_detail {

// Throws std::runtime_error("<what> failed: <VkResult name>") unless r == VK_SUCCESS.
void vkCheck(VkResult r, const char* what);

// Runs the pushed cleanups in reverse order when destroyed (or on run()): every Vulkan object the renderer
// creates registers its destroy call here right after creation, so early throws leak nothing.
class CleanupStack {
 public:
  CleanupStack() = default;
  CleanupStack(const CleanupStack&) = delete;
  CleanupStack& operator=(const CleanupStack&) = delete;
  ~CleanupStack() { run(); }
  void push(std::function<void()> f) { fns_.push_back(std::move(f)); }
  void run() {
    while (!fns_.empty()) {
      auto f = std::move(fns_.back());
      fns_.pop_back();
      f();
    }
  }

 private:
  std::vector<std::function<void()>> fns_;
};

struct GpuBuffer {
  VkBuffer buffer = VK_NULL_HANDLE;
  VkDeviceMemory memory = VK_NULL_HANDLE;
  VkDeviceSize size = 0;
};

struct GpuImage {
  VkImage image = VK_NULL_HANDLE;
  VkDeviceMemory memory = VK_NULL_HANDLE;
  VkImageView view = VK_NULL_HANDLE;
};

// Instance (no surface extensions), physical device (lavapipe preferred, else the first with a queue family
// that does graphics + compute), logical device, one queue and a command pool. Destroyed in the destructor.
class VulkanContext {
 public:
  VulkanContext();  // throws std::runtime_error
  ~VulkanContext();
  VulkanContext(const VulkanContext&) = delete;
  VulkanContext& operator=(const VulkanContext&) = delete;

  VkPhysicalDevice physicalDevice() const { return physical_; }
  VkDevice device() const { return device_; }
  VkQueue queue() const { return queue_; }
  VkCommandPool commandPool() const { return pool_; }
  // Nanoseconds per timestamp tick, or 0 when the queue does not support timestamps.
  double timestampPeriodNs() const { return timestampPeriodNs_; }
  const std::string& deviceName() const { return deviceName_; }

  // A buffer in memory with `props`; its destruction is pushed onto `cleanup`.
  GpuBuffer createBuffer(VkDeviceSize size, VkBufferUsageFlags usage, VkMemoryPropertyFlags props,
                         CleanupStack& cleanup) const;
  // A 2D image (one mip, `layers` layers, optimal tiling) in device-local memory with a view of all layers
  // (2D for one layer, 2D array for more); destruction pushed.
  GpuImage createImage(uint32_t width, uint32_t height, VkFormat format, VkImageUsageFlags usage,
                       VkImageAspectFlags aspect, CleanupStack& cleanup, uint32_t layers = 1) const;
  // A 3D colour image (one mip, optimal tiling, device-local) with a 3D view; destruction pushed.
  GpuImage createImage3D(uint32_t width, uint32_t height, uint32_t depth, VkFormat format,
                         VkImageUsageFlags usage, CleanupStack& cleanup) const;
  // A 2D view of one layer of `image`; destruction pushed.
  VkImageView createLayerView(VkImage image, VkFormat format, VkImageAspectFlags aspect, uint32_t layer,
                              CleanupStack& cleanup) const;

 private:
  uint32_t memoryType(uint32_t typeBits, VkMemoryPropertyFlags props) const;
  // Allocates memory meeting `req` with `props` and registers its release on `cleanup`; `what` names the
  // resource in the error message.
  VkDeviceMemory allocateMemory(const VkMemoryRequirements& req, VkMemoryPropertyFlags props,
                                const char* what, CleanupStack& cleanup) const;
  void destroy();

  VkInstance instance_ = VK_NULL_HANDLE;
  VkPhysicalDevice physical_ = VK_NULL_HANDLE;
  VkDevice device_ = VK_NULL_HANDLE;
  VkQueue queue_ = VK_NULL_HANDLE;
  VkCommandPool pool_ = VK_NULL_HANDLE;
  uint32_t queueFamily_ = 0;
  double timestampPeriodNs_ = 0;
  std::string deviceName_;
};

}  // namespace tetraprobe::render_detail
