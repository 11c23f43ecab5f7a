// surface_lighting: the sample's deferred lighting pass through tetraprobe.glsl (surface_lighting.h).
// The shader is compiled at build time (CMakeLists.txt: glslangValidator with TETRAPROBE_SHADER_DIR on the
// include path) into surface_lighting_comp.h. What an engine adds to its own pass is only this: set 0 laid
// out with levelDescriptorBindings and written with writeLevelDescriptors, and the pipeline specialized
// with shaderSpecialization(variant).
#include "surface_lighting.h"

#include <algorithm>

#include "surface_lighting_comp.h"  // kSurfaceLightingComp: SPIR-V words

using namespace tetraprobe;

namespace {
constexpr uint32_t kMaxLevels = 4;
}

SurfaceLighting::~SurfaceLighting() {
  if (!e_) return;
  VkDevice d = e_->device;
  vkDeviceWaitIdle(d);
  for (VkPipeline p : pipelines_) vkDestroyPipeline(d, p, nullptr);
  if (descriptorPool_) vkDestroyDescriptorPool(d, descriptorPool_, nullptr);
  if (module_) vkDestroyShaderModule(d, module_, nullptr);
  if (pipelineLayout_) vkDestroyPipelineLayout(d, pipelineLayout_, nullptr);
  if (pointsLayout_) vkDestroyDescriptorSetLayout(d, pointsLayout_, nullptr);
  if (levelLayout_) vkDestroyDescriptorSetLayout(d, levelLayout_, nullptr);
  const auto destroy = [d](Buffer& b) {
    if (b.buffer) vkDestroyBuffer(d, b.buffer, nullptr);
    if (b.memory) vkFreeMemory(d, b.memory, nullptr);
  };
  destroy(points_);
  for (Buffer& b : outputs_) destroy(b);
}

bool SurfaceLighting::makeBuffer(VkDeviceSize size, Buffer& out) {
  VkBufferCreateInfo bci{VK_STRUCTURE_TYPE_BUFFER_CREATE_INFO};
  bci.size = size;
  bci.usage = VK_BUFFER_USAGE_STORAGE_BUFFER_BIT;
  if (vkCreateBuffer(e_->device, &bci, nullptr, &out.buffer) != VK_SUCCESS) return false;
  const VkMemoryAllocateInfo alloc = hostAllocation(*e_, out.buffer);
  return alloc.memoryTypeIndex != UINT32_MAX &&
         vkAllocateMemory(e_->device, &alloc, nullptr, &out.memory) == VK_SUCCESS &&
         vkBindBufferMemory(e_->device, out.buffer, out.memory, 0) == VK_SUCCESS &&
         vkMapMemory(e_->device, out.memory, 0, VK_WHOLE_SIZE, 0, &out.mapped) == VK_SUCCESS;
}

