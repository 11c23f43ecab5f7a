// A regular SH L2 grid (RenderGrid) as seven 3D textures with a trilinear sampler, as
// shaders/lighting_grid_texture.comp reads them: what an engine's irradiance volume uploads. Internal to the
// render module (the bench pass of renderLevel).
#pragma once

#include <cstdint>

#include <vulkan/vulkan.h>
#include <glm/vec3.hpp>

#include "tetraprobe/render/render.h"
#include "vulkan_context.h"

namespace tetraprobe::render_detail {

inline constexpr int kGridTextureCount = 7;  // 27 floats a node in 7 RGBA texels (the 28th is 0)

struct GridTextures {
  GpuImage images[kGridTextureCount];
  VkSampler sampler = VK_NULL_HANDLE;  // linear min/mag, clamp to edge, no mips
  GpuBuffer header;                    // 48 bytes: vec4 min (local frame), vec4 step, ivec4 dims
  VkFormat format = VK_FORMAT_UNDEFINED;
  uint64_t bytes = 0;  // texel bytes of the seven textures
};

// Creates, fills (a staging copy, waited for) and leaves in SHADER_READ_ONLY_OPTIMAL the textures of `grid`,
// with node (0, 0, 0) at grid.min - origin. RGBA32F when the device filters it linearly, else RGBA16F (which
// Vulkan guarantees). Everything is destroyed by `cleanup`. Throws std::runtime_error on a Vulkan failure.
GridTextures createGridTextures(const VulkanContext& ctx, const RenderGrid& grid, const glm::dvec3& origin,
                                CleanupStack& cleanup);

}  // namespace tetraprobe::render_detail
