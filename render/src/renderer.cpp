// Headless renderer: rasterizes a mesh into a G-buffer (local position, flat normal, albedo; RGBA32F +
// depth), lights each pixel in a compute pass through shaders/tetraprobe.glsl, and reads all four images
// back.
#include "tetraprobe/render/render.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstring>
#include <limits>
#include <stdexcept>
#include <string>

#include <glm/common.hpp>
#include <glm/geometric.hpp>
#include <glm/gtc/matrix_transform.hpp>
#include <glm/mat4x4.hpp>

#include "gbuffer.frag.h"
#include "gbuffer.vert.h"
#include "lighting.comp.h"
#include "lighting_grid.comp.h"
#include "tetraprobe/runtime/vulkan_upload.h"
#include "vulkan_context.h"

namespace tetraprobe {
namespace {

using render_detail::CleanupStack;
using render_detail::GpuBuffer;
using render_detail::GpuImage;
using render_detail::vkCheck;
using render_detail::VulkanContext;

constexpr VkFormat kGbufferFormat = VK_FORMAT_R32G32B32A32_SFLOAT;
constexpr VkFormat kDepthFormat = VK_FORMAT_D32_SFLOAT;
constexpr int kImageCount = 4;           // color, position, normal, albedo (readback order)
constexpr uint32_t kTimestampCount = 4;  // frame start, G-buffer done, warm-up done, lighting done

// One triangle-soup vertex, as gbuffer.vert reads it (locations 0, 1, 2).
struct Vertex {
  glm::vec3 position;  // level local frame
  glm::vec3 normal;    // the triangle's unit normal
  glm::vec3 albedo;
};
static_assert(sizeof(Vertex) == 36, "gbuffer.vert vertex stride");

struct LightingPush {
  int32_t size[2];
  int32_t mode;
};
static_assert(sizeof(LightingPush) == 12, "lighting.comp push constants");

// Expands the indexed mesh into a soup in the local frame (world - origin in double), with flat normals
// computed in double from the world positions.
std::vector<Vertex> buildSoup(const RenderMesh& mesh, const glm::dvec3& origin, glm::dvec3* lo,
                              glm::dvec3* hi) {
  std::vector<Vertex> soup;
  soup.reserve(mesh.triangles.size() * 3);
  *lo = glm::dvec3(std::numeric_limits<double>::max());
  *hi = -*lo;
  for (size_t t = 0; t < mesh.triangles.size(); ++t) {
    const glm::uvec3 tri = mesh.triangles[t];
    for (int k = 0; k < 3; ++k)
      if (tri[k] >= mesh.positions.size())
        throw std::runtime_error("render mesh: triangle " + std::to_string(t) + " has vertex index " +
                                 std::to_string(tri[k]) + " >= " + std::to_string(mesh.positions.size()) +
                                 " positions");
    const glm::dvec3 a(mesh.positions[tri[0]]), b(mesh.positions[tri[1]]), c(mesh.positions[tri[2]]);
    const glm::dvec3 cr = glm::cross(b - a, c - a);
    const double len = glm::length(cr);
    if (!(len > 0.0) || !std::isfinite(len)) continue;  // degenerate or non-finite: covers no pixel
    const glm::vec3 n(cr / len);
    const glm::vec3 albedo = t < mesh.triangleAlbedo.size() ? mesh.triangleAlbedo[t] : glm::vec3(0.8f);
    for (const glm::dvec3& p : {a, b, c}) {
      soup.push_back({glm::vec3(p - origin), n, albedo});
      *lo = glm::min(*lo, p);
      *hi = glm::max(*hi, p);
    }
  }
  return soup;
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

VkRenderPass createRenderPass(VkDevice device, CleanupStack& cleanup) {
  VkAttachmentDescription att[4] = {};
  for (int i = 0; i < 3; ++i) {
    att[i].format = kGbufferFormat;
    att[i].samples = VK_SAMPLE_COUNT_1_BIT;
    att[i].loadOp = VK_ATTACHMENT_LOAD_OP_CLEAR;
    att[i].storeOp = VK_ATTACHMENT_STORE_OP_STORE;
    att[i].stencilLoadOp = VK_ATTACHMENT_LOAD_OP_DONT_CARE;
    att[i].stencilStoreOp = VK_ATTACHMENT_STORE_OP_DONT_CARE;
    att[i].initialLayout = VK_IMAGE_LAYOUT_UNDEFINED;
    att[i].finalLayout = VK_IMAGE_LAYOUT_GENERAL;  // read by the compute pass, then copied
  }
  att[3].format = kDepthFormat;
  att[3].samples = VK_SAMPLE_COUNT_1_BIT;
  att[3].loadOp = VK_ATTACHMENT_LOAD_OP_CLEAR;
  att[3].storeOp = VK_ATTACHMENT_STORE_OP_DONT_CARE;
  att[3].stencilLoadOp = VK_ATTACHMENT_LOAD_OP_DONT_CARE;
  att[3].stencilStoreOp = VK_ATTACHMENT_STORE_OP_DONT_CARE;
  att[3].initialLayout = VK_IMAGE_LAYOUT_UNDEFINED;
  att[3].finalLayout = VK_IMAGE_LAYOUT_DEPTH_STENCIL_ATTACHMENT_OPTIMAL;
  VkAttachmentReference colorRefs[3] = {{0, VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL},
                                        {1, VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL},
                                        {2, VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL}};
  VkAttachmentReference depthRef{3, VK_IMAGE_LAYOUT_DEPTH_STENCIL_ATTACHMENT_OPTIMAL};
  VkSubpassDescription subpass{};
  subpass.pipelineBindPoint = VK_PIPELINE_BIND_POINT_GRAPHICS;
  subpass.colorAttachmentCount = 3;
  subpass.pColorAttachments = colorRefs;
  subpass.pDepthStencilAttachment = &depthRef;
  // The G-buffer writes become visible to the lighting pass (image loads) and to the readback copies.
  VkSubpassDependency dep{};
  dep.srcSubpass = 0;
  dep.dstSubpass = VK_SUBPASS_EXTERNAL;
  dep.srcStageMask = VK_PIPELINE_STAGE_COLOR_ATTACHMENT_OUTPUT_BIT;
  dep.dstStageMask = VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT | VK_PIPELINE_STAGE_TRANSFER_BIT;
  dep.srcAccessMask = VK_ACCESS_COLOR_ATTACHMENT_WRITE_BIT;
  dep.dstAccessMask = VK_ACCESS_SHADER_READ_BIT | VK_ACCESS_TRANSFER_READ_BIT;
  VkRenderPassCreateInfo info{VK_STRUCTURE_TYPE_RENDER_PASS_CREATE_INFO};
  info.attachmentCount = 4;
  info.pAttachments = att;
  info.subpassCount = 1;
  info.pSubpasses = &subpass;
  info.dependencyCount = 1;
  info.pDependencies = &dep;
  VkRenderPass pass;
  vkCheck(vkCreateRenderPass(device, &info, nullptr, &pass), "vkCreateRenderPass");
  cleanup.push([device, pass] { vkDestroyRenderPass(device, pass, nullptr); });
  return pass;
}

VkPipeline createGbufferPipeline(VkDevice device, VkRenderPass pass, VkPipelineLayout layout, uint32_t width,
                                 uint32_t height, CleanupStack& cleanup) {
  const VkShaderModule vert = createShader(device, kSpirv_gbuffer_vert, sizeof(kSpirv_gbuffer_vert), cleanup);
  const VkShaderModule frag = createShader(device, kSpirv_gbuffer_frag, sizeof(kSpirv_gbuffer_frag), cleanup);
  VkPipelineShaderStageCreateInfo stages[2] = {};
  stages[0].sType = stages[1].sType = VK_STRUCTURE_TYPE_PIPELINE_SHADER_STAGE_CREATE_INFO;
  stages[0].stage = VK_SHADER_STAGE_VERTEX_BIT;
  stages[0].module = vert;
  stages[0].pName = "main";
  stages[1].stage = VK_SHADER_STAGE_FRAGMENT_BIT;
  stages[1].module = frag;
  stages[1].pName = "main";

  const VkVertexInputBindingDescription binding{0, sizeof(Vertex), VK_VERTEX_INPUT_RATE_VERTEX};
  const VkVertexInputAttributeDescription attrs[3] = {
      {0, 0, VK_FORMAT_R32G32B32_SFLOAT, offsetof(Vertex, position)},
      {1, 0, VK_FORMAT_R32G32B32_SFLOAT, offsetof(Vertex, normal)},
      {2, 0, VK_FORMAT_R32G32B32_SFLOAT, offsetof(Vertex, albedo)}};
  VkPipelineVertexInputStateCreateInfo vertexInput{VK_STRUCTURE_TYPE_PIPELINE_VERTEX_INPUT_STATE_CREATE_INFO};
  vertexInput.vertexBindingDescriptionCount = 1;
  vertexInput.pVertexBindingDescriptions = &binding;
  vertexInput.vertexAttributeDescriptionCount = 3;
  vertexInput.pVertexAttributeDescriptions = attrs;
  VkPipelineInputAssemblyStateCreateInfo assembly{
      VK_STRUCTURE_TYPE_PIPELINE_INPUT_ASSEMBLY_STATE_CREATE_INFO};
  assembly.topology = VK_PRIMITIVE_TOPOLOGY_TRIANGLE_LIST;
  const VkViewport viewport{0, 0, float(width), float(height), 0, 1};
  const VkRect2D scissor{{0, 0}, {width, height}};
  VkPipelineViewportStateCreateInfo viewportState{VK_STRUCTURE_TYPE_PIPELINE_VIEWPORT_STATE_CREATE_INFO};
  viewportState.viewportCount = 1;
  viewportState.pViewports = &viewport;
  viewportState.scissorCount = 1;
  viewportState.pScissors = &scissor;
  // The projection flips y (row 0 = top), so counter-clockwise as seen by the viewer stays counter-clockwise.
  VkPipelineRasterizationStateCreateInfo raster{VK_STRUCTURE_TYPE_PIPELINE_RASTERIZATION_STATE_CREATE_INFO};
  raster.polygonMode = VK_POLYGON_MODE_FILL;
  raster.cullMode = VK_CULL_MODE_BACK_BIT;
  raster.frontFace = VK_FRONT_FACE_COUNTER_CLOCKWISE;
  raster.lineWidth = 1.0f;
  VkPipelineMultisampleStateCreateInfo multisample{VK_STRUCTURE_TYPE_PIPELINE_MULTISAMPLE_STATE_CREATE_INFO};
  multisample.rasterizationSamples = VK_SAMPLE_COUNT_1_BIT;
  VkPipelineDepthStencilStateCreateInfo depth{VK_STRUCTURE_TYPE_PIPELINE_DEPTH_STENCIL_STATE_CREATE_INFO};
  depth.depthTestEnable = VK_TRUE;
  depth.depthWriteEnable = VK_TRUE;
  depth.depthCompareOp = VK_COMPARE_OP_LESS;
  VkPipelineColorBlendAttachmentState blendAtt[3] = {};
  for (auto& b : blendAtt)
    b.colorWriteMask = VK_COLOR_COMPONENT_R_BIT | VK_COLOR_COMPONENT_G_BIT | VK_COLOR_COMPONENT_B_BIT |
                       VK_COLOR_COMPONENT_A_BIT;
  VkPipelineColorBlendStateCreateInfo blend{VK_STRUCTURE_TYPE_PIPELINE_COLOR_BLEND_STATE_CREATE_INFO};
  blend.attachmentCount = 3;
  blend.pAttachments = blendAtt;

  VkGraphicsPipelineCreateInfo info{VK_STRUCTURE_TYPE_GRAPHICS_PIPELINE_CREATE_INFO};
  info.stageCount = 2;
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

void imageBarrier(VkCommandBuffer cmd, VkImage image, VkImageLayout from, VkImageLayout to, VkAccessFlags src,
                  VkAccessFlags dst, VkPipelineStageFlags srcStage, VkPipelineStageFlags dstStage) {
  VkImageMemoryBarrier b{VK_STRUCTURE_TYPE_IMAGE_MEMORY_BARRIER};
  b.srcAccessMask = src;
  b.dstAccessMask = dst;
  b.oldLayout = from;
  b.newLayout = to;
  b.srcQueueFamilyIndex = b.dstQueueFamilyIndex = VK_QUEUE_FAMILY_IGNORED;
  b.image = image;
  b.subresourceRange = {VK_IMAGE_ASPECT_COLOR_BIT, 0, 1, 0, 1};
  vkCmdPipelineBarrier(cmd, srcStage, dstStage, 0, 0, nullptr, 0, nullptr, 1, &b);
}

// local frame -> Vulkan clip space: right-handed look-at, depth 0..1, y flipped so row 0 is the top.
glm::mat4 viewProjection(const RenderView& view, const glm::dvec3& origin, const glm::dvec3& lo,
                         const glm::dvec3& hi) {
  const glm::dvec3 eye = glm::dvec3(view.eye) - origin;
  const glm::dvec3 target = glm::dvec3(view.target) - origin;
  double farDist = 1.0;
  if (lo.x <= hi.x) {
    for (int i = 0; i < 8; ++i) {
      const glm::dvec3 corner((i & 1) ? hi.x : lo.x, (i & 2) ? hi.y : lo.y, (i & 4) ? hi.z : lo.z);
      farDist = std::max(farDist, glm::length(corner - origin - eye));
    }
  }
  farDist *= 1.01;
  const double nearDist = farDist * 1e-5;
  const glm::dmat4 v = glm::lookAtRH(eye, target, glm::dvec3(view.up));
  glm::dmat4 p = glm::perspectiveRH_ZO(glm::radians(double(view.fovYDeg)), double(view.width) / view.height,
                                       nearDist, farDist);
  p[1][1] *= -1.0;
  return glm::mat4(p * v);
}

// The grid's storage buffer header (shaders/lighting_grid.comp), 48 bytes.
struct GridHeader {
  float min[4];
  float step[4];
  int32_t dims[4];
};
static_assert(sizeof(GridHeader) == 48, "lighting_grid.comp header: vec4 min, vec4 step, ivec4 dims");

// The lighting pass reads either a level (tetraprobe.glsl, set 0 = the level's buffers) or a grid
// (lighting_grid.comp, set 0 binding 0 = one buffer).
RenderResult renderImpl(const RenderMesh& mesh, const glm::dvec3& origin, const Level* level,
                        const ProbeQuery* query, const RenderGrid* grid, const RenderView& view) {
  const auto t0 = std::chrono::steady_clock::now();
  if (view.width <= 0 || view.height <= 0 || view.width > 16384 || view.height > 16384)
    throw std::runtime_error("render: image size " + std::to_string(view.width) + "x" +
                             std::to_string(view.height) + " is outside 1..16384");
  if (!(view.fovYDeg > 0.0f && view.fovYDeg < 180.0f))
    throw std::runtime_error("render: fovYDeg must be in (0, 180)");
  if (glm::length(glm::cross(view.target - view.eye, view.up)) == 0.0f)
    throw std::runtime_error("render: eye, target and up must not be collinear");
  const uint32_t width = uint32_t(view.width), height = uint32_t(view.height);

  glm::dvec3 lo, hi;
  const std::vector<Vertex> soup = buildSoup(mesh, origin, &lo, &hi);
  const glm::mat4 viewProj = viewProjection(view, origin, lo, hi);

  VulkanContext ctx;
  const VkDevice device = ctx.device();
  CleanupStack cleanup;  // declared after ctx: runs first, while the device still exists

  const VkMemoryPropertyFlags hostMem =
      VK_MEMORY_PROPERTY_HOST_VISIBLE_BIT | VK_MEMORY_PROPERTY_HOST_COHERENT_BIT;
  // Level buffers, exactly as an engine would upload them; or the grid's one buffer.
  VulkanLevelBuffers levelBuffers;
  GpuBuffer gridBuffer;
  if (level) {
    std::string uploadError;
    if (uploadLevelBuffers(ctx.physicalDevice(), device, *level, query->startGrid(), query->outerCells(),
                           query->cellGrid(), levelBuffers, &uploadError) != VK_SUCCESS)
      throw std::runtime_error("render: level upload failed: " + uploadError);
    cleanup.push([device, &levelBuffers] { destroyLevelBuffers(device, levelBuffers); });
  } else {
    const size_t nodes = size_t(grid->dims.x) * size_t(grid->dims.y) * size_t(grid->dims.z);
    const VkDeviceSize bytes = sizeof(GridHeader) + nodes * sizeof(ShRgb);
    gridBuffer = ctx.createBuffer(bytes, VK_BUFFER_USAGE_STORAGE_BUFFER_BIT, hostMem, cleanup);
    GridHeader header{};
    const glm::vec3 localMin(grid->min - origin);
    for (int a = 0; a < 3; ++a) {
      header.min[a] = localMin[a];
      header.step[a] = float(grid->step);
      header.dims[a] = grid->dims[a];
    }
    void* mapped;
    vkCheck(vkMapMemory(device, gridBuffer.memory, 0, VK_WHOLE_SIZE, 0, &mapped), "vkMapMemory (grid)");
    std::memcpy(mapped, &header, sizeof header);
    std::memcpy(static_cast<char*>(mapped) + sizeof header, grid->sh, nodes * sizeof(ShRgb));
    vkUnmapMemory(device, gridBuffer.memory);
  }

  const VkDeviceSize vertexBytes = std::max<VkDeviceSize>(sizeof(Vertex), soup.size() * sizeof(Vertex));
  const GpuBuffer vertices =
      ctx.createBuffer(vertexBytes, VK_BUFFER_USAGE_VERTEX_BUFFER_BIT, hostMem, cleanup);
  {
    void* mapped;
    vkCheck(vkMapMemory(device, vertices.memory, 0, VK_WHOLE_SIZE, 0, &mapped), "vkMapMemory (vertices)");
    if (!soup.empty()) std::memcpy(mapped, soup.data(), soup.size() * sizeof(Vertex));
    vkUnmapMemory(device, vertices.memory);
  }

  // Images: 0 color (lighting output), 1 position, 2 normal, 3 albedo; plus depth.
  const VkImageUsageFlags gbufUsage =
      VK_IMAGE_USAGE_COLOR_ATTACHMENT_BIT | VK_IMAGE_USAGE_STORAGE_BIT | VK_IMAGE_USAGE_TRANSFER_SRC_BIT;
  GpuImage images[kImageCount];
  images[0] = ctx.createImage(width, height, kGbufferFormat,
                              VK_IMAGE_USAGE_STORAGE_BIT | VK_IMAGE_USAGE_TRANSFER_SRC_BIT,
                              VK_IMAGE_ASPECT_COLOR_BIT, cleanup);
  for (int i = 1; i < kImageCount; ++i)
    images[i] = ctx.createImage(width, height, kGbufferFormat, gbufUsage, VK_IMAGE_ASPECT_COLOR_BIT, cleanup);
  const GpuImage depth =
      ctx.createImage(width, height, kDepthFormat, VK_IMAGE_USAGE_DEPTH_STENCIL_ATTACHMENT_BIT,
                      VK_IMAGE_ASPECT_DEPTH_BIT, cleanup);
  const VkDeviceSize imageBytes = VkDeviceSize(width) * height * 4 * sizeof(float);
  GpuBuffer readback[kImageCount];
  for (auto& b : readback)
    b = ctx.createBuffer(imageBytes, VK_BUFFER_USAGE_TRANSFER_DST_BIT, hostMem, cleanup);

  // G-buffer pass.
  const VkRenderPass renderPass = createRenderPass(device, cleanup);
  VkFramebuffer framebuffer;
  {
    const VkImageView views[4] = {images[1].view, images[2].view, images[3].view, depth.view};
    VkFramebufferCreateInfo info{VK_STRUCTURE_TYPE_FRAMEBUFFER_CREATE_INFO};
    info.renderPass = renderPass;
    info.attachmentCount = 4;
    info.pAttachments = views;
    info.width = width;
    info.height = height;
    info.layers = 1;
    vkCheck(vkCreateFramebuffer(device, &info, nullptr, &framebuffer), "vkCreateFramebuffer");
    cleanup.push([device, framebuffer] { vkDestroyFramebuffer(device, framebuffer, nullptr); });
  }
  const VkPipelineLayout gbufferLayout =
      createPipelineLayout(device, nullptr, 0, VK_SHADER_STAGE_VERTEX_BIT, sizeof(glm::mat4), cleanup);
  const VkPipeline gbufferPipeline =
      createGbufferPipeline(device, renderPass, gbufferLayout, width, height, cleanup);

  // Lighting pass: set 0 = the level (vulkan_upload.h), set 1 = the G-buffer and output images.
  VkDescriptorSetLayoutBinding levelBindings[kGpuBindingCount];
  levelDescriptorBindings(VK_SHADER_STAGE_COMPUTE_BIT, 0, levelBindings);
  const uint32_t levelBindingCount = level ? uint32_t(kGpuBindingCount) : 1u;  // the grid: binding 0 only
  VkDescriptorSetLayoutBinding imageBindings[4];
  for (uint32_t i = 0; i < 4; ++i)
    imageBindings[i] = {i, VK_DESCRIPTOR_TYPE_STORAGE_IMAGE, 1, VK_SHADER_STAGE_COMPUTE_BIT, nullptr};
  const VkDescriptorSetLayout setLayouts[2] = {
      createSetLayout(device, levelBindings, levelBindingCount, cleanup),
      createSetLayout(device, imageBindings, 4, cleanup)};
  const VkPipelineLayout lightingLayout =
      createPipelineLayout(device, setLayouts, 2, VK_SHADER_STAGE_COMPUTE_BIT, sizeof(LightingPush), cleanup);
  VkPipeline lightingPipeline;
  {
    const VkShaderModule comp =
        level ? createShader(device, kSpirv_lighting_comp, sizeof(kSpirv_lighting_comp), cleanup)
              : createShader(device, kSpirv_lighting_grid_comp, sizeof(kSpirv_lighting_grid_comp), cleanup);
    VkComputePipelineCreateInfo info{VK_STRUCTURE_TYPE_COMPUTE_PIPELINE_CREATE_INFO};
    info.stage.sType = VK_STRUCTURE_TYPE_PIPELINE_SHADER_STAGE_CREATE_INFO;
    info.stage.stage = VK_SHADER_STAGE_COMPUTE_BIT;
    info.stage.module = comp;
    info.stage.pName = "main";
    info.layout = lightingLayout;
    vkCheck(vkCreateComputePipelines(device, VK_NULL_HANDLE, 1, &info, nullptr, &lightingPipeline),
            "vkCreateComputePipelines");
    cleanup.push([device, lightingPipeline] { vkDestroyPipeline(device, lightingPipeline, nullptr); });
  }
  VkDescriptorPool descriptorPool;
  {
    const VkDescriptorPoolSize sizes[2] = {{VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, levelBindingCount},
                                           {VK_DESCRIPTOR_TYPE_STORAGE_IMAGE, 4}};
    VkDescriptorPoolCreateInfo info{VK_STRUCTURE_TYPE_DESCRIPTOR_POOL_CREATE_INFO};
    info.maxSets = 2;
    info.poolSizeCount = 2;
    info.pPoolSizes = sizes;
    vkCheck(vkCreateDescriptorPool(device, &info, nullptr, &descriptorPool), "vkCreateDescriptorPool");
    cleanup.push([device, descriptorPool] { vkDestroyDescriptorPool(device, descriptorPool, nullptr); });
  }
  VkDescriptorSet sets[2];
  {
    VkDescriptorSetAllocateInfo info{VK_STRUCTURE_TYPE_DESCRIPTOR_SET_ALLOCATE_INFO};
    info.descriptorPool = descriptorPool;
    info.descriptorSetCount = 2;
    info.pSetLayouts = setLayouts;
    vkCheck(vkAllocateDescriptorSets(device, &info, sets), "vkAllocateDescriptorSets");
  }
  if (level) {
    writeLevelDescriptors(device, sets[0], 0, levelBuffers);
  } else {
    const VkDescriptorBufferInfo info{gridBuffer.buffer, 0, VK_WHOLE_SIZE};
    VkWriteDescriptorSet write{VK_STRUCTURE_TYPE_WRITE_DESCRIPTOR_SET};
    write.dstSet = sets[0];
    write.dstBinding = 0;
    write.descriptorCount = 1;
    write.descriptorType = VK_DESCRIPTOR_TYPE_STORAGE_BUFFER;
    write.pBufferInfo = &info;
    vkUpdateDescriptorSets(device, 1, &write, 0, nullptr);
  }
  {
    // Bindings 0..2 = position, normal, albedo; 3 = output color.
    const int order[4] = {1, 2, 3, 0};
    VkDescriptorImageInfo infos[4];
    VkWriteDescriptorSet writes[4];
    for (uint32_t i = 0; i < 4; ++i) {
      infos[i] = {VK_NULL_HANDLE, images[order[i]].view, VK_IMAGE_LAYOUT_GENERAL};
      writes[i] = VkWriteDescriptorSet{VK_STRUCTURE_TYPE_WRITE_DESCRIPTOR_SET};
      writes[i].dstSet = sets[1];
      writes[i].dstBinding = i;
      writes[i].descriptorCount = 1;
      writes[i].descriptorType = VK_DESCRIPTOR_TYPE_STORAGE_IMAGE;
      writes[i].pImageInfo = &infos[i];
    }
    vkUpdateDescriptorSets(device, 4, writes, 0, nullptr);
  }

  VkQueryPool queryPool = VK_NULL_HANDLE;
  const bool timestamps = ctx.timestampPeriodNs() > 0;
  if (timestamps) {
    VkQueryPoolCreateInfo info{VK_STRUCTURE_TYPE_QUERY_POOL_CREATE_INFO};
    info.queryType = VK_QUERY_TYPE_TIMESTAMP;
    info.queryCount = kTimestampCount;
    vkCheck(vkCreateQueryPool(device, &info, nullptr, &queryPool), "vkCreateQueryPool");
    cleanup.push([device, queryPool] { vkDestroyQueryPool(device, queryPool, nullptr); });
  }

  // Record: G-buffer pass, lighting dispatch, copies of all four images to host memory.
  VkCommandBuffer cmd;
  {
    VkCommandBufferAllocateInfo info{VK_STRUCTURE_TYPE_COMMAND_BUFFER_ALLOCATE_INFO};
    info.commandPool = ctx.commandPool();
    info.level = VK_COMMAND_BUFFER_LEVEL_PRIMARY;
    info.commandBufferCount = 1;
    vkCheck(vkAllocateCommandBuffers(device, &info, &cmd), "vkAllocateCommandBuffers");
    const VkCommandPool pool = ctx.commandPool();
    cleanup.push([device, pool, cmd] { vkFreeCommandBuffers(device, pool, 1, &cmd); });
  }
  VkCommandBufferBeginInfo begin{VK_STRUCTURE_TYPE_COMMAND_BUFFER_BEGIN_INFO};
  begin.flags = VK_COMMAND_BUFFER_USAGE_ONE_TIME_SUBMIT_BIT;
  vkCheck(vkBeginCommandBuffer(cmd, &begin), "vkBeginCommandBuffer");
  if (timestamps) {
    vkCmdResetQueryPool(cmd, queryPool, 0, kTimestampCount);
    vkCmdWriteTimestamp(cmd, VK_PIPELINE_STAGE_TOP_OF_PIPE_BIT, queryPool, 0);
  }
  {
    VkClearValue clears[4] = {};
    clears[3].depthStencil = {1.0f, 0};
    VkRenderPassBeginInfo info{VK_STRUCTURE_TYPE_RENDER_PASS_BEGIN_INFO};
    info.renderPass = renderPass;
    info.framebuffer = framebuffer;
    info.renderArea = {{0, 0}, {width, height}};
    info.clearValueCount = 4;
    info.pClearValues = clears;
    vkCmdBeginRenderPass(cmd, &info, VK_SUBPASS_CONTENTS_INLINE);
    if (!soup.empty()) {
      vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_GRAPHICS, gbufferPipeline);
      const VkDeviceSize offset = 0;
      vkCmdBindVertexBuffers(cmd, 0, 1, &vertices.buffer, &offset);
      vkCmdPushConstants(cmd, gbufferLayout, VK_SHADER_STAGE_VERTEX_BIT, 0, sizeof(glm::mat4), &viewProj);
      vkCmdDraw(cmd, uint32_t(soup.size()), 1, 0, 0);
    }
    vkCmdEndRenderPass(cmd);
  }
  if (timestamps) vkCmdWriteTimestamp(cmd, VK_PIPELINE_STAGE_BOTTOM_OF_PIPE_BIT, queryPool, 1);
  imageBarrier(cmd, images[0].image, VK_IMAGE_LAYOUT_UNDEFINED, VK_IMAGE_LAYOUT_GENERAL, 0,
               VK_ACCESS_SHADER_WRITE_BIT, VK_PIPELINE_STAGE_TOP_OF_PIPE_BIT,
               VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT);
  vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_COMPUTE, lightingPipeline);
  vkCmdBindDescriptorSets(cmd, VK_PIPELINE_BIND_POINT_COMPUTE, lightingLayout, 0, 2, sets, 0, nullptr);
  const int32_t mode = view.mode == RenderMode::kIndirect ? 1 : 0;
  // Warm-up: one workgroup (pixel 0,0 only). lavapipe JIT-compiles a pipeline at its first dispatch; this
  // keeps that compile out of the timed full-screen pass.
  const LightingPush warmup{{1, 1}, mode};
  vkCmdPushConstants(cmd, lightingLayout, VK_SHADER_STAGE_COMPUTE_BIT, 0, sizeof(warmup), &warmup);
  vkCmdDispatch(cmd, 1, 1, 1);
  imageBarrier(cmd, images[0].image, VK_IMAGE_LAYOUT_GENERAL, VK_IMAGE_LAYOUT_GENERAL,
               VK_ACCESS_SHADER_WRITE_BIT, VK_ACCESS_SHADER_WRITE_BIT, VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT,
               VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT);
  if (timestamps) vkCmdWriteTimestamp(cmd, VK_PIPELINE_STAGE_BOTTOM_OF_PIPE_BIT, queryPool, 2);
  const LightingPush push{{int32_t(width), int32_t(height)}, mode};
  vkCmdPushConstants(cmd, lightingLayout, VK_SHADER_STAGE_COMPUTE_BIT, 0, sizeof(push), &push);
  vkCmdDispatch(cmd, (width + 7) / 8, (height + 7) / 8, 1);
  imageBarrier(cmd, images[0].image, VK_IMAGE_LAYOUT_GENERAL, VK_IMAGE_LAYOUT_GENERAL,
               VK_ACCESS_SHADER_WRITE_BIT, VK_ACCESS_TRANSFER_READ_BIT, VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT,
               VK_PIPELINE_STAGE_TRANSFER_BIT);
  // After the barrier: lavapipe runs dispatches asynchronously and only a barrier waits for them.
  if (timestamps) vkCmdWriteTimestamp(cmd, VK_PIPELINE_STAGE_BOTTOM_OF_PIPE_BIT, queryPool, 3);
  for (int i = 0; i < kImageCount; ++i) {
    VkBufferImageCopy region{};
    region.imageSubresource = {VK_IMAGE_ASPECT_COLOR_BIT, 0, 0, 1};
    region.imageExtent = {width, height, 1};
    vkCmdCopyImageToBuffer(cmd, images[i].image, VK_IMAGE_LAYOUT_GENERAL, readback[i].buffer, 1, &region);
  }
  {
    VkMemoryBarrier b{VK_STRUCTURE_TYPE_MEMORY_BARRIER};
    b.srcAccessMask = VK_ACCESS_TRANSFER_WRITE_BIT;
    b.dstAccessMask = VK_ACCESS_HOST_READ_BIT;
    vkCmdPipelineBarrier(cmd, VK_PIPELINE_STAGE_TRANSFER_BIT, VK_PIPELINE_STAGE_HOST_BIT, 0, 1, &b, 0,
                         nullptr, 0, nullptr);
  }
  vkCheck(vkEndCommandBuffer(cmd), "vkEndCommandBuffer");

  VkFence fence;
  {
    VkFenceCreateInfo info{VK_STRUCTURE_TYPE_FENCE_CREATE_INFO};
    vkCheck(vkCreateFence(device, &info, nullptr, &fence), "vkCreateFence");
    cleanup.push([device, fence] { vkDestroyFence(device, fence, nullptr); });
  }
  VkSubmitInfo submit{VK_STRUCTURE_TYPE_SUBMIT_INFO};
  submit.commandBufferCount = 1;
  submit.pCommandBuffers = &cmd;
  vkCheck(vkQueueSubmit(ctx.queue(), 1, &submit, fence), "vkQueueSubmit");
  // Wait before anything can throw, so the cleanup never destroys objects in use.
  const VkResult waited = vkWaitForFences(device, 1, &fence, VK_TRUE, std::numeric_limits<uint64_t>::max());
  if (waited != VK_SUCCESS) vkDeviceWaitIdle(device);
  vkCheck(waited, "vkWaitForFences");

  RenderResult result;
  Image* outs[kImageCount] = {&result.color, &result.position, &result.normal, &result.albedo};
  for (int i = 0; i < kImageCount; ++i) {
    Image& img = *outs[i];
    img.width = view.width;
    img.height = view.height;
    img.rgba.resize(size_t(width) * height * 4);
    void* mapped;
    vkCheck(vkMapMemory(device, readback[i].memory, 0, VK_WHOLE_SIZE, 0, &mapped), "vkMapMemory (readback)");
    std::memcpy(img.rgba.data(), mapped, img.rgba.size() * sizeof(float));
    vkUnmapMemory(device, readback[i].memory);
  }
  if (timestamps) {
    uint64_t ticks[kTimestampCount] = {};
    if (vkGetQueryPoolResults(device, queryPool, 0, kTimestampCount, sizeof(ticks), ticks, sizeof(uint64_t),
                              VK_QUERY_RESULT_64_BIT | VK_QUERY_RESULT_WAIT_BIT) == VK_SUCCESS) {
      const double msPerTick = ctx.timestampPeriodNs() * 1e-6;
      result.timings.gbufferMs = double(ticks[1] - ticks[0]) * msPerTick;
      result.timings.lightingWarmupMs = double(ticks[2] - ticks[1]) * msPerTick;
      result.timings.lightingMs = double(ticks[3] - ticks[2]) * msPerTick;
    }
  }
  cleanup.run();
  result.timings.totalMs =
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  return result;
}

}  // namespace

RenderResult renderLevel(const RenderMesh& mesh, const Level& level, const ProbeQuery& query,
                         const RenderView& view) {
  return renderImpl(mesh, level.origin, &level, &query, nullptr, view);
}

RenderResult renderGridVolume(const RenderMesh& mesh, const RenderGrid& grid, const RenderView& view) {
  if (grid.dims.x < 2 || grid.dims.y < 2 || grid.dims.z < 2 || !grid.sh || !(grid.step > 0.0))
    throw std::runtime_error("render: a grid needs at least 2 nodes per axis, a positive step and its SH");
  const glm::dvec3 centre = grid.min + glm::dvec3(grid.dims - 1) * grid.step * 0.5;
  return renderImpl(mesh, glm::round(centre), nullptr, nullptr, &grid, view);
}

}  // namespace tetraprobe
