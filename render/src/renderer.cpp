// Headless renderer: per frame, optional shadow maps (full mode), a G-buffer raster (local position, flat
// normal, albedo, emission; RGBA32F + depth), then the mode's full-screen compute passes (the probe lookup
// through shaders/tetraprobe.glsl, direct light, or a debug view) and for the probe view a dot raster;
// timestamps after every pass; the frame resubmitted for warm-up and timing; the images read back.
#include "tetraprobe/render/render.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstddef>
#include <cstring>
#include <limits>
#include <stdexcept>
#include <string>

#include <glm/common.hpp>
#include <glm/geometric.hpp>
#include <glm/gtc/matrix_transform.hpp>
#include <glm/mat4x4.hpp>

#include "ambient.comp.h"
#include "debug_occlusion.comp.h"
#include "debug_surface.comp.h"
#include "debug_tets.comp.h"
#include "direct.comp.h"
#include "grid_texture.h"
#include "lighting.comp.h"
#include "lighting_edges.comp.h"
#include "lighting_grid.comp.h"
#include "lighting_grid_texture.comp.h"
#include "lighting_half.comp.h"
#include "lighting_nearest.comp.h"
#include "lighting_temporal.comp.h"
#include "lighting_upsample.comp.h"
#include "pipelines.h"
#include "shadow_lights.h"
#include "tetraprobe/runtime/vulkan_upload.h"
#include "vulkan_context.h"

