// Render passes and pipelines of the headless renderer (pipelines.h): fixed-function state for the G-buffer,
// shadow-map and probe-dot rasters, and compute pipelines, from the SPIR-V embedded at build time.
#include "pipelines.h"

#include "gbuffer.frag.h"
#include "gbuffer.vert.h"
#include "probe_dots.frag.h"
#include "probe_dots.vert.h"
#include "shadow_depth.vert.h"

namespace tetraprobe::render_detail {
namespace {

VkRenderPass makePass(VkDevice device, const VkRenderPassCreateInfo& info, CleanupStack& cleanup) {
  VkRenderPass pass;
  vkCheck(vkCreateRenderPass(device, &info, nullptr, &pass), "vkCreateRenderPass");
  cleanup.push([device, pass] { vkDestroyRenderPass(device, pass, nullptr); });
  return pass;
}

VkAttachmentDescription attachment(VkFormat format, VkAttachmentLoadOp load, VkAttachmentStoreOp store,
                                   VkImageLayout initial, VkImageLayout final) {
  VkAttachmentDescription a{};
  a.format = format;
  a.samples = VK_SAMPLE_COUNT_1_BIT;
  a.loadOp = load;
  a.storeOp = store;
  a.stencilLoadOp = VK_ATTACHMENT_LOAD_OP_DONT_CARE;
  a.stencilStoreOp = VK_ATTACHMENT_STORE_OP_DONT_CARE;
  a.initialLayout = initial;
  a.finalLayout = final;
  return a;
}

// The fixed-function state every raster here shares, filled in by makeGraphics from a few choices.
struct RasterChoices {
  const uint32_t* vert;
  size_t vertBytes;
  const uint32_t* frag;  // nullptr: depth only
  size_t fragBytes;
  uint32_t vertexAttributes;  // of Vertex, from location 0 (0: no vertex input)
  uint32_t width, height;
  VkCullModeFlags cull;
  bool depthWrite;
  VkCompareOp compare;
  bool depthBias;
  uint32_t colorOutputs;
};

VkPipeline makeGraphics(VkDevice device, VkRenderPass pass, VkPipelineLayout layout, const RasterChoices& c,
                        CleanupStack& cleanup) {
  VkPipelineShaderStageCreateInfo stages[2] = {};
  stages[0].sType = stages[1].sType = VK_STRUCTURE_TYPE_PIPELINE_SHADER_STAGE_CREATE_INFO;
  stages[0].stage = VK_SHADER_STAGE_VERTEX_BIT;
  stages[0].module = createShader(device, c.vert, c.vertBytes, cleanup);
  stages[0].pName = "main";
  if (c.frag) {
    stages[1].stage = VK_SHADER_STAGE_FRAGMENT_BIT;
    stages[1].module = createShader(device, c.frag, c.fragBytes, cleanup);
    stages[1].pName = "main";
  }
  const VkVertexInputBindingDescription binding{0, sizeof(Vertex), VK_VERTEX_INPUT_RATE_VERTEX};
  const VkVertexInputAttributeDescription attrs[4] = {
      {0, 0, VK_FORMAT_R32G32B32_SFLOAT, offsetof(Vertex, position)},
      {1, 0, VK_FORMAT_R32G32B32_SFLOAT, offsetof(Vertex, normal)},
      {2, 0, VK_FORMAT_R32G32B32_SFLOAT, offsetof(Vertex, albedo)},
      {3, 0, VK_FORMAT_R32G32B32_SFLOAT, offsetof(Vertex, emission)}};
  VkPipelineVertexInputStateCreateInfo vertexInput{VK_STRUCTURE_TYPE_PIPELINE_VERTEX_INPUT_STATE_CREATE_INFO};
  if (c.vertexAttributes > 0) {
    vertexInput.vertexBindingDescriptionCount = 1;
    vertexInput.pVertexBindingDescriptions = &binding;
    vertexInput.vertexAttributeDescriptionCount = c.vertexAttributes;
    vertexInput.pVertexAttributeDescriptions = attrs;
  }
  VkPipelineInputAssemblyStateCreateInfo assembly{
      VK_STRUCTURE_TYPE_PIPELINE_INPUT_ASSEMBLY_STATE_CREATE_INFO};
  assembly.topology = VK_PRIMITIVE_TOPOLOGY_TRIANGLE_LIST;
  const VkViewport viewport{0, 0, float(c.width), float(c.height), 0, 1};
  const VkRect2D scissor{{0, 0}, {c.width, c.height}};
  VkPipelineViewportStateCreateInfo viewportState{VK_STRUCTURE_TYPE_PIPELINE_VIEWPORT_STATE_CREATE_INFO};
  viewportState.viewportCount = 1;
  viewportState.pViewports = &viewport;
  viewportState.scissorCount = 1;
  viewportState.pScissors = &scissor;
  // The camera projection flips y (row 0 = top), so counter-clockwise as seen by the viewer stays so.
  VkPipelineRasterizationStateCreateInfo raster{VK_STRUCTURE_TYPE_PIPELINE_RASTERIZATION_STATE_CREATE_INFO};
  raster.polygonMode = VK_POLYGON_MODE_FILL;
  raster.cullMode = c.cull;
  raster.frontFace = VK_FRONT_FACE_COUNTER_CLOCKWISE;
  raster.lineWidth = 1.0f;
  if (c.depthBias) {
    raster.depthBiasEnable = VK_TRUE;
    raster.depthBiasConstantFactor = 0.0f;
    raster.depthBiasSlopeFactor = 1.5f;
  }
  VkPipelineMultisampleStateCreateInfo multisample{VK_STRUCTURE_TYPE_PIPELINE_MULTISAMPLE_STATE_CREATE_INFO};
  multisample.rasterizationSamples = VK_SAMPLE_COUNT_1_BIT;
  VkPipelineDepthStencilStateCreateInfo depth{VK_STRUCTURE_TYPE_PIPELINE_DEPTH_STENCIL_STATE_CREATE_INFO};
  depth.depthTestEnable = VK_TRUE;
  depth.depthWriteEnable = c.depthWrite ? VK_TRUE : VK_FALSE;
  depth.depthCompareOp = c.compare;
  VkPipelineColorBlendAttachmentState blendAtt[4] = {};
  for (auto& b : blendAtt)
    b.colorWriteMask = VK_COLOR_COMPONENT_R_BIT | VK_COLOR_COMPONENT_G_BIT | VK_COLOR_COMPONENT_B_BIT |
                       VK_COLOR_COMPONENT_A_BIT;
  VkPipelineColorBlendStateCreateInfo blend{VK_STRUCTURE_TYPE_PIPELINE_COLOR_BLEND_STATE_CREATE_INFO};
  blend.attachmentCount = c.colorOutputs;
  blend.pAttachments = blendAtt;

  VkGraphicsPipelineCreateInfo info{VK_STRUCTURE_TYPE_GRAPHICS_PIPELINE_CREATE_INFO};
  info.stageCount = c.frag ? 2 : 1;
  info.pStages = stages;
  info.pVertexInputState = &vertexInput;
  info.pInputAssemblyState = &assembly;
  info.pViewportState = &viewportState;
  info.pRasterizationState = &raster;
  info.pMultisampleState = &multisample;
  info.pDepthStencilState = &depth;
  info.pColorBlendState = &blend;
  info.layout = layout;
  info.renderPass = pass;
  VkPipeline pipeline;
  vkCheck(vkCreateGraphicsPipelines(device, VK_NULL_HANDLE, 1, &info, nullptr, &pipeline),
          "vkCreateGraphicsPipelines");
  cleanup.push([device, pipeline] { vkDestroyPipeline(device, pipeline, nullptr); });
  return pipeline;
}

}  // namespace

VkRenderPass createGbufferPass(VkDevice device, CleanupStack& cleanup) {
  VkAttachmentDescription att[5];
  for (int i = 0; i < 4; ++i)
    att[i] = attachment(kGbufferFormat, VK_ATTACHMENT_LOAD_OP_CLEAR, VK_ATTACHMENT_STORE_OP_STORE,
                        VK_IMAGE_LAYOUT_UNDEFINED, VK_IMAGE_LAYOUT_GENERAL);
  att[4] = attachment(kDepthFormat, VK_ATTACHMENT_LOAD_OP_CLEAR, VK_ATTACHMENT_STORE_OP_STORE,
                      VK_IMAGE_LAYOUT_UNDEFINED, VK_IMAGE_LAYOUT_DEPTH_STENCIL_ATTACHMENT_OPTIMAL);
  VkAttachmentReference colorRefs[4];
  for (uint32_t i = 0; i < 4; ++i) colorRefs[i] = {i, VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL};
  VkAttachmentReference depthRef{4, VK_IMAGE_LAYOUT_DEPTH_STENCIL_ATTACHMENT_OPTIMAL};
  VkSubpassDescription subpass{};
  subpass.pipelineBindPoint = VK_PIPELINE_BIND_POINT_GRAPHICS;
  subpass.colorAttachmentCount = 4;
  subpass.pColorAttachments = colorRefs;
  subpass.pDepthStencilAttachment = &depthRef;
  // The G-buffer writes become visible to the compute passes, the copies and the probe-dot depth test.
  VkSubpassDependency dep{};
  dep.srcSubpass = 0;
  dep.dstSubpass = VK_SUBPASS_EXTERNAL;
  dep.srcStageMask =
      VK_PIPELINE_STAGE_COLOR_ATTACHMENT_OUTPUT_BIT | VK_PIPELINE_STAGE_LATE_FRAGMENT_TESTS_BIT;
  dep.dstStageMask = VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT | VK_PIPELINE_STAGE_TRANSFER_BIT |
                     VK_PIPELINE_STAGE_EARLY_FRAGMENT_TESTS_BIT;
  dep.srcAccessMask = VK_ACCESS_COLOR_ATTACHMENT_WRITE_BIT | VK_ACCESS_DEPTH_STENCIL_ATTACHMENT_WRITE_BIT;
  dep.dstAccessMask =
      VK_ACCESS_SHADER_READ_BIT | VK_ACCESS_TRANSFER_READ_BIT | VK_ACCESS_DEPTH_STENCIL_ATTACHMENT_READ_BIT;
  VkRenderPassCreateInfo info{VK_STRUCTURE_TYPE_RENDER_PASS_CREATE_INFO};
  info.attachmentCount = 5;
  info.pAttachments = att;
  info.subpassCount = 1;
  info.pSubpasses = &subpass;
  info.dependencyCount = 1;
  info.pDependencies = &dep;
  return makePass(device, info, cleanup);
}

VkRenderPass createShadowPass(VkDevice device, CleanupStack& cleanup) {
  const VkAttachmentDescription att =
      attachment(kDepthFormat, VK_ATTACHMENT_LOAD_OP_CLEAR, VK_ATTACHMENT_STORE_OP_STORE,
                 VK_IMAGE_LAYOUT_UNDEFINED, VK_IMAGE_LAYOUT_DEPTH_STENCIL_READ_ONLY_OPTIMAL);
  VkAttachmentReference depthRef{0, VK_IMAGE_LAYOUT_DEPTH_STENCIL_ATTACHMENT_OPTIMAL};
  VkSubpassDescription subpass{};
  subpass.pipelineBindPoint = VK_PIPELINE_BIND_POINT_GRAPHICS;
  subpass.pDepthStencilAttachment = &depthRef;
  VkSubpassDependency deps[2] = {};
  // The previous frame's sampling finishes before the layer is cleared; the depth reaches direct.comp.
  deps[0].srcSubpass = VK_SUBPASS_EXTERNAL;
  deps[0].dstSubpass = 0;
  deps[0].srcStageMask = VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT;
  deps[0].dstStageMask = VK_PIPELINE_STAGE_EARLY_FRAGMENT_TESTS_BIT;
  deps[0].dstAccessMask = VK_ACCESS_DEPTH_STENCIL_ATTACHMENT_WRITE_BIT;
  deps[1].srcSubpass = 0;
  deps[1].dstSubpass = VK_SUBPASS_EXTERNAL;
  deps[1].srcStageMask = VK_PIPELINE_STAGE_LATE_FRAGMENT_TESTS_BIT;
  deps[1].dstStageMask = VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT;
  deps[1].srcAccessMask = VK_ACCESS_DEPTH_STENCIL_ATTACHMENT_WRITE_BIT;
  deps[1].dstAccessMask = VK_ACCESS_SHADER_READ_BIT;
  VkRenderPassCreateInfo info{VK_STRUCTURE_TYPE_RENDER_PASS_CREATE_INFO};
  info.attachmentCount = 1;
  info.pAttachments = &att;
  info.subpassCount = 1;
  info.pSubpasses = &subpass;
  info.dependencyCount = 2;
  info.pDependencies = deps;
  return makePass(device, info, cleanup);
}

VkRenderPass createOverlayPass(VkDevice device, CleanupStack& cleanup) {
  const VkAttachmentDescription att[2] = {
      attachment(kGbufferFormat, VK_ATTACHMENT_LOAD_OP_LOAD, VK_ATTACHMENT_STORE_OP_STORE,
                 VK_IMAGE_LAYOUT_GENERAL, VK_IMAGE_LAYOUT_GENERAL),
      attachment(kDepthFormat, VK_ATTACHMENT_LOAD_OP_LOAD, VK_ATTACHMENT_STORE_OP_STORE,
                 VK_IMAGE_LAYOUT_DEPTH_STENCIL_ATTACHMENT_OPTIMAL,
                 VK_IMAGE_LAYOUT_DEPTH_STENCIL_ATTACHMENT_OPTIMAL)};
  VkAttachmentReference colorRef{0, VK_IMAGE_LAYOUT_GENERAL};
  VkAttachmentReference depthRef{1, VK_IMAGE_LAYOUT_DEPTH_STENCIL_ATTACHMENT_OPTIMAL};
  VkSubpassDescription subpass{};
  subpass.pipelineBindPoint = VK_PIPELINE_BIND_POINT_GRAPHICS;
  subpass.colorAttachmentCount = 1;
  subpass.pColorAttachments = &colorRef;
  subpass.pDepthStencilAttachment = &depthRef;
  VkSubpassDependency deps[2] = {};
  // debug_surface.comp's writes come before the dots are drawn over them; the dots reach the copies.
  deps[0].srcSubpass = VK_SUBPASS_EXTERNAL;
  deps[0].dstSubpass = 0;
  deps[0].srcStageMask = VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT;
  deps[0].dstStageMask = VK_PIPELINE_STAGE_COLOR_ATTACHMENT_OUTPUT_BIT;
  deps[0].srcAccessMask = VK_ACCESS_SHADER_WRITE_BIT;
  deps[0].dstAccessMask = VK_ACCESS_COLOR_ATTACHMENT_READ_BIT | VK_ACCESS_COLOR_ATTACHMENT_WRITE_BIT;
  deps[1].srcSubpass = 0;
  deps[1].dstSubpass = VK_SUBPASS_EXTERNAL;
  deps[1].srcStageMask = VK_PIPELINE_STAGE_COLOR_ATTACHMENT_OUTPUT_BIT;
  deps[1].dstStageMask = VK_PIPELINE_STAGE_TRANSFER_BIT;
  deps[1].srcAccessMask = VK_ACCESS_COLOR_ATTACHMENT_WRITE_BIT;
  deps[1].dstAccessMask = VK_ACCESS_TRANSFER_READ_BIT;
  VkRenderPassCreateInfo info{VK_STRUCTURE_TYPE_RENDER_PASS_CREATE_INFO};
  info.attachmentCount = 2;
  info.pAttachments = att;
  info.subpassCount = 1;
  info.pSubpasses = &subpass;
  info.dependencyCount = 2;
  info.pDependencies = deps;
  return makePass(device, info, cleanup);
}

VkFramebuffer createFramebuffer(VkDevice device, VkRenderPass pass, const VkImageView* views, uint32_t count,
                                uint32_t width, uint32_t height, CleanupStack& cleanup, const char* what) {
  VkFramebufferCreateInfo info{VK_STRUCTURE_TYPE_FRAMEBUFFER_CREATE_INFO};
  info.renderPass = pass;
  info.attachmentCount = count;
  info.pAttachments = views;
  info.width = width;
  info.height = height;
  info.layers = 1;
  VkFramebuffer fb;
  vkCheck(vkCreateFramebuffer(device, &info, nullptr, &fb), what);
  cleanup.push([device, fb] { vkDestroyFramebuffer(device, fb, nullptr); });
  return fb;
}

VkShaderModule createShader(VkDevice device, const uint32_t* code, size_t bytes, CleanupStack& cleanup) {
  VkShaderModuleCreateInfo info{VK_STRUCTURE_TYPE_SHADER_MODULE_CREATE_INFO};
  info.codeSize = bytes;
  info.pCode = code;
  VkShaderModule module;
  vkCheck(vkCreateShaderModule(device, &info, nullptr, &module), "vkCreateShaderModule");
  cleanup.push([device, module] { vkDestroyShaderModule(device, module, nullptr); });
  return module;
}

VkPipelineLayout createPipelineLayout(VkDevice device, const VkDescriptorSetLayout* sets, uint32_t setCount,
                                      VkShaderStageFlags pushStages, uint32_t pushBytes,
                                      CleanupStack& cleanup) {
  const VkPushConstantRange push{pushStages, 0, pushBytes};
  VkPipelineLayoutCreateInfo info{VK_STRUCTURE_TYPE_PIPELINE_LAYOUT_CREATE_INFO};
  info.setLayoutCount = setCount;
  info.pSetLayouts = sets;
  info.pushConstantRangeCount = 1;
  info.pPushConstantRanges = &push;
  VkPipelineLayout layout;
  vkCheck(vkCreatePipelineLayout(device, &info, nullptr, &layout), "vkCreatePipelineLayout");
  cleanup.push([device, layout] { vkDestroyPipelineLayout(device, layout, nullptr); });
  return layout;
}

VkDescriptorSetLayout createSetLayout(VkDevice device, const VkDescriptorSetLayoutBinding* bindings,
                                      uint32_t count, CleanupStack& cleanup) {
  VkDescriptorSetLayoutCreateInfo info{VK_STRUCTURE_TYPE_DESCRIPTOR_SET_LAYOUT_CREATE_INFO};
  info.bindingCount = count;
  info.pBindings = bindings;
  VkDescriptorSetLayout layout;
  vkCheck(vkCreateDescriptorSetLayout(device, &info, nullptr, &layout), "vkCreateDescriptorSetLayout");
  cleanup.push([device, layout] { vkDestroyDescriptorSetLayout(device, layout, nullptr); });
  return layout;
}

VkPipeline createGbufferPipeline(VkDevice device, VkRenderPass pass, VkPipelineLayout layout, uint32_t width,
                                 uint32_t height, CleanupStack& cleanup) {
  const RasterChoices c{kSpirv_gbuffer_vert,
                        sizeof(kSpirv_gbuffer_vert),
                        kSpirv_gbuffer_frag,
                        sizeof(kSpirv_gbuffer_frag),
                        4,
                        width,
                        height,
                        VK_CULL_MODE_BACK_BIT,
                        true,
                        VK_COMPARE_OP_LESS,
                        false,
                        4};
  return makeGraphics(device, pass, layout, c, cleanup);
}

VkPipeline createShadowPipeline(VkDevice device, VkRenderPass pass, VkPipelineLayout layout, uint32_t size,
                                CleanupStack& cleanup) {
  const RasterChoices c{kSpirv_shadow_depth_vert,
                        sizeof(kSpirv_shadow_depth_vert),
                        nullptr,
                        0,
                        1,
                        size,
                        size,
                        VK_CULL_MODE_NONE,
                        true,
                        VK_COMPARE_OP_LESS,
                        true,
                        0};
  return makeGraphics(device, pass, layout, c, cleanup);
}

VkPipeline createDotsPipeline(VkDevice device, VkRenderPass pass, VkPipelineLayout layout, uint32_t width,
                              uint32_t height, VkCompareOp compare, CleanupStack& cleanup) {
  const RasterChoices c{kSpirv_probe_dots_vert,
                        sizeof(kSpirv_probe_dots_vert),
                        kSpirv_probe_dots_frag,
                        sizeof(kSpirv_probe_dots_frag),
                        0,
                        width,
                        height,
                        VK_CULL_MODE_NONE,
                        false,
                        compare,
                        false,
                        1};
  return makeGraphics(device, pass, layout, c, cleanup);
}

VkPipeline createComputePipeline(VkDevice device, VkPipelineLayout layout, const uint32_t* code, size_t bytes,
                                 CleanupStack& cleanup, const VkSpecializationInfo* specialization) {
  VkComputePipelineCreateInfo info{VK_STRUCTURE_TYPE_COMPUTE_PIPELINE_CREATE_INFO};
  info.stage.sType = VK_STRUCTURE_TYPE_PIPELINE_SHADER_STAGE_CREATE_INFO;
  info.stage.stage = VK_SHADER_STAGE_COMPUTE_BIT;
  info.stage.module = createShader(device, code, bytes, cleanup);
  info.stage.pName = "main";
  info.stage.pSpecializationInfo = specialization;
  info.layout = layout;
  VkPipeline pipeline;
  vkCheck(vkCreateComputePipelines(device, VK_NULL_HANDLE, 1, &info, nullptr, &pipeline),
          "vkCreateComputePipelines");
  cleanup.push([device, pipeline] { vkDestroyPipeline(device, pipeline, nullptr); });
  return pipeline;
}

}  // namespace tetraprobe::render_detail
