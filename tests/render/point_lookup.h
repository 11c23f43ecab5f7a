// Test harness: the GPU lookup (shaders/tetraprobe.glsl through point_lookup.comp, on the renderer's headless
// Vulkan context: lavapipe in CI) at a fixed list of points, against any number of uploaded levels, with room
// for commands recorded before the lookup (run-time SH updates). Used by tests/render/test_sh_update.cpp and
// tests/visual (a relit baked level). Throws std::runtime_error ("no Vulkan ...") without a device.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstring>
#include <functional>
#include <stdexcept>
#include <string>
#include <vector>

#include "point_lookup.comp.h"
#include "tetraprobe/runtime/query.h"
#include "tetraprobe/runtime/vulkan_upload.h"
#include "vulkan_context.h"

namespace tetraprobe::test {

// Records `record` into a one-time command buffer, submits it to the context's queue and waits.
inline void submitAndWait(const render_detail::VulkanContext& ctx,
                          const std::function<void(VkCommandBuffer)>& record) {
  using render_detail::vkCheck;
  const VkDevice dev = ctx.device();
  VkCommandBufferAllocateInfo cai{VK_STRUCTURE_TYPE_COMMAND_BUFFER_ALLOCATE_INFO};
  cai.commandPool = ctx.commandPool();
  cai.level = VK_COMMAND_BUFFER_LEVEL_PRIMARY;
  cai.commandBufferCount = 1;
  VkCommandBuffer cmd;
  vkCheck(vkAllocateCommandBuffers(dev, &cai, &cmd), "vkAllocateCommandBuffers");
  VkCommandBufferBeginInfo begin{VK_STRUCTURE_TYPE_COMMAND_BUFFER_BEGIN_INFO};
  begin.flags = VK_COMMAND_BUFFER_USAGE_ONE_TIME_SUBMIT_BIT;
  vkCheck(vkBeginCommandBuffer(cmd, &begin), "vkBeginCommandBuffer");
  record(cmd);
  vkCheck(vkEndCommandBuffer(cmd), "vkEndCommandBuffer");
  VkSubmitInfo submit{VK_STRUCTURE_TYPE_SUBMIT_INFO};
  submit.commandBufferCount = 1;
  submit.pCommandBuffers = &cmd;
  vkCheck(vkQueueSubmit(ctx.queue(), 1, &submit, VK_NULL_HANDLE), "vkQueueSubmit");
  vkCheck(vkQueueWaitIdle(ctx.queue()), "vkQueueWaitIdle");
  vkFreeCommandBuffers(dev, ctx.commandPool(), 1, &cmd);
}

using render_detail::CleanupStack;
using render_detail::GpuBuffer;
using render_detail::vkCheck;
using render_detail::VulkanContext;

// One query as point_lookup.comp reads it (std430).
struct PointNormal {
  float position[4];
  float normal[4];
};

// ProbeQuery::irradiance at every point (local frame positions, as the GPU gets them).
inline std::vector<glm::vec3> cpuIrradiance(const ProbeQuery& q, const std::vector<PointNormal>& pts) {
  std::vector<glm::vec3> out;
  for (const PointNormal& p : pts)
    out.push_back(q.irradiance(q.level().origin + glm::dvec3(p.position[0], p.position[1], p.position[2]),
                               glm::vec3(p.normal[0], p.normal[1], p.normal[2])));
  return out;
}

// point_lookup.comp over a fixed point list: set 0 = a level's six buffers, set 1 = points and results.
class PointLookup {
 public:
  explicit PointLookup(const std::vector<PointNormal>& pts) : count_(uint32_t(pts.size())) {
    const VkDevice dev = ctx_.device();
    VkDescriptorSetLayoutBinding levelBindings[kGpuBindingCount];
    levelDescriptorBindings(VK_SHADER_STAGE_COMPUTE_BIT, 0, levelBindings);
    VkDescriptorSetLayoutBinding ioBindings[2] = {};
    for (uint32_t i = 0; i < 2; ++i)
      ioBindings[i] = {i, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, 1, VK_SHADER_STAGE_COMPUTE_BIT, nullptr};
    setLayouts_[0] = setLayout(levelBindings, kGpuBindingCount);
    setLayouts_[1] = setLayout(ioBindings, 2);

    const VkPushConstantRange push{VK_SHADER_STAGE_COMPUTE_BIT, 0, sizeof(uint32_t)};
    VkPipelineLayoutCreateInfo pli{VK_STRUCTURE_TYPE_PIPELINE_LAYOUT_CREATE_INFO};
    pli.setLayoutCount = 2;
    pli.pSetLayouts = setLayouts_;
    pli.pushConstantRangeCount = 1;
    pli.pPushConstantRanges = &push;
    vkCheck(vkCreatePipelineLayout(dev, &pli, nullptr, &layout_), "vkCreatePipelineLayout");
    cleanup_.push([dev, l = layout_] { vkDestroyPipelineLayout(dev, l, nullptr); });
    VkShaderModuleCreateInfo smi{VK_STRUCTURE_TYPE_SHADER_MODULE_CREATE_INFO};
    smi.codeSize = sizeof(kSpirv_point_lookup_comp);
    smi.pCode = kSpirv_point_lookup_comp;
    VkShaderModule module;
    vkCheck(vkCreateShaderModule(dev, &smi, nullptr, &module), "vkCreateShaderModule");
    cleanup_.push([dev, module] { vkDestroyShaderModule(dev, module, nullptr); });
    VkComputePipelineCreateInfo cpi{VK_STRUCTURE_TYPE_COMPUTE_PIPELINE_CREATE_INFO};
    cpi.stage = {VK_STRUCTURE_TYPE_PIPELINE_SHADER_STAGE_CREATE_INFO};
    cpi.stage.stage = VK_SHADER_STAGE_COMPUTE_BIT;
    cpi.stage.module = module;
    cpi.stage.pName = "main";
    cpi.layout = layout_;
    vkCheck(vkCreateComputePipelines(dev, VK_NULL_HANDLE, 1, &cpi, nullptr, &pipeline_),
            "vkCreateComputePipelines");
    cleanup_.push([dev, p = pipeline_] { vkDestroyPipeline(dev, p, nullptr); });

    const VkDescriptorPoolSize size{VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, 64};
    VkDescriptorPoolCreateInfo dpi{VK_STRUCTURE_TYPE_DESCRIPTOR_POOL_CREATE_INFO};
    dpi.maxSets = 8;
    dpi.poolSizeCount = 1;
    dpi.pPoolSizes = &size;
    vkCheck(vkCreateDescriptorPool(dev, &dpi, nullptr, &pool_), "vkCreateDescriptorPool");
    cleanup_.push([dev, p = pool_] { vkDestroyDescriptorPool(dev, p, nullptr); });

    const VkMemoryPropertyFlags host =
        VK_MEMORY_PROPERTY_HOST_VISIBLE_BIT | VK_MEMORY_PROPERTY_HOST_COHERENT_BIT;
    const VkDeviceSize bytes = sizeof(PointNormal) * pts.size();
    points_ = ctx_.createBuffer(bytes, VK_BUFFER_USAGE_STORAGE_BUFFER_BIT, host, cleanup_);
    results_ = ctx_.createBuffer(16 * pts.size(), VK_BUFFER_USAGE_STORAGE_BUFFER_BIT, host, cleanup_);
    void* mapped = nullptr;
    vkCheck(vkMapMemory(dev, points_.memory, 0, VK_WHOLE_SIZE, 0, &mapped), "vkMapMemory");
    std::memcpy(mapped, pts.data(), size_t(bytes));
    vkUnmapMemory(dev, points_.memory);
    ioSet_ = allocateSet(setLayouts_[1]);
    VkDescriptorBufferInfo infos[2] = {{points_.buffer, 0, VK_WHOLE_SIZE},
                                       {results_.buffer, 0, VK_WHOLE_SIZE}};
    VkWriteDescriptorSet writes[2];
    for (uint32_t i = 0; i < 2; ++i) {
      writes[i] = VkWriteDescriptorSet{VK_STRUCTURE_TYPE_WRITE_DESCRIPTOR_SET};
      writes[i].dstSet = ioSet_;
      writes[i].dstBinding = i;
      writes[i].descriptorCount = 1;
      writes[i].descriptorType = VK_DESCRIPTOR_TYPE_STORAGE_BUFFER;
      writes[i].pBufferInfo = &infos[i];
    }
    vkUpdateDescriptorSets(dev, 2, writes, 0, nullptr);
  }
  ~PointLookup() {
    for (VulkanLevelBuffers& b : uploads_) destroyLevelBuffers(ctx_.device(), b);
    cleanup_.run();
  }

