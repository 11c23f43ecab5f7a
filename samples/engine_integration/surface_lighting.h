// The engine's lighting pass for the sample (surface_lighting.cpp): its own compute shader
// (shaders/surface_lighting.comp, compiled at build time against the installed tetraprobe.glsl) shading
// surface points with a level's six GPU buffers, as an engine's deferred pass shades its G-buffer.
#pragma once

#include "engine.h"

#include <cstdint>
#include <string>
#include <vector>

#include <glm/vec3.hpp>
#include <glm/vec4.hpp>

#include <tetraprobe/runtime/shader_variant.h>
#include <tetraprobe/runtime/vulkan_upload.h>

// A surface point of the engine's G-buffer: a position in the level's local frame (world - Level::origin)
// and a unit normal; `sky` marks a pixel with no geometry (not shaded, irradiance 0).
struct SurfacePoint {
  glm::vec3 local;
  glm::vec3 normal;
  bool sky = false;
};

// One descriptor set layout for the level (set 0: levelDescriptorBindings), one for the points and outputs
// (set 1), host-visible buffers for up to `capacity` points and `outputs` results of as many points, and a
// pipeline per level variant (the same SPIR-V, specialized: shaderSpecialization). The Engine must outlive it.
class SurfaceLighting {
 public:
  SurfaceLighting() = default;
  SurfaceLighting(const SurfaceLighting&) = delete;
  SurfaceLighting& operator=(const SurfaceLighting&) = delete;
  ~SurfaceLighting();

  // False (error set) when a Vulkan object cannot be made.
  bool init(Engine& e, uint32_t capacity, uint32_t outputs, std::string* error);
  // A pipeline for `variant` and a descriptor set bound to `buffers`: what shading a level needs. Returns a
  // handle for shade(), or -1 (error set).
  int addLevel(const tetraprobe::ShaderVariant& variant, const tetraprobe::VulkanLevelBuffers& buffers,
               std::string* error);
  // Copies the points into the points buffer (host-visible, coherent); at most `capacity` of them. Not while
  // a frame that shades them is in flight.
  void setPoints(const std::vector<SurfacePoint>& points);
  // Records the dispatch shading the points with level `level` into output `output`, and a barrier that
  // makes the results visible to the host once the frame's fence has signalled.
  void cmdShade(VkCommandBuffer cmd, int level, uint32_t output) const;
  // Output `output` after the frame's fence: one vec4 a point (w = 1 where shaded, 0 on sky).
  const glm::vec4* results(uint32_t output) const;

 private:
  struct Buffer {
    VkBuffer buffer = VK_NULL_HANDLE;
    VkDeviceMemory memory = VK_NULL_HANDLE;
    void* mapped = nullptr;
  };
  bool makeBuffer(VkDeviceSize size, Buffer& out);

  Engine* e_ = nullptr;
  uint32_t capacity_ = 0, count_ = 0;
  VkDescriptorSetLayout levelLayout_ = VK_NULL_HANDLE, pointsLayout_ = VK_NULL_HANDLE;
  VkPipelineLayout pipelineLayout_ = VK_NULL_HANDLE;
  VkShaderModule module_ = VK_NULL_HANDLE;
  VkDescriptorPool descriptorPool_ = VK_NULL_HANDLE;
  Buffer points_;
  std::vector<Buffer> outputs_;
  std::vector<VkDescriptorSet> outputSets_;  // set 1, one per output
  std::vector<VkPipeline> pipelines_;        // per level
  std::vector<VkDescriptorSet> levelSets_;   // set 0, per level
};
