// The engine's side of the GPU samples (gpu_level.cpp, gpu_streaming.cpp): one Vulkan device, queue,
// command buffer and fence, frames submitted and waited for, and a buffer read back through a copy.
#pragma once

#include <cstring>
#include <string>
#include <vector>

#include <vulkan/vulkan.h>

// The engine's Vulkan objects for this sample: one device, one queue, one command buffer, one fence.
struct Engine {
  VkInstance instance = VK_NULL_HANDLE;
  VkPhysicalDevice physical = VK_NULL_HANDLE;
  VkDevice device = VK_NULL_HANDLE;
  VkQueue queue = VK_NULL_HANDLE;
  VkCommandPool pool = VK_NULL_HANDLE;
  VkCommandBuffer cmd = VK_NULL_HANDLE;
  VkFence fence = VK_NULL_HANDLE;
  std::string name;

  ~Engine() {
    if (device != VK_NULL_HANDLE) {
      vkDeviceWaitIdle(device);
      if (fence != VK_NULL_HANDLE) vkDestroyFence(device, fence, nullptr);
      if (pool != VK_NULL_HANDLE) vkDestroyCommandPool(device, pool, nullptr);
      vkDestroyDevice(device, nullptr);
    }
    if (instance != VK_NULL_HANDLE) vkDestroyInstance(instance, nullptr);
  }

  // False when there is no Vulkan driver or device with a graphics or compute queue.
  bool start() {
    VkApplicationInfo app{VK_STRUCTURE_TYPE_APPLICATION_INFO};
    app.pApplicationName = "engine_integration";
    app.apiVersion = VK_API_VERSION_1_1;
    VkInstanceCreateInfo ici{VK_STRUCTURE_TYPE_INSTANCE_CREATE_INFO};
    ici.pApplicationInfo = &app;
    if (vkCreateInstance(&ici, nullptr, &instance) != VK_SUCCESS) return false;
    uint32_t count = 0;
    vkEnumeratePhysicalDevices(instance, &count, nullptr);
    std::vector<VkPhysicalDevice> devices(count);
    vkEnumeratePhysicalDevices(instance, &count, devices.data());
    for (VkPhysicalDevice d : devices) {
      uint32_t familyCount = 0;
      vkGetPhysicalDeviceQueueFamilyProperties(d, &familyCount, nullptr);
      std::vector<VkQueueFamilyProperties> families(familyCount);
      vkGetPhysicalDeviceQueueFamilyProperties(d, &familyCount, families.data());
      for (uint32_t f = 0; f < familyCount && device == VK_NULL_HANDLE; ++f) {
        if (!(families[f].queueFlags & (VK_QUEUE_GRAPHICS_BIT | VK_QUEUE_COMPUTE_BIT))) continue;
        const float priority = 1.0f;
        VkDeviceQueueCreateInfo qci{VK_STRUCTURE_TYPE_DEVICE_QUEUE_CREATE_INFO};
        qci.queueFamilyIndex = f;
        qci.queueCount = 1;
        qci.pQueuePriorities = &priority;
        VkDeviceCreateInfo dci{VK_STRUCTURE_TYPE_DEVICE_CREATE_INFO};
        dci.queueCreateInfoCount = 1;
        dci.pQueueCreateInfos = &qci;
        if (vkCreateDevice(d, &dci, nullptr, &device) != VK_SUCCESS) continue;
        physical = d;
        vkGetDeviceQueue(device, f, 0, &queue);
        VkCommandPoolCreateInfo pci{VK_STRUCTURE_TYPE_COMMAND_POOL_CREATE_INFO};
        pci.flags = VK_COMMAND_POOL_CREATE_RESET_COMMAND_BUFFER_BIT;
        pci.queueFamilyIndex = f;
        VkCommandBufferAllocateInfo cai{VK_STRUCTURE_TYPE_COMMAND_BUFFER_ALLOCATE_INFO};
        cai.level = VK_COMMAND_BUFFER_LEVEL_PRIMARY;
        cai.commandBufferCount = 1;
        VkFenceCreateInfo fci{VK_STRUCTURE_TYPE_FENCE_CREATE_INFO};
        if (vkCreateCommandPool(device, &pci, nullptr, &pool) != VK_SUCCESS) return false;
        cai.commandPool = pool;
        if (vkAllocateCommandBuffers(device, &cai, &cmd) != VK_SUCCESS) return false;
        if (vkCreateFence(device, &fci, nullptr, &fence) != VK_SUCCESS) return false;
        VkPhysicalDeviceProperties props;
        vkGetPhysicalDeviceProperties(d, &props);
        name = props.deviceName;
      }
      if (device != VK_NULL_HANDLE) return true;
    }
    return false;
  }