  VkDevice device() const { return ctx_.device(); }
  const VulkanContext& context() const { return ctx_; }

  // Uploads `level` (with `query`'s acceleration data); returns its index for run().
  size_t upload(const Level& level, const ProbeQuery& query) {
    VulkanLevelBuffers b;
    std::string error;
    const VkResult r =
        uploadLevelBuffers(ctx_.physicalDevice(), ctx_.device(), ctx_.queue(), ctx_.commandPool(), level,
                           query.startGrid(), query.outerCells(), query.cellGrid(), b, &error);
    if (r != VK_SUCCESS) throw std::runtime_error("upload: " + error);
    uploads_.push_back(b);
    sets_.push_back(allocateSet(setLayouts_[0]));
    writeLevelDescriptors(ctx_.device(), sets_.back(), 0, b);
    return uploads_.size() - 1;
  }
  const VulkanLevelBuffers& buffers(size_t i) const { return uploads_[i]; }

  // writeLevelSh (staged, waited for) of level.sh[first, first + count) into upload i.
  VkResult writeSh(size_t i, const Level& level, size_t first, size_t count, std::string* error) {
    return writeLevelSh(ctx_.physicalDevice(), ctx_.device(), ctx_.queue(), ctx_.commandPool(), uploads_[i],
                        level, first, count, error);
  }