namespace tetraprobe {
namespace {

using render_detail::CleanupStack;
using render_detail::GpuBuffer;
using render_detail::GpuImage;
using render_detail::kDepthFormat;
using render_detail::kGbufferFormat;
using render_detail::Vertex;
using render_detail::vkCheck;
using render_detail::VulkanContext;

constexpr int kImageCount = 4;            // read back: color, position, normal, albedo
constexpr uint32_t kMaxTimestamps = 128;  // two per pass

// Push constants of every compute pass (lighting.comp reads the first 12 bytes).
struct ComputePush {
  int32_t size[2];
  int32_t mode;         // lighting.comp: 0 irradiance, 1 albedo * E / pi
  int32_t lightCount;   // direct.comp
  float eye[4];         // debug views: camera position (local frame), w = radians per pixel
  float shadowInfo[4];  // direct.comp: texels per shadow-map side, the sun box's half-width (metres)
  int32_t parity;       // lighting_temporal.comp: the half of the pixel tets holding last frame's
  int32_t unused[3];
  glm::mat4 previousViewProj;  // lighting_temporal.comp: last frame's local frame -> clip space
};
static_assert(sizeof(ComputePush) == 128, "the compute shaders' push constant block (128: Vulkan's minimum)");
static_assert(offsetof(ComputePush, parity) == 48 && offsetof(ComputePush, previousViewProj) == 64,
              "lighting_temporal.comp's push block: parity at byte 48, the matrix at layout(offset = 64)");

struct DotsPush {
  glm::mat4 viewProj;
  float radius[2];  // NDC units
  float brightness;
  float pad;
};
static_assert(sizeof(DotsPush) == 80, "probe_dots.vert push constants");

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
    const glm::vec3 emission = t < mesh.triangleEmission.size() ? mesh.triangleEmission[t] : glm::vec3(0.0f);
    for (const glm::dvec3& p : {a, b, c}) {
      soup.push_back({glm::vec3(p - origin), n, albedo, emission});
      *lo = glm::min(*lo, p);
      *hi = glm::max(*hi, p);
    }
  }
  return soup;
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

// The nearest-probe buckets' storage buffer header (shaders/lighting_nearest.comp), 32 bytes.
struct NearestHeader {
  float min[4];     // xyz: lower corner, local frame; w: cell size
  int32_t dims[4];  // xyz: cells per axis; w: probe count
};
static_assert(sizeof(NearestHeader) == 32,
              "lighting_nearest.comp header: vec4 min (w cell), ivec4 dims (w probes)");

// A lighting pass that reads one storage buffer (set 0, binding 0) instead of a level: the grid or the
// nearest-probe competitor of `tetraprobe eval`.
struct OneBufferLookup {
  std::string bytes;
  const uint32_t* spirv = nullptr;
  size_t spirvBytes = 0;
};

template <typename T>
void appendBytes(std::string& out, const T* data, size_t count) {
  out.append(reinterpret_cast<const char*>(data), count * sizeof(T));
}

void memoryBarrier(VkCommandBuffer cmd, VkPipelineStageFlags srcStage, VkPipelineStageFlags dstStage,
                   VkAccessFlags src, VkAccessFlags dst) {
  VkMemoryBarrier b{VK_STRUCTURE_TYPE_MEMORY_BARRIER};
  b.srcAccessMask = src;
  b.dstAccessMask = dst;
  vkCmdPipelineBarrier(cmd, srcStage, dstStage, 0, 1, &b, 0, nullptr, 0, nullptr);
}

void fillBuffer(VkDevice device, const GpuBuffer& buffer, const void* data, size_t bytes, const char* what) {
  void* mapped;
  vkCheck(vkMapMemory(device, buffer.memory, 0, VK_WHOLE_SIZE, 0, &mapped), what);
  if (bytes > 0) std::memcpy(mapped, data, bytes);
  vkUnmapMemory(device, buffer.memory);
}

double median(std::vector<double> v) {
  if (v.empty()) return 0.0;
  std::sort(v.begin(), v.end());
  const size_t n = v.size();
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

VkCommandBuffer allocateCommandBuffer(const VulkanContext& ctx, CleanupStack& cleanup) {
  const VkDevice device = ctx.device();
  VkCommandBufferAllocateInfo info{VK_STRUCTURE_TYPE_COMMAND_BUFFER_ALLOCATE_INFO};
  info.commandPool = ctx.commandPool();
  info.level = VK_COMMAND_BUFFER_LEVEL_PRIMARY;
  info.commandBufferCount = 1;
  VkCommandBuffer cmd;
  vkCheck(vkAllocateCommandBuffers(device, &info, &cmd), "vkAllocateCommandBuffers");
  const VkCommandPool pool = ctx.commandPool();
  cleanup.push([device, pool, cmd] { vkFreeCommandBuffers(device, pool, 1, &cmd); });
  return cmd;
}

// A frame as one command buffer per pass, each between two timestamps: TOP_OF_PIPE before its commands and
// BOTTOM_OF_PIPE after them and a closing barrier. One buffer per pass because lavapipe, which runs
// dispatches asynchronously, does not order a timestamp between two passes of one command buffer after the
// first pass's work (measured: two full-screen dispatches both landed before the timestamp written between
// them); a submission boundary with a fence wait between passes does.
class PassRecorder {
 public:
  PassRecorder(const VulkanContext& ctx, CleanupStack& cleanup, VkQueryPool pool)
      : ctx_(ctx), cleanup_(cleanup), pool_(pool) {}
  VkCommandBuffer begin() {
    buffers_.push_back(allocateCommandBuffer(ctx_, cleanup_));
    const VkCommandBuffer cmd = buffers_.back();
    VkCommandBufferBeginInfo info{VK_STRUCTURE_TYPE_COMMAND_BUFFER_BEGIN_INFO};
    vkCheck(vkBeginCommandBuffer(cmd, &info), "vkBeginCommandBuffer");
    const auto q = uint32_t(2 * names_.size());
    if (pool_ != VK_NULL_HANDLE) {
      vkCmdResetQueryPool(cmd, pool_, q, 2);
      vkCmdWriteTimestamp(cmd, VK_PIPELINE_STAGE_TOP_OF_PIPE_BIT, pool_, q);
    }
    return cmd;
  }
  void end(const char* pass) {
    const VkCommandBuffer cmd = buffers_.back();
    if (pool_ != VK_NULL_HANDLE)
      vkCmdWriteTimestamp(cmd, VK_PIPELINE_STAGE_BOTTOM_OF_PIPE_BIT, pool_, uint32_t(2 * names_.size() + 1));
    vkCheck(vkEndCommandBuffer(cmd), "vkEndCommandBuffer");
    names_.push_back(pass);
  }
  const std::vector<VkCommandBuffer>& buffers() const { return buffers_; }
  const std::vector<std::string>& names() const { return names_; }

 private:
  const VulkanContext& ctx_;
  CleanupStack& cleanup_;
  VkQueryPool pool_;
  std::vector<VkCommandBuffer> buffers_;
  std::vector<std::string> names_;
};

// Submits `cmd` and waits for it. Waits before anything can throw, so the cleanup never destroys objects in
// use.
void submitAndWait(const VulkanContext& ctx, VkCommandBuffer cmd, VkFence fence) {
  const VkDevice device = ctx.device();
  VkSubmitInfo submit{VK_STRUCTURE_TYPE_SUBMIT_INFO};
  submit.commandBufferCount = 1;
  submit.pCommandBuffers = &cmd;
  vkCheck(vkQueueSubmit(ctx.queue(), 1, &submit, fence), "vkQueueSubmit");
  const VkResult waited = vkWaitForFences(device, 1, &fence, VK_TRUE, std::numeric_limits<uint64_t>::max());
  if (waited != VK_SUCCESS) vkDeviceWaitIdle(device);
  vkCheck(waited, "vkWaitForFences");
  vkCheck(vkResetFences(device, 1, &fence), "vkResetFences");
}

bool usesLighting(RenderMode m) {
  return m == RenderMode::kIrradiance || m == RenderMode::kIndirect || m == RenderMode::kFull;
}

// The lighting pass reads either a level (tetraprobe.glsl, set 0 = the level's buffers) or one buffer
// (lighting_grid.comp or lighting_nearest.comp, set 0 binding 0).
RenderResult renderImpl(const RenderMesh& mesh, const glm::dvec3& origin, const Level* level,
                        const ProbeQuery* query, const OneBufferLookup* grid, const RenderView& view,
                        const RenderOptions& options) {
  const auto t0 = std::chrono::steady_clock::now();
  if (view.width <= 0 || view.height <= 0 || view.width > 16384 || view.height > 16384)
    throw std::runtime_error("render: image size " + std::to_string(view.width) + "x" +
                             std::to_string(view.height) + " is outside 1..16384");
  if (!(view.fovYDeg > 0.0f && view.fovYDeg < 180.0f))
    throw std::runtime_error("render: fovYDeg must be in (0, 180)");
  if (glm::length(glm::cross(view.target - view.eye, view.up)) == 0.0f)
    throw std::runtime_error("render: eye, target and up must not be collinear");
  if (!level && !(view.mode == RenderMode::kIrradiance || view.mode == RenderMode::kIndirect))
    throw std::runtime_error("render: a grid renders irradiance or indirect only");
  if (options.shadowMapSize < 16 || options.shadowMapSize > 8192)
    throw std::runtime_error("render: shadowMapSize must be in 16..8192");
  if (!level && (options.variant || options.lightingSpirv || !options.benchVariants.empty() ||
                 options.benchAmbient || options.benchGrid))
    throw std::runtime_error("render: shader variants and bench passes need a level");
  if (options.benchVariants.size() > 16) throw std::runtime_error("render: at most 16 bench variants");
  if (options.temporalFrames != 0 &&
      (options.temporalFrames < 2 || options.temporalFrames > 32 || !level ||
       !(view.mode == RenderMode::kIrradiance || view.mode == RenderMode::kIndirect)))
    throw std::runtime_error(
        "render: the temporal start needs 2..32 frames, a level and mode irradiance or indirect");
  if (options.halfResolution &&
      (!level || !(view.mode == RenderMode::kIrradiance || view.mode == RenderMode::kIndirect)))
    throw std::runtime_error(
        "render: the half-resolution lookup needs a level and mode irradiance or indirect");
  if (options.benchGrid &&
      (options.benchGrid->dims.x < 2 || options.benchGrid->dims.y < 2 || options.benchGrid->dims.z < 2 ||
       !options.benchGrid->sh || !(options.benchGrid->step > 0.0)))
    throw std::runtime_error(
        "render: a bench grid needs at least 2 nodes per axis, a positive step and its SH");
  if (options.warmupFrames < 0 || options.timedFrames < 1 ||
      options.warmupFrames + options.timedFrames > 1000)
    throw std::runtime_error("render: need warmupFrames >= 0, timedFrames >= 1 and at most 1000 frames");
  const uint32_t width = uint32_t(view.width), height = uint32_t(view.height);
  const RenderMode mode = view.mode;

  glm::dvec3 lo, hi;
  const std::vector<Vertex> soup = buildSoup(mesh, origin, &lo, &hi);
  const glm::mat4 viewProj = viewProjection(view, origin, lo, hi);
  if (soup.empty()) lo = hi = origin;
  const render_detail::ShadowLights shadow =
      mode == RenderMode::kFull ? render_detail::packShadowLights(options.lights, origin, lo, hi)
                                : render_detail::ShadowLights{};

  VulkanContext ctx;
  const VkDevice device = ctx.device();
  CleanupStack cleanup;  // declared after ctx: runs first, while the device still exists

  const VkMemoryPropertyFlags hostMem =
      VK_MEMORY_PROPERTY_HOST_VISIBLE_BIT | VK_MEMORY_PROPERTY_HOST_COHERENT_BIT;
  // Level buffers, exactly as an engine would upload them (device-local, staged); or the grid's one buffer.
  VulkanLevelBuffers levelBuffers;
  GpuBuffer gridBuffer;
  if (level) {
    std::string uploadError;
    if (options.levelBuffers && !options.variant)
      throw std::runtime_error("render: packed level buffers need their shader variant");
    const VkResult uploaded =
        options.levelBuffers
            ? uploadPackedLevelBuffers(ctx.physicalDevice(), device, ctx.queue(), ctx.commandPool(),
                                       *options.levelBuffers, levelBuffers, &uploadError)
            : uploadLevelBuffers(ctx.physicalDevice(), device, ctx.queue(), ctx.commandPool(), *level,
                                 query->startGrid(), query->outerCells(), query->cellGrid(), levelBuffers,
                                 &uploadError);
    if (uploaded != VK_SUCCESS) throw std::runtime_error("render: level upload failed: " + uploadError);
    cleanup.push([device, &levelBuffers] { destroyLevelBuffers(device, levelBuffers); });
  } else {
    gridBuffer = ctx.createBuffer(grid->bytes.size(), VK_BUFFER_USAGE_STORAGE_BUFFER_BIT, hostMem, cleanup);
    fillBuffer(device, gridBuffer, grid->bytes.data(), grid->bytes.size(), "vkMapMemory (one-buffer lookup)");
  }

  const GpuBuffer vertices =
      ctx.createBuffer(std::max<VkDeviceSize>(sizeof(Vertex), soup.size() * sizeof(Vertex)),
                       VK_BUFFER_USAGE_VERTEX_BUFFER_BIT, hostMem, cleanup);
  fillBuffer(device, vertices, soup.data(), soup.size() * sizeof(Vertex), "vkMapMemory (vertices)");

  // Images: the output colour, the G-buffer (position, normal, albedo, emission) and depth.
  const VkImageUsageFlags gbufUsage =
      VK_IMAGE_USAGE_COLOR_ATTACHMENT_BIT | VK_IMAGE_USAGE_STORAGE_BIT | VK_IMAGE_USAGE_TRANSFER_SRC_BIT;
  const VkImageAspectFlags colorAspect = VK_IMAGE_ASPECT_COLOR_BIT;
  const GpuImage color = ctx.createImage(width, height, kGbufferFormat, gbufUsage, colorAspect, cleanup);
  const GpuImage gPosition = ctx.createImage(width, height, kGbufferFormat, gbufUsage, colorAspect, cleanup);
  const GpuImage gNormal = ctx.createImage(width, height, kGbufferFormat, gbufUsage, colorAspect, cleanup);
  const GpuImage gAlbedo = ctx.createImage(width, height, kGbufferFormat, gbufUsage, colorAspect, cleanup);
  const GpuImage gEmission = ctx.createImage(width, height, kGbufferFormat, gbufUsage, colorAspect, cleanup);
  const GpuImage depth =
      ctx.createImage(width, height, kDepthFormat, VK_IMAGE_USAGE_DEPTH_STENCIL_ATTACHMENT_BIT,
                      VK_IMAGE_ASPECT_DEPTH_BIT, cleanup);
  const GpuImage* readImages[kImageCount] = {&color, &gPosition, &gNormal, &gAlbedo};
  const VkDeviceSize imageBytes = VkDeviceSize(width) * height * 4 * sizeof(float);
  // The half-resolution lookup (tetraprobe_upsample.glsl): pass 1's E at ceil(W/2) x ceil(H/2), pass 2's image.
  const bool half = options.halfResolution;
  const uint32_t halfW = (width + 1) / 2, halfH = (height + 1) / 2;
  // The temporal start (lighting_temporal.comp): its output and two frames of tets a pixel.
  const bool temporal = options.temporalFrames > 0;
  GpuImage temporalImage;
  GpuBuffer pixelTets, temporalReadback;
  if (temporal) {
    temporalImage =
        ctx.createImage(width, height, kGbufferFormat,
                        VK_IMAGE_USAGE_STORAGE_BIT | VK_IMAGE_USAGE_TRANSFER_SRC_BIT, colorAspect, cleanup);
    pixelTets = ctx.createBuffer(2 * VkDeviceSize(width) * height * sizeof(int32_t),
                                 VK_BUFFER_USAGE_STORAGE_BUFFER_BIT | VK_BUFFER_USAGE_TRANSFER_DST_BIT,
                                 VK_MEMORY_PROPERTY_DEVICE_LOCAL_BIT, cleanup);
    temporalReadback = ctx.createBuffer(imageBytes, VK_BUFFER_USAGE_TRANSFER_DST_BIT, hostMem, cleanup);
  }
  GpuImage halfE, upsampled;
  GpuBuffer upsampledReadback,
      edgePixels;  // edgePixels: lighting_upsample.comp's list for lighting_edges.comp
  const VkDeviceSize edgeHeaderBytes = 5 * sizeof(uint32_t);
  if (half) {
    edgePixels = ctx.createBuffer(edgeHeaderBytes + VkDeviceSize(width) * height * sizeof(uint32_t),
                                  VK_BUFFER_USAGE_STORAGE_BUFFER_BIT | VK_BUFFER_USAGE_INDIRECT_BUFFER_BIT |
                                      VK_BUFFER_USAGE_TRANSFER_DST_BIT,
                                  VK_MEMORY_PROPERTY_DEVICE_LOCAL_BIT, cleanup);
    halfE = ctx.createImage(halfW, halfH, kGbufferFormat, VK_IMAGE_USAGE_STORAGE_BIT, colorAspect, cleanup);
    upsampled =
        ctx.createImage(width, height, kGbufferFormat,
                        VK_IMAGE_USAGE_STORAGE_BIT | VK_IMAGE_USAGE_TRANSFER_SRC_BIT, colorAspect, cleanup);
  }
  GpuBuffer readback[kImageCount];
  for (auto& b : readback)
    b = ctx.createBuffer(imageBytes, VK_BUFFER_USAGE_TRANSFER_DST_BIT, hostMem, cleanup);

  // G-buffer pass.
  const VkRenderPass gbufferPass = render_detail::createGbufferPass(device, cleanup);
  const VkImageView gbufferViews[5] = {gPosition.view, gNormal.view, gAlbedo.view, gEmission.view,
                                       depth.view};
  const VkFramebuffer gbufferFramebuffer = render_detail::createFramebuffer(
      device, gbufferPass, gbufferViews, 5, width, height, cleanup, "vkCreateFramebuffer");
  const VkPipelineLayout gbufferLayout = render_detail::createPipelineLayout(
      device, nullptr, 0, VK_SHADER_STAGE_VERTEX_BIT, sizeof(glm::mat4), cleanup);
  const VkPipeline gbufferPipeline =
      render_detail::createGbufferPipeline(device, gbufferPass, gbufferLayout, width, height, cleanup);

  // Shadow maps (full mode): one depth layer per cube face or sun; a 1x1 stand-in when there are none.
  const uint32_t shadowLayers = uint32_t(std::max<size_t>(1, shadow.layers.size()));
  const uint32_t shadowSize = shadow.layers.empty() ? 1u : uint32_t(options.shadowMapSize);
  GpuImage shadowImage;
  VkRenderPass shadowPass = VK_NULL_HANDLE;
  VkPipelineLayout shadowLayout = VK_NULL_HANDLE;
  VkPipeline shadowPipeline = VK_NULL_HANDLE;
  std::vector<VkFramebuffer> shadowFramebuffers;
  VkSampler shadowSampler = VK_NULL_HANDLE;
  if (mode == RenderMode::kFull) {
    shadowImage = ctx.createImage(shadowSize, shadowSize, kDepthFormat,
                                  VK_IMAGE_USAGE_DEPTH_STENCIL_ATTACHMENT_BIT | VK_IMAGE_USAGE_SAMPLED_BIT,
                                  VK_IMAGE_ASPECT_DEPTH_BIT, cleanup, shadowLayers);
    if (shadowLayers == 1) {  // direct.comp reads a 2D array view
      VkImageViewCreateInfo vci{VK_STRUCTURE_TYPE_IMAGE_VIEW_CREATE_INFO};
      vci.image = shadowImage.image;
      vci.viewType = VK_IMAGE_VIEW_TYPE_2D_ARRAY;
      vci.format = kDepthFormat;
      vci.subresourceRange = {VK_IMAGE_ASPECT_DEPTH_BIT, 0, 1, 0, 1};
      vkCheck(vkCreateImageView(device, &vci, nullptr, &shadowImage.view), "vkCreateImageView (shadow)");
      const VkImageView v = shadowImage.view;
      cleanup.push([device, v] { vkDestroyImageView(device, v, nullptr); });
    }
    VkSamplerCreateInfo si{VK_STRUCTURE_TYPE_SAMPLER_CREATE_INFO};
    si.magFilter = si.minFilter = VK_FILTER_LINEAR;
    si.mipmapMode = VK_SAMPLER_MIPMAP_MODE_NEAREST;
    si.addressModeU = si.addressModeV = si.addressModeW = VK_SAMPLER_ADDRESS_MODE_CLAMP_TO_EDGE;
    si.compareEnable = VK_TRUE;
    si.compareOp = VK_COMPARE_OP_LESS_OR_EQUAL;
    si.maxLod = 0.0f;
    vkCheck(vkCreateSampler(device, &si, nullptr, &shadowSampler), "vkCreateSampler");
    cleanup.push([device, shadowSampler] { vkDestroySampler(device, shadowSampler, nullptr); });
    if (!shadow.layers.empty()) {
      shadowPass = render_detail::createShadowPass(device, cleanup);
      shadowLayout = render_detail::createPipelineLayout(device, nullptr, 0, VK_SHADER_STAGE_VERTEX_BIT,
                                                         sizeof(glm::mat4), cleanup);
      shadowPipeline =
          render_detail::createShadowPipeline(device, shadowPass, shadowLayout, shadowSize, cleanup);
      for (uint32_t layer = 0; layer < shadowLayers; ++layer) {
        const VkImageView view1 =
            ctx.createLayerView(shadowImage.image, kDepthFormat, VK_IMAGE_ASPECT_DEPTH_BIT, layer, cleanup);
        shadowFramebuffers.push_back(render_detail::createFramebuffer(
            device, shadowPass, &view1, 1, shadowSize, shadowSize, cleanup, "vkCreateFramebuffer (shadow)"));
      }
    }
  }
  const GpuBuffer lightBuffer =
      ctx.createBuffer(std::max<size_t>(1, shadow.lights.size()) * sizeof(render_detail::GpuLight),
                       VK_BUFFER_USAGE_STORAGE_BUFFER_BIT, hostMem, cleanup);
  fillBuffer(device, lightBuffer, shadow.lights.data(),
             shadow.lights.size() * sizeof(render_detail::GpuLight), "vkMapMemory (lights)");
  const GpuBuffer matrixBuffer = ctx.createBuffer(shadowLayers * sizeof(glm::mat4),
                                                  VK_BUFFER_USAGE_STORAGE_BUFFER_BIT, hostMem, cleanup);
  fillBuffer(device, matrixBuffer, shadow.layers.data(), shadow.layers.size() * sizeof(glm::mat4),
             "vkMapMemory (shadow matrices)");

  // Compute passes: set 0 = the level (vulkan_upload.h) or the grid, set 1 = the images (0 position,
  // 1 normal, 2 albedo, 3 colour, 4 emission), set 2 = direct light (lights, layer matrices, shadow maps),
  // set 3 = the bench grid's textures and header.
  VkDescriptorSetLayoutBinding levelBindings[kGpuBindingCount];
  levelDescriptorBindings(VK_SHADER_STAGE_COMPUTE_BIT, 0, levelBindings);
  const uint32_t levelBindingCount = level ? uint32_t(kGpuBindingCount) : 1u;  // the grid: binding 0 only
  // 5, 6, 7: the half-resolution lookup's two images and its list of pixels looked up at full resolution;
  // 8, 9: the temporal start's image and its two frames of pixel tets.
  std::vector<VkDescriptorSetLayoutBinding> imageBindings;
  for (uint32_t i = 0; i < 10; ++i)
    if (i < 5 || (half && i < 8) || (temporal && i >= 8))
      imageBindings.push_back(
          {i, i == 7 || i == 9 ? VK_DESCRIPTOR_TYPE_STORAGE_BUFFER : VK_DESCRIPTOR_TYPE_STORAGE_IMAGE, 1,
           VK_SHADER_STAGE_COMPUTE_BIT, nullptr});
  const VkDescriptorSetLayoutBinding directBindings[3] = {
      {0, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, 1, VK_SHADER_STAGE_COMPUTE_BIT, nullptr},
      {1, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, 1, VK_SHADER_STAGE_COMPUTE_BIT, nullptr},
      {2, VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER, 1, VK_SHADER_STAGE_COMPUTE_BIT, nullptr}};
  const bool full = mode == RenderMode::kFull;
  const VkDescriptorSetLayoutBinding gridBindings[2] = {
      {0, VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER, render_detail::kGridTextureCount,
       VK_SHADER_STAGE_COMPUTE_BIT, nullptr},
      {1, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, 1, VK_SHADER_STAGE_COMPUTE_BIT, nullptr}};
  const VkDescriptorSetLayout setLayouts[4] = {
      render_detail::createSetLayout(device, levelBindings, levelBindingCount, cleanup),
      render_detail::createSetLayout(device, imageBindings.data(), uint32_t(imageBindings.size()), cleanup),
      render_detail::createSetLayout(device, directBindings, full ? 3u : 0u, cleanup),
      render_detail::createSetLayout(device, gridBindings, options.benchGrid ? 2u : 0u, cleanup)};
  const VkPipelineLayout computeLayout = render_detail::createPipelineLayout(
      device, setLayouts, 4, VK_SHADER_STAGE_COMPUTE_BIT, sizeof(ComputePush), cleanup);
  auto compute = [&](const uint32_t* code, size_t bytes, const VkSpecializationInfo* spec = nullptr) {
    return render_detail::createComputePipeline(device, computeLayout, code, bytes, cleanup, spec);
  };
  // The lookup's variant (shader_variant.h): the level's own unless the options name one.
  const ShaderVariant variant = !level ? kGenericShaderVariant
                                : options.variant
                                    ? *options.variant
                                    : shaderVariantFor(*level, query->outerCells(), query->cellGrid());
  const uint32_t* lightingCode = options.lightingSpirv ? options.lightingSpirv : kSpirv_lighting_comp;
  const size_t lightingBytes =
      options.lightingSpirv ? options.lightingSpirvBytes : sizeof(kSpirv_lighting_comp);
  auto lookupCode = [&](const ShaderVariant& v, const uint32_t* code, size_t bytes) {
    ShaderSpecialization spec;
    shaderSpecialization(v, 0, spec);
    return compute(code, bytes, &spec.info);
  };
  auto lookup = [&](const ShaderVariant& v) { return lookupCode(v, lightingCode, lightingBytes); };
  VkPipeline lightingPipeline = VK_NULL_HANDLE, directPipeline = VK_NULL_HANDLE,
             debugPipeline = VK_NULL_HANDLE;
  if (usesLighting(mode)) lightingPipeline = level ? lookup(variant) : compute(grid->spirv, grid->spirvBytes);
  // Bench passes (levels only): the lookup in other variants, a constant, the grid from 3D textures.
  std::vector<std::pair<std::string, VkPipeline>> benchPipelines;
  for (const ShaderVariant& v : options.benchVariants)
    benchPipelines.emplace_back("lookup:" + v.name(), lookup(v));
  if (options.benchAmbient)
    benchPipelines.emplace_back("ambient", compute(kSpirv_ambient_comp, sizeof(kSpirv_ambient_comp)));
  render_detail::GridTextures gridTextures;
  if (options.benchGrid) {
    gridTextures = render_detail::createGridTextures(ctx, *options.benchGrid, origin, cleanup);
    benchPipelines.emplace_back("grid_texture", compute(kSpirv_lighting_grid_texture_comp,
                                                        sizeof(kSpirv_lighting_grid_texture_comp)));
  }
  // The half-resolution lookup in the level's variant: pass 1 (lookup per 2x2 block), pass 2 (upsample).
  VkPipeline halfPipeline = VK_NULL_HANDLE, upsamplePipeline = VK_NULL_HANDLE, edgesPipeline = VK_NULL_HANDLE;
  if (half) {
    halfPipeline = lookupCode(variant, kSpirv_lighting_half_comp, sizeof(kSpirv_lighting_half_comp));
    upsamplePipeline = compute(kSpirv_lighting_upsample_comp, sizeof(kSpirv_lighting_upsample_comp));
    edgesPipeline = lookupCode(variant, kSpirv_lighting_edges_comp, sizeof(kSpirv_lighting_edges_comp));
    upsampledReadback = ctx.createBuffer(imageBytes, VK_BUFFER_USAGE_TRANSFER_DST_BIT, hostMem, cleanup);
  }
  const VkPipeline temporalPipeline =
      temporal ? lookupCode(variant, kSpirv_lighting_temporal_comp, sizeof(kSpirv_lighting_temporal_comp))
               : VK_NULL_HANDLE;
  if (full) directPipeline = compute(kSpirv_direct_comp, sizeof(kSpirv_direct_comp));
  if (mode == RenderMode::kProbes)
    debugPipeline = compute(kSpirv_debug_surface_comp, sizeof(kSpirv_debug_surface_comp));
  if (mode == RenderMode::kTets)
    debugPipeline = compute(kSpirv_debug_tets_comp, sizeof(kSpirv_debug_tets_comp));
  if (mode == RenderMode::kOcclusion)
    debugPipeline = compute(kSpirv_debug_occlusion_comp, sizeof(kSpirv_debug_occlusion_comp));

  // Probe dots (probes mode): a buffer of (local position, kind), the overlay pass and its two pipelines.
  const bool dots = mode == RenderMode::kProbes;
  GpuBuffer probeBuffer;
  VkRenderPass overlayPass = VK_NULL_HANDLE;
  VkFramebuffer overlayFramebuffer = VK_NULL_HANDLE;
  VkDescriptorSetLayout dotsSetLayout = VK_NULL_HANDLE;
  VkPipelineLayout dotsLayout = VK_NULL_HANDLE;
  VkPipeline dotsVisible = VK_NULL_HANDLE, dotsHidden = VK_NULL_HANDLE;
  const uint32_t probeCount = level ? uint32_t(level->probes.size()) : 0u;
  if (dots) {
    std::vector<glm::vec4> probes;
    probes.reserve(probeCount);
    for (uint32_t i = 0; i < probeCount; ++i)
      probes.emplace_back(level->probes[i],
                          i < level->probeKinds.size() ? float(uint8_t(level->probeKinds[i])) : -1.0f);
    probeBuffer = ctx.createBuffer(std::max<size_t>(1, probes.size()) * sizeof(glm::vec4),
                                   VK_BUFFER_USAGE_STORAGE_BUFFER_BIT, hostMem, cleanup);
    fillBuffer(device, probeBuffer, probes.data(), probes.size() * sizeof(glm::vec4), "vkMapMemory (probes)");
    overlayPass = render_detail::createOverlayPass(device, cleanup);
    const VkImageView views[2] = {color.view, depth.view};
    overlayFramebuffer = render_detail::createFramebuffer(device, overlayPass, views, 2, width, height,
                                                          cleanup, "vkCreateFramebuffer (dots)");
    const VkDescriptorSetLayoutBinding b{0, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, 1, VK_SHADER_STAGE_VERTEX_BIT,
                                         nullptr};
    dotsSetLayout = render_detail::createSetLayout(device, &b, 1, cleanup);
    dotsLayout = render_detail::createPipelineLayout(device, &dotsSetLayout, 1, VK_SHADER_STAGE_VERTEX_BIT,
                                                     sizeof(DotsPush), cleanup);
    dotsHidden = render_detail::createDotsPipeline(device, overlayPass, dotsLayout, width, height,
                                                   VK_COMPARE_OP_GREATER, cleanup);
    dotsVisible = render_detail::createDotsPipeline(device, overlayPass, dotsLayout, width, height,
                                                    VK_COMPARE_OP_LESS_OR_EQUAL, cleanup);
  }

  VkDescriptorPool descriptorPool;
  {
    const VkDescriptorPoolSize sizes[3] = {
        {VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, levelBindingCount + 6},
        {VK_DESCRIPTOR_TYPE_STORAGE_IMAGE, 8},
        {VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER, 1 + render_detail::kGridTextureCount}};
    VkDescriptorPoolCreateInfo info{VK_STRUCTURE_TYPE_DESCRIPTOR_POOL_CREATE_INFO};
    info.maxSets = 5;
    info.poolSizeCount = 3;
    info.pPoolSizes = sizes;
    vkCheck(vkCreateDescriptorPool(device, &info, nullptr, &descriptorPool), "vkCreateDescriptorPool");
    cleanup.push([device, descriptorPool] { vkDestroyDescriptorPool(device, descriptorPool, nullptr); });
  }
  VkDescriptorSet sets[4];
  {
    VkDescriptorSetAllocateInfo info{VK_STRUCTURE_TYPE_DESCRIPTOR_SET_ALLOCATE_INFO};
    info.descriptorPool = descriptorPool;
    info.descriptorSetCount = 4;
    info.pSetLayouts = setLayouts;
    vkCheck(vkAllocateDescriptorSets(device, &info, sets), "vkAllocateDescriptorSets");
  }
  VkDescriptorSet dotsSet = VK_NULL_HANDLE;
  if (dots) {
    VkDescriptorSetAllocateInfo info{VK_STRUCTURE_TYPE_DESCRIPTOR_SET_ALLOCATE_INFO};
    info.descriptorPool = descriptorPool;
    info.descriptorSetCount = 1;
    info.pSetLayouts = &dotsSetLayout;
    vkCheck(vkAllocateDescriptorSets(device, &info, &dotsSet), "vkAllocateDescriptorSets (dots)");
  }
  auto writeBuffer = [&](VkDescriptorSet set, uint32_t binding, VkBuffer buffer) {
    const VkDescriptorBufferInfo info{buffer, 0, VK_WHOLE_SIZE};
    VkWriteDescriptorSet write{VK_STRUCTURE_TYPE_WRITE_DESCRIPTOR_SET};
    write.dstSet = set;
    write.dstBinding = binding;
    write.descriptorCount = 1;
    write.descriptorType = VK_DESCRIPTOR_TYPE_STORAGE_BUFFER;
    write.pBufferInfo = &info;
    vkUpdateDescriptorSets(device, 1, &write, 0, nullptr);
  };
  if (level)
    writeLevelDescriptors(device, sets[0], 0, levelBuffers);
  else
    writeBuffer(sets[0], 0, gridBuffer.buffer);
  {
    const GpuImage* bound[9] = {&gPosition, &gNormal,   &gAlbedo, &color,        &gEmission,
                                &halfE,     &upsampled, nullptr,  &temporalImage};
    VkDescriptorImageInfo infos[9];
    VkWriteDescriptorSet writes[9];
    uint32_t count = 0;
    for (uint32_t i = 0; i < 9; ++i) {
      if (!bound[i] || (i >= 5 && i < 8 && !half) || (i == 8 && !temporal)) continue;
      infos[count] = {VK_NULL_HANDLE, bound[i]->view, VK_IMAGE_LAYOUT_GENERAL};
      writes[count] = VkWriteDescriptorSet{VK_STRUCTURE_TYPE_WRITE_DESCRIPTOR_SET};
      writes[count].dstSet = sets[1];
      writes[count].dstBinding = i;
      writes[count].descriptorCount = 1;
      writes[count].descriptorType = VK_DESCRIPTOR_TYPE_STORAGE_IMAGE;
      writes[count].pImageInfo = &infos[count];
      ++count;
    }
    vkUpdateDescriptorSets(device, count, writes, 0, nullptr);
  }
  if (half) writeBuffer(sets[1], 7, edgePixels.buffer);
  if (temporal) writeBuffer(sets[1], 9, pixelTets.buffer);
  if (full) {
    writeBuffer(sets[2], 0, lightBuffer.buffer);
    writeBuffer(sets[2], 1, matrixBuffer.buffer);
    const VkDescriptorImageInfo info{shadowSampler, shadowImage.view,
                                     VK_IMAGE_LAYOUT_DEPTH_STENCIL_READ_ONLY_OPTIMAL};
    VkWriteDescriptorSet write{VK_STRUCTURE_TYPE_WRITE_DESCRIPTOR_SET};
    write.dstSet = sets[2];
    write.dstBinding = 2;
    write.descriptorCount = 1;
    write.descriptorType = VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER;
    write.pImageInfo = &info;
    vkUpdateDescriptorSets(device, 1, &write, 0, nullptr);
  }
  if (dots) writeBuffer(dotsSet, 0, probeBuffer.buffer);
  if (options.benchGrid) {
    VkDescriptorImageInfo infos[render_detail::kGridTextureCount];
    for (int j = 0; j < render_detail::kGridTextureCount; ++j)
      infos[j] = {gridTextures.sampler, gridTextures.images[j].view,
                  VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL};
    VkWriteDescriptorSet write{VK_STRUCTURE_TYPE_WRITE_DESCRIPTOR_SET};
    write.dstSet = sets[3];
    write.dstBinding = 0;
    write.descriptorCount = render_detail::kGridTextureCount;
    write.descriptorType = VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER;
    write.pImageInfo = infos;
    vkUpdateDescriptorSets(device, 1, &write, 0, nullptr);
    writeBuffer(sets[3], 1, gridTextures.header.buffer);
  }

  VkQueryPool queryPool = VK_NULL_HANDLE;
  if (ctx.timestampPeriodNs() > 0) {
    VkQueryPoolCreateInfo info{VK_STRUCTURE_TYPE_QUERY_POOL_CREATE_INFO};
    info.queryType = VK_QUERY_TYPE_TIMESTAMP;
    info.queryCount = kMaxTimestamps;
    vkCheck(vkCreateQueryPool(device, &info, nullptr, &queryPool), "vkCreateQueryPool");
    cleanup.push([device, queryPool] { vkDestroyQueryPool(device, queryPool, nullptr); });
  }

  // Record one frame, a command buffer per pass; it is submitted warmupFrames + timedFrames times.
  PassRecorder clock(ctx, cleanup, queryPool);
  VkCommandBuffer cmd = VK_NULL_HANDLE;
  if (full && !shadowFramebuffers.empty()) {
    cmd = clock.begin();
    vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_GRAPHICS, shadowPipeline);
    const VkDeviceSize offset = 0;
    vkCmdBindVertexBuffers(cmd, 0, 1, &vertices.buffer, &offset);
    for (size_t layer = 0; layer < shadowFramebuffers.size(); ++layer) {
      VkClearValue clear{};
      clear.depthStencil = {1.0f, 0};
      VkRenderPassBeginInfo info{VK_STRUCTURE_TYPE_RENDER_PASS_BEGIN_INFO};
      info.renderPass = shadowPass;
      info.framebuffer = shadowFramebuffers[layer];
      info.renderArea = {{0, 0}, {shadowSize, shadowSize}};
      info.clearValueCount = 1;
      info.pClearValues = &clear;
      vkCmdBeginRenderPass(cmd, &info, VK_SUBPASS_CONTENTS_INLINE);
      if (!soup.empty()) {
        vkCmdPushConstants(cmd, shadowLayout, VK_SHADER_STAGE_VERTEX_BIT, 0, sizeof(glm::mat4),
                           &shadow.layers[layer]);
        vkCmdDraw(cmd, uint32_t(soup.size()), 1, 0, 0);
      }
      vkCmdEndRenderPass(cmd);
    }
    clock.end("shadow_maps");
  }
  // The G-buffer at one camera, then every compute output image to the general layout.
  auto recordGbuffer = [&](const glm::mat4& vp) {
    VkClearValue clears[5] = {};
    clears[4].depthStencil = {1.0f, 0};
    VkRenderPassBeginInfo info{VK_STRUCTURE_TYPE_RENDER_PASS_BEGIN_INFO};
    info.renderPass = gbufferPass;
    info.framebuffer = gbufferFramebuffer;
    info.renderArea = {{0, 0}, {width, height}};
    info.clearValueCount = 5;
    info.pClearValues = clears;
    vkCmdBeginRenderPass(cmd, &info, VK_SUBPASS_CONTENTS_INLINE);
    if (!soup.empty()) {
      vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_GRAPHICS, gbufferPipeline);
      const VkDeviceSize offset = 0;
      vkCmdBindVertexBuffers(cmd, 0, 1, &vertices.buffer, &offset);
      vkCmdPushConstants(cmd, gbufferLayout, VK_SHADER_STAGE_VERTEX_BIT, 0, sizeof(glm::mat4), &vp);
      vkCmdDraw(cmd, uint32_t(soup.size()), 1, 0, 0);
    }
    vkCmdEndRenderPass(cmd);
    imageBarrier(cmd, color.image, VK_IMAGE_LAYOUT_UNDEFINED, VK_IMAGE_LAYOUT_GENERAL, 0,
                 VK_ACCESS_SHADER_WRITE_BIT, VK_PIPELINE_STAGE_TOP_OF_PIPE_BIT,
                 VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT);
    if (half)
      for (VkImage image : {halfE.image, upsampled.image})
        imageBarrier(cmd, image, VK_IMAGE_LAYOUT_UNDEFINED, VK_IMAGE_LAYOUT_GENERAL, 0,
                     VK_ACCESS_SHADER_WRITE_BIT, VK_PIPELINE_STAGE_TOP_OF_PIPE_BIT,
                     VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT);
    if (temporal)
      imageBarrier(cmd, temporalImage.image, VK_IMAGE_LAYOUT_UNDEFINED, VK_IMAGE_LAYOUT_GENERAL, 0,
                   VK_ACCESS_SHADER_WRITE_BIT, VK_PIPELINE_STAGE_TOP_OF_PIPE_BIT,
                   VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT);
  };
  ComputePush push{};
  push.size[0] = int32_t(width);
  push.size[1] = int32_t(height);
  push.mode = mode == RenderMode::kIrradiance ? 0 : 1;
  push.lightCount = int32_t(shadow.lights.size());
  const glm::vec3 eyeLocal(glm::dvec3(view.eye) - origin);
  push.eye[0] = eyeLocal.x;
  push.eye[1] = eyeLocal.y;
  push.eye[2] = eyeLocal.z;
  push.eye[3] = float(glm::radians(double(view.fovYDeg)) / double(height));
  push.shadowInfo[0] = float(shadowSize);
  push.shadowInfo[1] = shadow.sunHalfWidth;
  const VkAccessFlags anyAccess = VK_ACCESS_SHADER_READ_BIT | VK_ACCESS_SHADER_WRITE_BIT |
                                  VK_ACCESS_TRANSFER_READ_BIT | VK_ACCESS_COLOR_ATTACHMENT_READ_BIT |
                                  VK_ACCESS_COLOR_ATTACHMENT_WRITE_BIT;
  const VkPipelineStageFlags anyStage = VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT |
                                        VK_PIPELINE_STAGE_TRANSFER_BIT |
                                        VK_PIPELINE_STAGE_COLOR_ATTACHMENT_OUTPUT_BIT;
  auto dispatch = [&](VkPipeline pipeline, const std::string& pass, const ComputePush& p, uint32_t groupsX,
                      uint32_t groupsY) {
    cmd = clock.begin();
    vkCmdBindDescriptorSets(cmd, VK_PIPELINE_BIND_POINT_COMPUTE, computeLayout, 0, 4, sets, 0, nullptr);
    vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_COMPUTE, pipeline);
    vkCmdPushConstants(cmd, computeLayout, VK_SHADER_STAGE_COMPUTE_BIT, 0, sizeof(p), &p);
    vkCmdDispatch(cmd, groupsX, groupsY, 1);
    memoryBarrier(cmd, VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT, anyStage, VK_ACCESS_SHADER_WRITE_BIT, anyAccess);
    clock.end(pass.c_str());
  };
  const uint32_t groupsX = (width + 7) / 8, groupsY = (height + 7) / 8;
  // The temporal start's camera path: temporalFrames - 1 frames before the view, each temporalStep behind
  // the next; in each, the G-buffer, the cold lookup and the temporal one (reading the tets the frame before
  // wrote). The view's own frame below is the path's last.
  std::vector<glm::mat4> pathViewProj;
  if (temporal) {
    for (int f = 0; f < options.temporalFrames; ++f) {
      RenderView v = view;
      const glm::vec3 back = float(options.temporalFrames - 1 - f) * options.temporalStep;
      v.eye -= back;
      v.target -= back;
      pathViewProj.push_back(viewProjection(v, origin, lo, hi));
    }
    pathViewProj.back() = viewProj;
  }
  auto temporalPush = [&](int f) {
    ComputePush p = push;
    p.parity = f % 2;
    p.previousViewProj = pathViewProj[size_t(std::max(f - 1, 0))];
    return p;
  };
  for (int f = 0; f + 1 < options.temporalFrames; ++f) {
    cmd = clock.begin();
    if (f == 0) {  // no tets from before the path: every hint -1
      vkCmdFillBuffer(cmd, pixelTets.buffer, 0, VK_WHOLE_SIZE, 0xffffffffu);
      memoryBarrier(cmd, VK_PIPELINE_STAGE_TRANSFER_BIT, VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT,
                    VK_ACCESS_TRANSFER_WRITE_BIT, VK_ACCESS_SHADER_READ_BIT | VK_ACCESS_SHADER_WRITE_BIT);
    }
    recordGbuffer(pathViewProj[size_t(f)]);
    clock.end("path_gbuffer");
    dispatch(lightingPipeline, "lookup_cold", push, groupsX, groupsY);
    dispatch(temporalPipeline, f == 0 ? "lookup_temporal_first" : "lookup_temporal", temporalPush(f), groupsX,
             groupsY);
  }
  cmd = clock.begin();
  if (full && shadowFramebuffers
                  .empty()) {  // the stand-in layer, never read (no lights), still needs its sampled layout
    VkImageMemoryBarrier b{VK_STRUCTURE_TYPE_IMAGE_MEMORY_BARRIER};
    b.dstAccessMask = VK_ACCESS_SHADER_READ_BIT;
    b.oldLayout = VK_IMAGE_LAYOUT_UNDEFINED;
    b.newLayout = VK_IMAGE_LAYOUT_DEPTH_STENCIL_READ_ONLY_OPTIMAL;
    b.srcQueueFamilyIndex = b.dstQueueFamilyIndex = VK_QUEUE_FAMILY_IGNORED;
    b.image = shadowImage.image;
    b.subresourceRange = {VK_IMAGE_ASPECT_DEPTH_BIT, 0, 1, 0, 1};
    vkCmdPipelineBarrier(cmd, VK_PIPELINE_STAGE_TOP_OF_PIPE_BIT, VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT, 0, 0,
                         nullptr, 0, nullptr, 1, &b);
  }
  recordGbuffer(viewProj);
  clock.end("gbuffer");
  for (const auto& [name, pipeline] : benchPipelines) dispatch(pipeline, name, push, groupsX, groupsY);
  if (half) {
    dispatch(halfPipeline, "lookup_half", push, (halfW + 7) / 8, (halfH + 7) / 8);
    // The list starts empty each frame: 0 workgroups (y = z = 1), 0 pixels.
    cmd = clock.begin();
    const uint32_t empty[5] = {0, 1, 1, 0, 0};
    vkCmdUpdateBuffer(cmd, edgePixels.buffer, 0, sizeof(empty), empty);
    memoryBarrier(cmd, VK_PIPELINE_STAGE_TRANSFER_BIT, VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT,
                  VK_ACCESS_TRANSFER_WRITE_BIT, VK_ACCESS_SHADER_READ_BIT | VK_ACCESS_SHADER_WRITE_BIT);
    vkCmdBindDescriptorSets(cmd, VK_PIPELINE_BIND_POINT_COMPUTE, computeLayout, 0, 4, sets, 0, nullptr);
    vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_COMPUTE, upsamplePipeline);
    vkCmdPushConstants(cmd, computeLayout, VK_SHADER_STAGE_COMPUTE_BIT, 0, sizeof(push), &push);
    vkCmdDispatch(cmd, groupsX, groupsY, 1);
    memoryBarrier(cmd, VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT, anyStage, VK_ACCESS_SHADER_WRITE_BIT, anyAccess);
    clock.end("upsample");
    cmd = clock.begin();
    memoryBarrier(cmd, VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT,
                  VK_PIPELINE_STAGE_DRAW_INDIRECT_BIT | VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT,
                  VK_ACCESS_SHADER_WRITE_BIT,
                  VK_ACCESS_INDIRECT_COMMAND_READ_BIT | VK_ACCESS_SHADER_READ_BIT);
    vkCmdBindDescriptorSets(cmd, VK_PIPELINE_BIND_POINT_COMPUTE, computeLayout, 0, 4, sets, 0, nullptr);
    vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_COMPUTE, edgesPipeline);
    vkCmdPushConstants(cmd, computeLayout, VK_SHADER_STAGE_COMPUTE_BIT, 0, sizeof(push), &push);
    vkCmdDispatchIndirect(cmd, edgePixels.buffer, 0);
    memoryBarrier(cmd, VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT, anyStage, VK_ACCESS_SHADER_WRITE_BIT, anyAccess);
    clock.end("lookup_edges");
  }
  if (lightingPipeline != VK_NULL_HANDLE) {
    // Warm-up: one workgroup (pixel 0,0 only). lavapipe JIT-compiles a pipeline at its first dispatch; this
    // keeps that compile out of the timed full-screen pass of a single frame.
    ComputePush warmup = push;
    warmup.size[0] = warmup.size[1] = 1;
    dispatch(lightingPipeline, "lighting_warmup", warmup, 1, 1);
    dispatch(lightingPipeline, "lighting", push, groupsX, groupsY);
    if (temporal)
      dispatch(temporalPipeline, "lookup_temporal", temporalPush(options.temporalFrames - 1), groupsX,
               groupsY);
  }
  if (directPipeline != VK_NULL_HANDLE) dispatch(directPipeline, "direct", push, groupsX, groupsY);
  if (debugPipeline != VK_NULL_HANDLE)
    dispatch(debugPipeline,
             mode == RenderMode::kProbes ? "surface"
             : mode == RenderMode::kTets ? "tets"
                                         : "occlusion",
             push, groupsX, groupsY);
  if (dots) {
    cmd = clock.begin();
    VkRenderPassBeginInfo info{VK_STRUCTURE_TYPE_RENDER_PASS_BEGIN_INFO};
    info.renderPass = overlayPass;
    info.framebuffer = overlayFramebuffer;
    info.renderArea = {{0, 0}, {width, height}};
    vkCmdBeginRenderPass(cmd, &info, VK_SUBPASS_CONTENTS_INLINE);
    if (probeCount > 0) {
      vkCmdBindDescriptorSets(cmd, VK_PIPELINE_BIND_POINT_GRAPHICS, dotsLayout, 0, 1, &dotsSet, 0, nullptr);
      const float radiusPx = std::max(2.5f, float(height) / 110.0f);
      DotsPush dp{viewProj, {2.0f * radiusPx / float(width), 2.0f * radiusPx / float(height)}, 1.0f, 0.0f};
      DotsPush hidden = dp;
      hidden.radius[0] *= 0.6f;
      hidden.radius[1] *= 0.6f;
      hidden.brightness = 0.35f;
      vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_GRAPHICS, dotsHidden);
      vkCmdPushConstants(cmd, dotsLayout, VK_SHADER_STAGE_VERTEX_BIT, 0, sizeof(hidden), &hidden);
      vkCmdDraw(cmd, 6, probeCount, 0, 0);
      vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_GRAPHICS, dotsVisible);
      vkCmdPushConstants(cmd, dotsLayout, VK_SHADER_STAGE_VERTEX_BIT, 0, sizeof(dp), &dp);
      vkCmdDraw(cmd, 6, probeCount, 0, 0);
    }
    vkCmdEndRenderPass(cmd);
    clock.end("probe_dots");
  }

  // Read back all four images after the last frame.
  const VkCommandBuffer copyCmd = allocateCommandBuffer(ctx, cleanup);
  VkCommandBufferBeginInfo begin{VK_STRUCTURE_TYPE_COMMAND_BUFFER_BEGIN_INFO};
  begin.flags = VK_COMMAND_BUFFER_USAGE_ONE_TIME_SUBMIT_BIT;
  vkCheck(vkBeginCommandBuffer(copyCmd, &begin), "vkBeginCommandBuffer (readback)");
  for (int i = 0; i < kImageCount; ++i) {
    VkBufferImageCopy region{};
    region.imageSubresource = {VK_IMAGE_ASPECT_COLOR_BIT, 0, 0, 1};
    region.imageExtent = {width, height, 1};
    vkCmdCopyImageToBuffer(copyCmd, readImages[i]->image, VK_IMAGE_LAYOUT_GENERAL, readback[i].buffer, 1,
                           &region);
    if (half && i == 0)
      vkCmdCopyImageToBuffer(copyCmd, upsampled.image, VK_IMAGE_LAYOUT_GENERAL, upsampledReadback.buffer, 1,
                             &region);
    if (temporal && i == 0)
      vkCmdCopyImageToBuffer(copyCmd, temporalImage.image, VK_IMAGE_LAYOUT_GENERAL, temporalReadback.buffer,
                             1, &region);
  }
  memoryBarrier(copyCmd, VK_PIPELINE_STAGE_TRANSFER_BIT, VK_PIPELINE_STAGE_HOST_BIT,
                VK_ACCESS_TRANSFER_WRITE_BIT, VK_ACCESS_HOST_READ_BIT);
  vkCheck(vkEndCommandBuffer(copyCmd), "vkEndCommandBuffer (readback)");

  VkFence fence;
  {
    VkFenceCreateInfo info{VK_STRUCTURE_TYPE_FENCE_CREATE_INFO};
    vkCheck(vkCreateFence(device, &info, nullptr, &fence), "vkCreateFence");
    cleanup.push([device, fence] { vkDestroyFence(device, fence, nullptr); });
  }
  const size_t passCount = clock.names().size();
  std::vector<std::vector<double>> samples(passCount);
  const int frames = options.warmupFrames + options.timedFrames;
  for (int f = 0; f < frames; ++f) {
    for (VkCommandBuffer pass : clock.buffers()) submitAndWait(ctx, pass, fence);
    if (queryPool == VK_NULL_HANDLE || f < options.warmupFrames) continue;
    uint64_t ticks[kMaxTimestamps] = {};
    if (vkGetQueryPoolResults(device, queryPool, 0, uint32_t(2 * passCount), sizeof(ticks), ticks,
                              sizeof(uint64_t),
                              VK_QUERY_RESULT_64_BIT | VK_QUERY_RESULT_WAIT_BIT) != VK_SUCCESS)
      continue;
    const double msPerTick = ctx.timestampPeriodNs() * 1e-6;
    for (size_t p = 0; p < passCount; ++p)
      samples[p].push_back(double(ticks[2 * p + 1] - ticks[2 * p]) * msPerTick);
  }
  submitAndWait(ctx, copyCmd, fence);

  RenderResult result;
  Image* outs[kImageCount + 2] = {&result.color,  &result.position,       &result.normal,
                                  &result.albedo, &result.halfResolution, &result.temporal};
  const GpuBuffer* sources[kImageCount + 2] = {&readback[0], &readback[1],       &readback[2],
                                               &readback[3], &upsampledReadback, &temporalReadback};
  for (int i = 0; i < kImageCount + 2; ++i) {
    if ((i == kImageCount && !half) || (i == kImageCount + 1 && !temporal)) continue;
    Image& img = *outs[i];
    const GpuBuffer& source = *sources[i];
    img.width = view.width;
    img.height = view.height;
    img.rgba.resize(size_t(width) * height * 4);
    void* mapped;
    vkCheck(vkMapMemory(device, source.memory, 0, VK_WHOLE_SIZE, 0, &mapped), "vkMapMemory (readback)");
    std::memcpy(img.rgba.data(), mapped, img.rgba.size() * sizeof(float));
    vkUnmapMemory(device, source.memory);
  }
  result.variant = variant;
  result.deviceName = ctx.deviceName();
  if (options.benchGrid) {
    result.gridTextureFormat = gridTextures.format == VK_FORMAT_R32G32B32A32_SFLOAT ? "rgba32f" : "rgba16f";
    result.gridTextureBytes = gridTextures.bytes;
  }
  RenderTimings& t = result.timings;
  t.warmupFrames = options.warmupFrames;
  t.timedFrames = options.timedFrames;
  for (size_t p = 0; p < passCount; ++p) {
    if (samples[p].empty()) continue;
    const double ms = median(samples[p]);
    const std::string& name = clock.names()[p];
    t.passes.push_back({name, ms});
    if (name == "gbuffer") t.gbufferMs = ms;
    if (name == "lighting_warmup") t.lightingWarmupMs = ms;
    if (name == "lighting") t.lightingMs = ms;
  }
  cleanup.run();
  t.totalMs = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  return result;
}

}  // namespace