  // One "frame": begin, record(cmd), end, submit with the fence, wait for it.
  template <typename Record>
  bool frame(const Record& record) {
    VkCommandBufferBeginInfo begin{VK_STRUCTURE_TYPE_COMMAND_BUFFER_BEGIN_INFO};
    begin.flags = VK_COMMAND_BUFFER_USAGE_ONE_TIME_SUBMIT_BIT;
    if (vkResetFences(device, 1, &fence) != VK_SUCCESS || vkBeginCommandBuffer(cmd, &begin) != VK_SUCCESS)
      return false;
    const bool recorded = record(cmd);
    VkSubmitInfo submit{VK_STRUCTURE_TYPE_SUBMIT_INFO};
    submit.commandBufferCount = 1;
    submit.pCommandBuffers = &cmd;
    return vkEndCommandBuffer(cmd) == VK_SUCCESS && vkQueueSubmit(queue, 1, &submit, fence) == VK_SUCCESS &&
           vkWaitForFences(device, 1, &fence, VK_TRUE, UINT64_MAX) == VK_SUCCESS && recorded;
  }
};

// The allocation for `buffer` in a host-visible, coherent memory type (memoryTypeIndex UINT32_MAX: none).
inline VkMemoryAllocateInfo hostAllocation(const Engine& e, VkBuffer buffer) {
  VkMemoryRequirements req;
  vkGetBufferMemoryRequirements(e.device, buffer, &req);
  VkPhysicalDeviceMemoryProperties mem;
  vkGetPhysicalDeviceMemoryProperties(e.physical, &mem);
  const VkMemoryPropertyFlags host =
      VK_MEMORY_PROPERTY_HOST_VISIBLE_BIT | VK_MEMORY_PROPERTY_HOST_COHERENT_BIT;
  VkMemoryAllocateInfo alloc{VK_STRUCTURE_TYPE_MEMORY_ALLOCATE_INFO};
  alloc.allocationSize = req.size;
  alloc.memoryTypeIndex = UINT32_MAX;
  for (uint32_t i = 0; i < mem.memoryTypeCount && alloc.memoryTypeIndex == UINT32_MAX; ++i)
    if ((req.memoryTypeBits & (1u << i)) && (mem.memoryTypes[i].propertyFlags & host) == host)
      alloc.memoryTypeIndex = i;
  return alloc;
}

// A buffer's bytes, copied on the GPU into a host-visible buffer (the level's buffers are not mappable on a
// discrete GPU).
inline bool readBuffer(Engine& e, VkBuffer source, VkDeviceSize size, std::vector<char>& out) {
  VkBufferCreateInfo bci{VK_STRUCTURE_TYPE_BUFFER_CREATE_INFO};
  bci.size = size;
  bci.usage = VK_BUFFER_USAGE_TRANSFER_DST_BIT;
  VkBuffer buffer = VK_NULL_HANDLE;
  if (vkCreateBuffer(e.device, &bci, nullptr, &buffer) != VK_SUCCESS) return false;
  const VkMemoryAllocateInfo alloc = hostAllocation(e, buffer);
  VkDeviceMemory memory = VK_NULL_HANDLE;
  void* mapped = nullptr;
  bool ok = alloc.memoryTypeIndex != UINT32_MAX &&
            vkAllocateMemory(e.device, &alloc, nullptr, &memory) == VK_SUCCESS &&
            vkBindBufferMemory(e.device, buffer, memory, 0) == VK_SUCCESS &&
            e.frame([&](VkCommandBuffer cmd) {
              const VkBufferCopy region{0, 0, bci.size};
              vkCmdCopyBuffer(cmd, source, buffer, 1, &region);
              VkMemoryBarrier toHost{VK_STRUCTURE_TYPE_MEMORY_BARRIER};
              toHost.srcAccessMask = VK_ACCESS_TRANSFER_WRITE_BIT;
              toHost.dstAccessMask = VK_ACCESS_HOST_READ_BIT;
              vkCmdPipelineBarrier(cmd, VK_PIPELINE_STAGE_TRANSFER_BIT, VK_PIPELINE_STAGE_HOST_BIT, 0, 1,
                                   &toHost, 0, nullptr, 0, nullptr);
              return true;
            }) &&
            vkMapMemory(e.device, memory, 0, VK_WHOLE_SIZE, 0, &mapped) == VK_SUCCESS;
  if (ok) {
    out.assign(static_cast<const char*>(mapped), static_cast<const char*>(mapped) + bci.size);
    vkUnmapMemory(e.device, memory);
  }
  if (memory != VK_NULL_HANDLE) vkFreeMemory(e.device, memory, nullptr);
  vkDestroyBuffer(e.device, buffer, nullptr);
  return ok;
}