  // One submission: `record` (if any: e.g. an SH update), then the lookup of every point against upload i.
  std::vector<glm::vec3> run(size_t i, const std::function<void(VkCommandBuffer)>& record = {}) {
    const VkDevice dev = ctx_.device();
    submitAndWait(ctx_, [&](VkCommandBuffer cmd) {
      if (record) record(cmd);
      vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_COMPUTE, pipeline_);
      const VkDescriptorSet sets[2] = {sets_[i], ioSet_};
      vkCmdBindDescriptorSets(cmd, VK_PIPELINE_BIND_POINT_COMPUTE, layout_, 0, 2, sets, 0, nullptr);
      vkCmdPushConstants(cmd, layout_, VK_SHADER_STAGE_COMPUTE_BIT, 0, sizeof(uint32_t), &count_);
      vkCmdDispatch(cmd, (count_ + 63) / 64, 1, 1);
      VkMemoryBarrier toHost{VK_STRUCTURE_TYPE_MEMORY_BARRIER};
      toHost.srcAccessMask = VK_ACCESS_SHADER_WRITE_BIT;
      toHost.dstAccessMask = VK_ACCESS_HOST_READ_BIT;
      vkCmdPipelineBarrier(cmd, VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT, VK_PIPELINE_STAGE_HOST_BIT, 0, 1,
                           &toHost, 0, nullptr, 0, nullptr);
    });
    std::vector<glm::vec3> out(count_);
    void* mapped = nullptr;
    vkCheck(vkMapMemory(dev, results_.memory, 0, VK_WHOLE_SIZE, 0, &mapped), "vkMapMemory");
    const auto* f = static_cast<const float*>(mapped);
    for (size_t k = 0; k < count_; ++k) out[k] = glm::vec3(f[4 * k], f[4 * k + 1], f[4 * k + 2]);
    vkUnmapMemory(dev, results_.memory);
    return out;
  }

 private:
  VkDescriptorSetLayout setLayout(const VkDescriptorSetLayoutBinding* b, uint32_t n) {
    VkDescriptorSetLayoutCreateInfo info{VK_STRUCTURE_TYPE_DESCRIPTOR_SET_LAYOUT_CREATE_INFO};
    info.bindingCount = n;
    info.pBindings = b;
    VkDescriptorSetLayout l;
    const VkDevice dev = ctx_.device();
    vkCheck(vkCreateDescriptorSetLayout(dev, &info, nullptr, &l), "vkCreateDescriptorSetLayout");
    cleanup_.push([dev, l] { vkDestroyDescriptorSetLayout(dev, l, nullptr); });
    return l;
  }
  VkDescriptorSet allocateSet(VkDescriptorSetLayout l) {
    VkDescriptorSetAllocateInfo info{VK_STRUCTURE_TYPE_DESCRIPTOR_SET_ALLOCATE_INFO};
    info.descriptorPool = pool_;
    info.descriptorSetCount = 1;
    info.pSetLayouts = &l;
    VkDescriptorSet s;
    vkCheck(vkAllocateDescriptorSets(ctx_.device(), &info, &s), "vkAllocateDescriptorSets");
    return s;
  }

  VulkanContext ctx_;
  CleanupStack cleanup_;
  uint32_t count_;
  VkDescriptorSetLayout setLayouts_[2] = {};
  VkPipelineLayout layout_ = VK_NULL_HANDLE;
  VkPipeline pipeline_ = VK_NULL_HANDLE;
  VkDescriptorPool pool_ = VK_NULL_HANDLE;
  GpuBuffer points_, results_;
  VkDescriptorSet ioSet_ = VK_NULL_HANDLE;
  std::vector<VulkanLevelBuffers> uploads_;
  std::vector<VkDescriptorSet> sets_;
};

// Largest relative difference per channel (denominator at least 1e-6 W/m^2).
inline double worstRelative(const std::vector<glm::vec3>& a, const std::vector<glm::vec3>& b) {
  double worst = 0.0;
  for (size_t i = 0; i < a.size(); ++i)
    for (int c = 0; c < 3; ++c)
      worst =
          std::max(worst, std::abs(double(a[i][c]) - b[i][c]) / std::max(std::abs(double(b[i][c])), 1e-6));
  return worst;
}

inline size_t countDifferent(const std::vector<glm::vec3>& a, const std::vector<glm::vec3>& b) {
  size_t n = 0;
  for (size_t i = 0; i < a.size(); ++i) n += a[i] != b[i];
  return n;
}

}  // namespace tetraprobe::test