double RenderTimings::passMs(const std::string& name) const {
  for (const PassTiming& p : passes)
    if (p.name == name) return p.ms;
  return 0.0;
}

bool isDebugMode(RenderMode mode) {
  return mode == RenderMode::kProbes || mode == RenderMode::kTets || mode == RenderMode::kOcclusion;
}

RenderResult renderLevel(const RenderMesh& mesh, const Level& level, const ProbeQuery& query,
                         const RenderView& view, const RenderOptions& options) {
  return renderImpl(mesh, level.origin, &level, &query, nullptr, view, options);
}

RenderResult renderGridVolume(const RenderMesh& mesh, const RenderGrid& grid, const RenderView& view) {
  if (grid.dims.x < 2 || grid.dims.y < 2 || grid.dims.z < 2 || !grid.sh || !(grid.step > 0.0))
    throw std::runtime_error("render: a grid needs at least 2 nodes per axis, a positive step and its SH");
  const glm::dvec3 centre = grid.min + glm::dvec3(grid.dims - 1) * grid.step * 0.5;
  const glm::dvec3 origin = glm::round(centre);
  const size_t nodes = size_t(grid.dims.x) * size_t(grid.dims.y) * size_t(grid.dims.z);
  GridHeader header{};
  const glm::vec3 localMin(grid.min - origin);
  for (int a = 0; a < 3; ++a) {
    header.min[a] = localMin[a];
    header.step[a] = float(grid.step);
    header.dims[a] = grid.dims[a];
  }
  OneBufferLookup one;
  appendBytes(one.bytes, &header, 1);
  appendBytes(one.bytes, grid.sh, nodes);
  one.spirv = kSpirv_lighting_grid_comp;
  one.spirvBytes = sizeof(kSpirv_lighting_grid_comp);
  return renderImpl(mesh, origin, nullptr, nullptr, &one, view, RenderOptions{});
}

