// Render passes and pipelines of the headless renderer: the G-buffer raster, the shadow-map depth raster,
// the probe-dot overlay and the full-screen compute passes. Internal to the render module.
#pragma once

#include <cstddef>
#include <cstdint>

#include <vulkan/vulkan.h>
#include <glm/vec3.hpp>

#include "vulkan_context.h"

namespace tetraprobe::render_detail {

constexpr VkFormat kGbufferFormat = VK_FORMAT_R32G32B32A32_SFLOAT;
constexpr VkFormat kDepthFormat = VK_FORMAT_D32_SFLOAT;

// One triangle-soup vertex, as gbuffer.vert (locations 0..3) and shadow_depth.vert (location 0) read it.
struct Vertex {
  glm::vec3 position;  // level local frame
  glm::vec3 normal;    // the triangle's unit normal
  glm::vec3 albedo;
  glm::vec3 emission;  // W/(m^2 sr), front face
};
static_assert(sizeof(Vertex) == 48, "gbuffer.vert vertex stride");

// G-buffer: four RGBA32F colour attachments (position, normal, albedo, emission; cleared, left GENERAL for
// the compute passes and copies) and depth (cleared, stored for the probe-dot pass).
VkRenderPass createGbufferPass(VkDevice device, CleanupStack& cleanup);
// Shadow map layer: depth only (cleared, left DEPTH_STENCIL_READ_ONLY_OPTIMAL for sampling by compute).
VkRenderPass createShadowPass(VkDevice device, CleanupStack& cleanup);
// Probe dots over the finished colour image (loaded, GENERAL) tested against the G-buffer's depth.
VkRenderPass createOverlayPass(VkDevice device, CleanupStack& cleanup);

// A single-layer framebuffer of `pass` over `views` (in attachment order), destroyed by `cleanup`; `what`
// names it in the error.
VkFramebuffer createFramebuffer(VkDevice device, VkRenderPass pass, const VkImageView* views, uint32_t count,
                                uint32_t width, uint32_t height, CleanupStack& cleanup, const char* what);

VkShaderModule createShader(VkDevice device, const uint32_t* code, size_t bytes, CleanupStack& cleanup);

VkPipelineLayout createPipelineLayout(VkDevice device, const VkDescriptorSetLayout* sets, uint32_t setCount,
                                      VkShaderStageFlags pushStages, uint32_t pushBytes,
                                      CleanupStack& cleanup);
VkDescriptorSetLayout createSetLayout(VkDevice device, const VkDescriptorSetLayoutBinding* bindings,
                                      uint32_t count, CleanupStack& cleanup);

// The G-buffer pipeline: back faces culled, depth LESS with writes, Vertex input, four colour outputs.
VkPipeline createGbufferPipeline(VkDevice device, VkRenderPass pass, VkPipelineLayout layout, uint32_t width,
                                 uint32_t height, CleanupStack& cleanup);
// The shadow-map pipeline: both faces drawn (either side casts a shadow), depth LESS with writes and a
// slope-scaled depth bias, positions only, no colour output.
VkPipeline createShadowPipeline(VkDevice device, VkRenderPass pass, VkPipelineLayout layout, uint32_t size,
                                CleanupStack& cleanup);
// The probe-dot pipeline: no vertex input (probe_dots.vert reads a buffer), depth test `compare` without
// writes, one colour output.
VkPipeline createDotsPipeline(VkDevice device, VkRenderPass pass, VkPipelineLayout layout, uint32_t width,
                              uint32_t height, VkCompareOp compare, CleanupStack& cleanup);
// `specialization` (may be null): the shader's specialization constants.
VkPipeline createComputePipeline(VkDevice device, VkPipelineLayout layout, const uint32_t* code, size_t bytes,
                                 CleanupStack& cleanup, const VkSpecializationInfo* specialization = nullptr);

}  // namespace tetraprobe::render_detail