bool SurfaceLighting::init(Engine& e, uint32_t capacity, uint32_t outputs, std::string* error) {
  e_ = &e;
  capacity_ = capacity;
  const auto fail = [&](const char* what) {
    if (error) *error = std::string("surface lighting: ") + what;
    return false;
  };
  // Set 0: the level's six read-only storage buffers, as tetraprobe.glsl declares them.
  VkDescriptorSetLayoutBinding level[kGpuBindingCount];
  levelDescriptorBindings(VK_SHADER_STAGE_COMPUTE_BIT, 0, level);
  VkDescriptorSetLayoutCreateInfo lci{VK_STRUCTURE_TYPE_DESCRIPTOR_SET_LAYOUT_CREATE_INFO};
  lci.bindingCount = kGpuBindingCount;
  lci.pBindings = level;
  if (vkCreateDescriptorSetLayout(e.device, &lci, nullptr, &levelLayout_) != VK_SUCCESS)
    return fail("vkCreateDescriptorSetLayout (level)");
  // Set 1: the engine's own, points in and irradiance out.
  VkDescriptorSetLayoutBinding own[2] = {};
  for (uint32_t b = 0; b < 2; ++b) {
    own[b].binding = b;
    own[b].descriptorType = VK_DESCRIPTOR_TYPE_STORAGE_BUFFER;
    own[b].descriptorCount = 1;
    own[b].stageFlags = VK_SHADER_STAGE_COMPUTE_BIT;
  }
  lci.bindingCount = 2;
  lci.pBindings = own;
  if (vkCreateDescriptorSetLayout(e.device, &lci, nullptr, &pointsLayout_) != VK_SUCCESS)
    return fail("vkCreateDescriptorSetLayout (points)");
  const VkDescriptorSetLayout sets[2] = {levelLayout_, pointsLayout_};
  const VkPushConstantRange push{VK_SHADER_STAGE_COMPUTE_BIT, 0, sizeof(uint32_t)};
  VkPipelineLayoutCreateInfo pli{VK_STRUCTURE_TYPE_PIPELINE_LAYOUT_CREATE_INFO};
  pli.setLayoutCount = 2;
  pli.pSetLayouts = sets;
  pli.pushConstantRangeCount = 1;
  pli.pPushConstantRanges = &push;
  if (vkCreatePipelineLayout(e.device, &pli, nullptr, &pipelineLayout_) != VK_SUCCESS)
    return fail("vkCreatePipelineLayout");
  VkShaderModuleCreateInfo smi{VK_STRUCTURE_TYPE_SHADER_MODULE_CREATE_INFO};
  smi.codeSize = sizeof(kSurfaceLightingComp);
  smi.pCode = kSurfaceLightingComp;
  if (vkCreateShaderModule(e.device, &smi, nullptr, &module_) != VK_SUCCESS)
    return fail("vkCreateShaderModule");
  const VkDescriptorPoolSize sizes{VK_DESCRIPTOR_TYPE_STORAGE_BUFFER,
                                   2 * outputs + kMaxLevels * uint32_t(kGpuBindingCount)};
  VkDescriptorPoolCreateInfo dpi{VK_STRUCTURE_TYPE_DESCRIPTOR_POOL_CREATE_INFO};
  dpi.maxSets = outputs + kMaxLevels;
  dpi.poolSizeCount = 1;
  dpi.pPoolSizes = &sizes;
  if (vkCreateDescriptorPool(e.device, &dpi, nullptr, &descriptorPool_) != VK_SUCCESS)
    return fail("vkCreateDescriptorPool");
  if (!makeBuffer(VkDeviceSize(capacity) * 2 * sizeof(glm::vec4), points_)) return fail("points buffer");
  outputs_.resize(outputs);
  outputSets_.resize(outputs);
  for (uint32_t o = 0; o < outputs; ++o) {
    if (!makeBuffer(VkDeviceSize(capacity) * sizeof(glm::vec4), outputs_[o])) return fail("output buffer");
    VkDescriptorSetAllocateInfo ai{VK_STRUCTURE_TYPE_DESCRIPTOR_SET_ALLOCATE_INFO};
    ai.descriptorPool = descriptorPool_;
    ai.descriptorSetCount = 1;
    ai.pSetLayouts = &pointsLayout_;
    if (vkAllocateDescriptorSets(e.device, &ai, &outputSets_[o]) != VK_SUCCESS)
      return fail("vkAllocateDescriptorSets (points)");
    const VkDescriptorBufferInfo infos[2] = {{points_.buffer, 0, VK_WHOLE_SIZE},
                                             {outputs_[o].buffer, 0, VK_WHOLE_SIZE}};
    VkWriteDescriptorSet w[2] = {};
    for (uint32_t b = 0; b < 2; ++b) {
      w[b].sType = VK_STRUCTURE_TYPE_WRITE_DESCRIPTOR_SET;
      w[b].dstSet = outputSets_[o];
      w[b].dstBinding = b;
      w[b].descriptorCount = 1;
      w[b].descriptorType = VK_DESCRIPTOR_TYPE_STORAGE_BUFFER;
      w[b].pBufferInfo = &infos[b];
    }
    vkUpdateDescriptorSets(e.device, 2, w, 0, nullptr);
  }
  return true;
}