RenderResult renderNearestProbe(const RenderMesh& mesh, const RenderNearest& nearest,
                                const RenderView& view) {
  const glm::ivec3 d = nearest.dims;
  const size_t n = nearest.probeCount;
  if (d.x < 1 || d.y < 1 || d.z < 1 || n < 1 || n > size_t(INT32_MAX / 32) || !(nearest.cell > 0.0f) ||
      !nearest.cellStart || !nearest.order || !nearest.positions || !nearest.sh ||
      double(d.x) * d.y * d.z > double(INT32_MAX / 4))
    throw std::runtime_error(
        "render: nearest-probe buckets need cells, probes, a positive cell size and data");
  const size_t cells = size_t(d.x) * size_t(d.y) * size_t(d.z);
  if (nearest.cellStart[cells] != n)
    throw std::runtime_error("render: nearest-probe buckets do not hold every probe");
  NearestHeader header{};
  for (int a = 0; a < 3; ++a) {
    header.min[a] = nearest.min[a];
    header.dims[a] = d[a];
  }
  header.min[3] = nearest.cell;
  header.dims[3] = int32_t(n);
  OneBufferLookup one;
  appendBytes(one.bytes, &header, 1);
  appendBytes(one.bytes, nearest.cellStart, cells + 1);
  appendBytes(one.bytes, nearest.order, n);
  appendBytes(one.bytes, nearest.positions, n);
  appendBytes(one.bytes, nearest.sh, n);
  one.spirv = kSpirv_lighting_nearest_comp;
  one.spirvBytes = sizeof(kSpirv_lighting_nearest_comp);
  return renderImpl(mesh, nearest.origin, nullptr, nullptr, &one, view, RenderOptions{});
}

}  // namespace tetraprobe
