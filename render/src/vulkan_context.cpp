// Headless Vulkan context for the renderer: instance without surface, device selection (lavapipe first),
// one graphics+compute queue, and buffer/image helpers.
#include "vulkan_context.h"

#include <cstdlib>
#include <cstring>
#include <stdexcept>
#include <string>

namespace tetraprobe::render_detail {
namespace {

const char* resultName(VkResult r) {
  switch (r) {
    case VK_SUCCESS:
      return "VK_SUCCESS";
    case VK_ERROR_OUT_OF_HOST_MEMORY:
      return "VK_ERROR_OUT_OF_HOST_MEMORY";
    case VK_ERROR_OUT_OF_DEVICE_MEMORY:
      return "VK_ERROR_OUT_OF_DEVICE_MEMORY";
    case VK_ERROR_INITIALIZATION_FAILED:
      return "VK_ERROR_INITIALIZATION_FAILED";
    case VK_ERROR_DEVICE_LOST:
      return "VK_ERROR_DEVICE_LOST";
    case VK_ERROR_LAYER_NOT_PRESENT:
      return "VK_ERROR_LAYER_NOT_PRESENT";
    case VK_ERROR_EXTENSION_NOT_PRESENT:
      return "VK_ERROR_EXTENSION_NOT_PRESENT";
    case VK_ERROR_FEATURE_NOT_PRESENT:
      return "VK_ERROR_FEATURE_NOT_PRESENT";
    case VK_ERROR_INCOMPATIBLE_DRIVER:
      return "VK_ERROR_INCOMPATIBLE_DRIVER";
    case VK_ERROR_FORMAT_NOT_SUPPORTED:
      return "VK_ERROR_FORMAT_NOT_SUPPORTED";
    default:
      return "VkResult error";
  }
}

bool validationRequested() {
  const char* v = std::getenv("TETRAPROBE_VK_VALIDATION");
  return v && v[0] && std::strcmp(v, "0") != 0;
}

bool layerAvailable(const char* name) {
  uint32_t count = 0;
  vkEnumerateInstanceLayerProperties(&count, nullptr);
  std::vector<VkLayerProperties> layers(count);
  vkEnumerateInstanceLayerProperties(&count, layers.data());
  for (const auto& l : layers)
    if (std::strcmp(l.layerName, name) == 0) return true;
  return false;
}

// The first queue family with graphics and compute, or -1.
int graphicsComputeFamily(VkPhysicalDevice device) {
  uint32_t count = 0;
  vkGetPhysicalDeviceQueueFamilyProperties(device, &count, nullptr);
  std::vector<VkQueueFamilyProperties> families(count);
  vkGetPhysicalDeviceQueueFamilyProperties(device, &count, families.data());
  const VkQueueFlags want = VK_QUEUE_GRAPHICS_BIT | VK_QUEUE_COMPUTE_BIT;
  for (uint32_t i = 0; i < count; ++i)
    if ((families[i].queueFlags & want) == want) return int(i);
  return -1;
}

}  // namespace

void vkCheck(VkResult r, const char* what) {
  if (r != VK_SUCCESS)
    throw std::runtime_error(std::string(what) + " failed: " + resultName(r) + " (" + std::to_string(r) +
                             ")");
}

VulkanContext::VulkanContext() {
  // The destructor does not run when a constructor throws: clean up what exists before rethrowing.
  try {
    VkApplicationInfo app{VK_STRUCTURE_TYPE_APPLICATION_INFO};
    app.pApplicationName = "tetraprobe-render";
    app.apiVersion = VK_API_VERSION_1_1;
    VkInstanceCreateInfo ici{VK_STRUCTURE_TYPE_INSTANCE_CREATE_INFO};
    ici.pApplicationInfo = &app;
    const char* validation = "VK_LAYER_KHRONOS_validation";
    if (validationRequested() && layerAvailable(validation)) {
      ici.enabledLayerCount = 1;
      ici.ppEnabledLayerNames = &validation;
    }
    const VkResult ir = vkCreateInstance(&ici, nullptr, &instance_);
    if (ir == VK_ERROR_INCOMPATIBLE_DRIVER || ir == VK_ERROR_INITIALIZATION_FAILED)
      throw std::runtime_error("no Vulkan driver: install mesa-vulkan-drivers (vkCreateInstance failed)");
    vkCheck(ir, "vkCreateInstance");

    uint32_t count = 0;
    vkEnumeratePhysicalDevices(instance_, &count, nullptr);
    std::vector<VkPhysicalDevice> devices(count);
    vkEnumeratePhysicalDevices(instance_, &count, devices.data());
    int family = -1;
    for (int pass = 0; pass < 2 && physical_ == VK_NULL_HANDLE; ++pass) {
      for (VkPhysicalDevice d : devices) {
        VkPhysicalDeviceProperties props;
        vkGetPhysicalDeviceProperties(d, &props);
        const bool lavapipe = std::strstr(props.deviceName, "llvmpipe") != nullptr;
        if (props.apiVersion < VK_API_VERSION_1_1 || (pass == 0 && !lavapipe)) continue;
        const int f = graphicsComputeFamily(d);
        if (f < 0) continue;
        physical_ = d;
        family = f;
        break;
      }
    }
    if (physical_ == VK_NULL_HANDLE)
      throw std::runtime_error("no Vulkan device: install mesa-vulkan-drivers");
    queueFamily_ = uint32_t(family);

    const float priority = 1.0f;
    VkDeviceQueueCreateInfo qci{VK_STRUCTURE_TYPE_DEVICE_QUEUE_CREATE_INFO};
    qci.queueFamilyIndex = queueFamily_;
    qci.queueCount = 1;
    qci.pQueuePriorities = &priority;
    VkDeviceCreateInfo dci{VK_STRUCTURE_TYPE_DEVICE_CREATE_INFO};
    dci.queueCreateInfoCount = 1;
    dci.pQueueCreateInfos = &qci;
    vkCheck(vkCreateDevice(physical_, &dci, nullptr, &device_), "vkCreateDevice");
    vkGetDeviceQueue(device_, queueFamily_, 0, &queue_);

    VkCommandPoolCreateInfo pci{VK_STRUCTURE_TYPE_COMMAND_POOL_CREATE_INFO};
    pci.queueFamilyIndex = queueFamily_;
    vkCheck(vkCreateCommandPool(device_, &pci, nullptr, &pool_), "vkCreateCommandPool");

    uint32_t familyCount = 0;
    vkGetPhysicalDeviceQueueFamilyProperties(physical_, &familyCount, nullptr);
    std::vector<VkQueueFamilyProperties> families(familyCount);
    vkGetPhysicalDeviceQueueFamilyProperties(physical_, &familyCount, families.data());
    VkPhysicalDeviceProperties props;
    vkGetPhysicalDeviceProperties(physical_, &props);
    if (families[queueFamily_].timestampValidBits > 0) timestampPeriodNs_ = props.limits.timestampPeriod;
    deviceName_ = props.deviceName;
  } catch (...) {
    destroy();
    throw;
  }
}

VulkanContext::~VulkanContext() {
  destroy();
}

void VulkanContext::destroy() {
  if (pool_ != VK_NULL_HANDLE) vkDestroyCommandPool(device_, pool_, nullptr);
  if (device_ != VK_NULL_HANDLE) vkDestroyDevice(device_, nullptr);
  if (instance_ != VK_NULL_HANDLE) vkDestroyInstance(instance_, nullptr);
  pool_ = VK_NULL_HANDLE;
  device_ = VK_NULL_HANDLE;
  instance_ = VK_NULL_HANDLE;
}

uint32_t VulkanContext::memoryType(uint32_t typeBits, VkMemoryPropertyFlags props) const {
  VkPhysicalDeviceMemoryProperties mem;
  vkGetPhysicalDeviceMemoryProperties(physical_, &mem);
  for (uint32_t i = 0; i < mem.memoryTypeCount; ++i)
    if ((typeBits & (1u << i)) && (mem.memoryTypes[i].propertyFlags & props) == props) return i;
  throw std::runtime_error("no Vulkan memory type with the required properties");
}

VkDeviceMemory VulkanContext::allocateMemory(const VkMemoryRequirements& req, VkMemoryPropertyFlags props,
                                             const char* what, CleanupStack& cleanup) const {
  VkMemoryAllocateInfo alloc{VK_STRUCTURE_TYPE_MEMORY_ALLOCATE_INFO};
  alloc.allocationSize = req.size;
  alloc.memoryTypeIndex = memoryType(req.memoryTypeBits, props);
  VkDeviceMemory mem = VK_NULL_HANDLE;
  vkCheck(vkAllocateMemory(device_, &alloc, nullptr, &mem), what);
  VkDevice dev = device_;
  cleanup.push([dev, mem] { vkFreeMemory(dev, mem, nullptr); });
  return mem;
}

GpuBuffer VulkanContext::createBuffer(VkDeviceSize size, VkBufferUsageFlags usage,
                                      VkMemoryPropertyFlags props, CleanupStack& cleanup) const {
  GpuBuffer b;
  b.size = size;
  VkBufferCreateInfo info{VK_STRUCTURE_TYPE_BUFFER_CREATE_INFO};
  info.size = size;
  info.usage = usage;
  info.sharingMode = VK_SHARING_MODE_EXCLUSIVE;
  vkCheck(vkCreateBuffer(device_, &info, nullptr, &b.buffer), "vkCreateBuffer");
  VkDevice dev = device_;
  VkBuffer buf = b.buffer;
  cleanup.push([dev, buf] { vkDestroyBuffer(dev, buf, nullptr); });
  VkMemoryRequirements req;
  vkGetBufferMemoryRequirements(device_, b.buffer, &req);
  b.memory = allocateMemory(req, props, "vkAllocateMemory (buffer)", cleanup);
  vkCheck(vkBindBufferMemory(device_, b.buffer, b.memory, 0), "vkBindBufferMemory");
  return b;
}

GpuImage VulkanContext::createImage(uint32_t width, uint32_t height, VkFormat format, VkImageUsageFlags usage,
                                    VkImageAspectFlags aspect, CleanupStack& cleanup, uint32_t layers) const {
  GpuImage im;
  VkImageCreateInfo info{VK_STRUCTURE_TYPE_IMAGE_CREATE_INFO};
  info.imageType = VK_IMAGE_TYPE_2D;
  info.format = format;
  info.extent = {width, height, 1};
  info.mipLevels = 1;
  info.arrayLayers = layers;
  info.samples = VK_SAMPLE_COUNT_1_BIT;
  info.tiling = VK_IMAGE_TILING_OPTIMAL;
  info.usage = usage;
  info.sharingMode = VK_SHARING_MODE_EXCLUSIVE;
  info.initialLayout = VK_IMAGE_LAYOUT_UNDEFINED;
  vkCheck(vkCreateImage(device_, &info, nullptr, &im.image), "vkCreateImage");
  VkDevice dev = device_;
  VkImage img = im.image;
  cleanup.push([dev, img] { vkDestroyImage(dev, img, nullptr); });
  VkMemoryRequirements req;
  vkGetImageMemoryRequirements(device_, im.image, &req);
  im.memory = allocateMemory(req, VK_MEMORY_PROPERTY_DEVICE_LOCAL_BIT, "vkAllocateMemory (image)", cleanup);
  vkCheck(vkBindImageMemory(device_, im.image, im.memory, 0), "vkBindImageMemory");
  VkImageViewCreateInfo vci{VK_STRUCTURE_TYPE_IMAGE_VIEW_CREATE_INFO};
  vci.image = im.image;
  vci.viewType = layers > 1 ? VK_IMAGE_VIEW_TYPE_2D_ARRAY : VK_IMAGE_VIEW_TYPE_2D;
  vci.format = format;
  vci.subresourceRange = {aspect, 0, 1, 0, layers};
  vkCheck(vkCreateImageView(device_, &vci, nullptr, &im.view), "vkCreateImageView");
  VkImageView view = im.view;
  cleanup.push([dev, view] { vkDestroyImageView(dev, view, nullptr); });
  return im;
}

GpuImage VulkanContext::createImage3D(uint32_t width, uint32_t height, uint32_t depth, VkFormat format,
                                      VkImageUsageFlags usage, CleanupStack& cleanup) const {
  GpuImage im;
  VkImageCreateInfo info{VK_STRUCTURE_TYPE_IMAGE_CREATE_INFO};
  info.imageType = VK_IMAGE_TYPE_3D;
  info.format = format;
  info.extent = {width, height, depth};
  info.mipLevels = 1;
  info.arrayLayers = 1;
  info.samples = VK_SAMPLE_COUNT_1_BIT;
  info.tiling = VK_IMAGE_TILING_OPTIMAL;
  info.usage = usage;
  info.sharingMode = VK_SHARING_MODE_EXCLUSIVE;
  info.initialLayout = VK_IMAGE_LAYOUT_UNDEFINED;
  vkCheck(vkCreateImage(device_, &info, nullptr, &im.image), "vkCreateImage (3D)");
  VkDevice dev = device_;
  VkImage img = im.image;
  cleanup.push([dev, img] { vkDestroyImage(dev, img, nullptr); });
  VkMemoryRequirements req;
  vkGetImageMemoryRequirements(device_, im.image, &req);
  im.memory =
      allocateMemory(req, VK_MEMORY_PROPERTY_DEVICE_LOCAL_BIT, "vkAllocateMemory (3D image)", cleanup);
  vkCheck(vkBindImageMemory(device_, im.image, im.memory, 0), "vkBindImageMemory (3D)");
  VkImageViewCreateInfo vci{VK_STRUCTURE_TYPE_IMAGE_VIEW_CREATE_INFO};
  vci.image = im.image;
  vci.viewType = VK_IMAGE_VIEW_TYPE_3D;
  vci.format = format;
  vci.subresourceRange = {VK_IMAGE_ASPECT_COLOR_BIT, 0, 1, 0, 1};
  vkCheck(vkCreateImageView(device_, &vci, nullptr, &im.view), "vkCreateImageView (3D)");
  VkImageView view = im.view;
  cleanup.push([dev, view] { vkDestroyImageView(dev, view, nullptr); });
  return im;
}

VkImageView VulkanContext::createLayerView(VkImage image, VkFormat format, VkImageAspectFlags aspect,
                                           uint32_t layer, CleanupStack& cleanup) const {
  VkImageViewCreateInfo vci{VK_STRUCTURE_TYPE_IMAGE_VIEW_CREATE_INFO};
  vci.image = image;
  vci.viewType = VK_IMAGE_VIEW_TYPE_2D;
  vci.format = format;
  vci.subresourceRange = {aspect, 0, 1, layer, 1};
  VkImageView view;
  vkCheck(vkCreateImageView(device_, &vci, nullptr, &view), "vkCreateImageView (layer)");
  VkDevice dev = device_;
  cleanup.push([dev, view] { vkDestroyImageView(dev, view, nullptr); });
  return view;
}

}  // namespace tetraprobe::render_detail