int SurfaceLighting::addLevel(const ShaderVariant& variant, const VulkanLevelBuffers& buffers,
                              std::string* error) {
  if (pipelines_.size() == kMaxLevels) {
    if (error) *error = "surface lighting: too many levels";
    return -1;
  }
  // The same SPIR-V for every level: the variant's specialization constants turn off what the level does not
  // use and fold its tet packing.
  ShaderSpecialization spec;
  shaderSpecialization(variant, 0, spec);
  VkComputePipelineCreateInfo ci{VK_STRUCTURE_TYPE_COMPUTE_PIPELINE_CREATE_INFO};
  ci.stage.sType = VK_STRUCTURE_TYPE_PIPELINE_SHADER_STAGE_CREATE_INFO;
  ci.stage.stage = VK_SHADER_STAGE_COMPUTE_BIT;
  ci.stage.module = module_;
  ci.stage.pName = "main";
  ci.stage.pSpecializationInfo = &spec.info;
  ci.layout = pipelineLayout_;
  VkPipeline pipeline = VK_NULL_HANDLE;
  if (vkCreateComputePipelines(e_->device, VK_NULL_HANDLE, 1, &ci, nullptr, &pipeline) != VK_SUCCESS) {
    if (error) *error = "surface lighting: vkCreateComputePipelines";
    return -1;
  }
  pipelines_.push_back(pipeline);
  VkDescriptorSetAllocateInfo ai{VK_STRUCTURE_TYPE_DESCRIPTOR_SET_ALLOCATE_INFO};
  ai.descriptorPool = descriptorPool_;
  ai.descriptorSetCount = 1;
  ai.pSetLayouts = &levelLayout_;
  VkDescriptorSet set = VK_NULL_HANDLE;
  if (vkAllocateDescriptorSets(e_->device, &ai, &set) != VK_SUCCESS) {
    if (error) *error = "surface lighting: vkAllocateDescriptorSets (level)";
    return -1;
  }
  writeLevelDescriptors(e_->device, set, 0, buffers);
  levelSets_.push_back(set);
  return int(pipelines_.size()) - 1;
}

void SurfaceLighting::setPoints(const std::vector<SurfacePoint>& points) {
  count_ = uint32_t(std::min<size_t>(points.size(), capacity_));
  auto* out = static_cast<glm::vec4*>(points_.mapped);
  for (uint32_t i = 0; i < count_; ++i) {
    out[2 * i] = glm::vec4(points[i].local, points[i].sky ? 0.0f : 1.0f);
    out[2 * i + 1] = glm::vec4(points[i].normal, 0.0f);
  }
}

void SurfaceLighting::cmdShade(VkCommandBuffer cmd, int level, uint32_t output) const {
  vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_COMPUTE, pipelines_[size_t(level)]);
  const VkDescriptorSet sets[2] = {levelSets_[size_t(level)], outputSets_[output]};
  vkCmdBindDescriptorSets(cmd, VK_PIPELINE_BIND_POINT_COMPUTE, pipelineLayout_, 0, 2, sets, 0, nullptr);
  vkCmdPushConstants(cmd, pipelineLayout_, VK_SHADER_STAGE_COMPUTE_BIT, 0, sizeof(uint32_t), &count_);
  vkCmdDispatch(cmd, (count_ + 63) / 64, 1, 1);
  VkMemoryBarrier toHost{VK_STRUCTURE_TYPE_MEMORY_BARRIER};
  toHost.srcAccessMask = VK_ACCESS_SHADER_WRITE_BIT;
  toHost.dstAccessMask = VK_ACCESS_HOST_READ_BIT;
  vkCmdPipelineBarrier(cmd, VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT, VK_PIPELINE_STAGE_HOST_BIT, 0, 1, &toHost,
                       0, nullptr, 0, nullptr);
}

const glm::vec4* SurfaceLighting::results(uint32_t output) const {
  return static_cast<const glm::vec4*>(outputs_[output].mapped);
}
