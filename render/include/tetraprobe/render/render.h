// Headless Vulkan renderer for tetraprobe levels: rasterizes a triangle mesh into a G-buffer and lights every
// pixel with the per-pixel probe lookup of shaders/tetraprobe.glsl (the same include engines use), then reads
// the images back. Also image output (PNG, EXR). Permissive: runtime + Vulkan + stb/tinyexr.
//
// Frames and units: mesh and camera in world metres (right-handed); the renderer subtracts Level::origin (in
// double) so the GPU works in the level's local frame. Images are linear float RGBA, row 0 = top.
#pragma once

#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include <glm/vec3.hpp>

#include "tetraprobe/runtime/gpu_layout.h"
#include "tetraprobe/runtime/level.h"
#include "tetraprobe/runtime/query.h"
#include "tetraprobe/runtime/shader_variant.h"

namespace tetraprobe {

// Triangles to render. Front faces are counter-clockwise seen from the front (normal = (b-a) x (c-a));
// back faces are culled from the camera (both faces cast shadows). Each triangle is shaded with its flat
// normal, triangleAlbedo and triangleEmission (linear RGB). Shadows treat every triangle as opaque.
struct RenderMesh {
  std::vector<glm::vec3> positions;         // world metres
  std::vector<glm::uvec3> triangles;        // indices into positions
  std::vector<glm::vec3> triangleAlbedo;    // one per triangle; missing entries default to 0.8 grey
  std::vector<glm::vec3> triangleEmission;  // W/(m^2 sr) from the front face; missing entries are 0
};

enum class RenderLightType { kPoint, kSpot, kDirectional };

// A light of the full render, with the bake's conventions (scene/scene.h Light): radiometric units, spot
// falloff smoothstep(cos outer, cos inner, cos angle). Lights with a radius or a sun disc are drawn as
// points (hard-edged shadows softened only by 3x3 PCF).
struct RenderLight {
  RenderLightType type = RenderLightType::kPoint;
  glm::vec3 position{0.0f};       // point, spot: world metres
  glm::vec3 direction{0, -1, 0};  // spot, directional: direction the light travels (normalized here)
  glm::vec3 intensity{0.0f};      // point, spot: W/sr; directional: W/m^2 at normal incidence
  float innerConeRad = 0.0f;      // spot: full intensity inside this half-angle
  float outerConeRad = 0.7854f;   // spot: zero outside this half-angle
};

enum class RenderMode {
  kIrradiance,  // E in W/m^2
  kIndirect,    // Lambertian outgoing radiance albedo * E / pi in W/(m^2 sr)
  // Outgoing radiance, W/(m^2 sr): emission + albedo / pi x (E_probes + E_direct), where E_direct is the
  // irradiance from RenderOptions::lights, each shadowed by shadow maps (point and spot: a cube of six
  // faces; sun: one orthographic map over the scene). Right for levels baked with the default content
  // (probes without direct punctual light); a level holding it (kContentDirectPunctual) counts it twice.
  kFull,
  // Debug views. color holds display colours (linear RGB in [0, 1], not radiance; write with
  // writePngLinear) over a grey backdrop shaded by facing ratio:
  // - kProbes: every probe as a round dot with a dark rim (depth-tested against the scene; probes behind
  //   geometry as smaller dots at 35 % brightness), coloured by Level::probeKinds: user white, surface green
  //   (0.1, 0.85, 0.1), volume cyan, open light blue, filler blue (0.1, 0.25, 1), shell orange (1, 0.5, 0),
  //   dilated magenta (1, 0, 1), hole red, refinement yellow, grid grey; all white when the level records no
  //   kinds.
  kProbes,
  // - kTets: each pixel in the hashed colour of the tet holding its surface point, dark where the point is
  //   within about a pixel of a tet face (the tet edges and faces as they cut the surfaces); points outside
  //   the hull in a darker colour per outer cell.
  kTets,
  // - kOcclusion: the kind of occlusion record of the pixel's tet (outside the hull: the hull tet's, as the
  //   lookup uses): none grey (0.5), planes blue (0.15, 0.35, 1), shadow maps green (0.2, 0.9, 0.25); red
  //   (1, 0.05, 0.05) mixed in by 50-100 % where the all-occluded fallback ran (the lookup's fallback
  //   share > 0). All times 0.6 + 0.4 x the facing ratio.
  kOcclusion,
};

// True for the debug views (display colours, not radiance).
bool isDebugMode(RenderMode mode);

struct RenderView {
  glm::vec3 eye{0.0f, 0.0f, 5.0f};  // world metres
  glm::vec3 target{0.0f};           // world metres
  glm::vec3 up{0, 1, 0};
  float fovYDeg = 60;  // vertical field of view; near/far planes are fitted to the mesh bounds
  int width = 960, height = 540;
  RenderMode mode = RenderMode::kIndirect;
};

// Linear float RGBA, row-major, row 0 = top: rgba[4 * (y * width + x) + c].
struct Image {
  int width = 0, height = 0;
  std::vector<float> rgba;
};

// Unit world direction of the primary ray through image point (x, y) of `view`, in pixels from the image's
// top-left corner (x right, y down: pixel (i, j)'s centre is (i + 0.5, j + 0.5)); the ray starts at view.eye.
// The camera renderLevel rasterizes with: glm::lookAtRH(eye, target, up), a vertical field of view of
// fovYDeg over view.height pixels, square pixels, row 0 = top. Computed in double; does not use view.mode.
// For tracing the same pixels on the CPU (the path-traced reference image, eval/reference_image.h).
glm::dvec3 pixelRayDirection(const RenderView& view, double x, double y);

// GPU time of one pass, milliseconds: the median over RenderOptions::timedFrames frames.
struct PassTiming {
  std::string name;  // shadow_maps, gbuffer, lighting_warmup, lighting, direct, surface, probe_dots, tets,
                     // occlusion (those the mode runs, in order)
  double ms = 0;
};

// Wall-clock and GPU times of one renderLevel call, milliseconds. GPU times come from timestamp queries (0
// when the queue has none), taken around each pass in a command buffer of its own (lavapipe runs dispatches
// asynchronously and does not order a timestamp between two passes of one command buffer after the first's
// work). lavapipe JIT-compiles shaders at the first draw/dispatch: in a single frame gbufferMs includes that
// compile; the lighting pass is preceded by a one-workgroup warm-up dispatch so lightingMs does not (the
// compile lands in lightingWarmupMs). With warm-up frames neither carries it.
struct RenderTimings {
  double totalMs = 0;           // whole call: device, upload, pipelines, render, readback, object cleanup
  double gbufferMs = 0;         // GPU: G-buffer render pass
  double lightingWarmupMs = 0;  // GPU: the one-workgroup warm-up dispatch of the lighting pipeline
  double lightingMs = 0;        // GPU: the full-screen lighting compute pass
  // Every pass the mode runs, median over the timed frames (the fields above are medians too). Empty when
  // the queue has no timestamps.
  std::vector<PassTiming> passes;
  int warmupFrames = 0, timedFrames = 1;

  // The first pass named `name` in `passes`; 0 when there is none.
  double passMs(const std::string& name) const;
};

// A regular SH L2 grid for the lighting pass to read instead of a level (shaders/lighting_grid.comp): the
// `grid` method of `tetraprobe eval` (eval/grid_volume.h), rendered to time it against the tet lookup.
// Node (i, j, k) at min + (i, j, k) x step, world metres; `sh` holds dims.x * dims.y * dims.z nodes, x fastest,
// in runtime/sh.h's convention; uploaded as a 48-byte header (vec4 min, vec4 step, ivec4 dims; local frame)
// and 27 floats per node.
struct RenderGrid {
  glm::dvec3 min{0.0};
  double step = 1.0;
  glm::ivec3 dims{0};         // each >= 2
  const ShRgb* sh = nullptr;  // must stay valid during the call
};

// The nearest-probe competitor of `tetraprobe eval` as the GPU reads it: a uniform bucket grid over the
// probes (eval/nearest_probe.h builds it). Positions are in the frame whose origin is `origin` (world,
// metres); every pointer must stay valid during the call.
struct RenderNearest {
  glm::dvec3 origin{0.0};
  glm::vec3 min{0.0f};  // the grid's lower corner, local frame
  float cell = 1.0f;    // cell size, metres, > 0
  glm::ivec3 dims{0};   // cells per axis, each >= 1
  size_t probeCount = 0;
  const uint32_t* cellStart = nullptr;  // cells + 1 prefix sums into `order`; cellStart[cells] == probeCount
  const uint32_t* order = nullptr;      // probe indices by cell
  const glm::vec3* positions = nullptr;
  const ShRgb* sh = nullptr;
};

// What renderLevel draws besides the mesh and the level, and how it times the GPU.
struct RenderOptions {
  std::vector<RenderLight> lights;  // kFull: the direct light (world frame)
  int shadowMapSize = 1024;         // kFull: texels per side of every shadow-map layer, 16..8192
  // The frame (every pass of the mode) is submitted warmupFrames + timedFrames times; RenderTimings hold the
  // median over the timed ones (the first frame carries lavapipe's shader compile). Each >= 0 and
  // timedFrames >= 1; the images are the last frame's (every frame renders the same).
  int warmupFrames = 0;
  int timedFrames = 1;
  // The lookup's shader variant in the lighting pass (lighting.comp specialized; runtime/shader_variant.h).
  // Empty: the level's own, shaderVariantFor(level, query.outerCells(), query.cellGrid()). A variant that
  // does not cover the level answers wrongly where the level uses what it leaves out.
  std::optional<ShaderVariant> variant;
  // The level's GPU buffers as bytes to upload in place of packing `level` (e.g. a GpuSectorPool's buffers(),
  // gpu_sector_pool.h, with its variant() in `variant`, which is then required). `level` still gives the
  // origin and the probes' dots. Must stay valid during the call. Null: packLevelBuffers(level, query...).
  const PackedLevelBuffers* levelBuffers = nullptr;
  // SPIR-V replacing lighting.comp (same interface and specialization constants; e.g. a debug build of the
  // lookup, for tests). Must stay valid during the call. Null: lighting.comp.
  const uint32_t* lightingSpirv = nullptr;
  size_t lightingSpirvBytes = 0;
  // Benchmark passes over the same G-buffer, each timed in a command buffer of its own before the lighting
  // pass (whose output then overwrites theirs), PassTiming names "lookup:" + ShaderVariant::name() for each
  // of benchVariants, "ambient" (benchAmbient: writes a constant E, the floor of a full-screen pass) and
  // "grid_texture" (benchGrid: the trilinear SH grid read from seven 3D textures with hardware filtering,
  // shaders/lighting_grid_texture.comp; RGBA32F when the device filters it linearly, else RGBA16F).
  std::vector<ShaderVariant> benchVariants;
  bool benchAmbient = false;
  const RenderGrid* benchGrid = nullptr;
  // The half-resolution lookup as well (shaders/tetraprobe_upsample.glsl: lighting_half.comp, one lookup per
  // 2x2 block, then lighting_upsample.comp), in the lighting pass's variant, on the same G-buffer after the
  // bench passes; PassTiming "lookup_half" and "upsample"; its image in RenderResult::halfResolution. Levels,
  // modes kIrradiance and kIndirect only.
  bool halfResolution = false;
  // The temporal start as well (shaders/lighting_temporal.comp: the walk starts from last frame's tet of the
  // pixel, reprojected): 0 = off, else 2..32 frames of a straight camera path that ends at the view, the eye
  // and target moving temporalStep (world metres) a frame. Each frame before the view's renders its G-buffer
  // (PassTiming "path_gbuffer"), the cold lookup ("lookup_cold") and the temporal one ("lookup_temporal";
  // the path's first, which has no tets from before, "lookup_temporal_first"); the view's own frame adds a
  // "lookup_temporal" after "lighting", its image in RenderResult::temporal. Levels, modes kIrradiance and
  // kIndirect only.
  int temporalFrames = 0;
  glm::vec3 temporalStep{0.0f};
};

struct RenderResult {
  Image color;     // per RenderView::mode; a = 1 on geometry; background pixels are 0 (all four channels)
  Image position;  // level local frame, metres; a = 1 where geometry, all 0 elsewhere
  Image normal;    // unit normal of the visible triangle (a = 1 where geometry)
  Image albedo;    // albedo of the visible triangle (a = 1 where geometry)
  // With RenderOptions::halfResolution: the upsampled half-resolution lookup, rgb as `color`, a = how each
  // pixel was answered: 0 background, 1 interpolated, 2 its block's own lookup, 3 looked up at full resolution.
  Image halfResolution;
  // With RenderOptions::temporalFrames: the view's lookup started from the path's previous frame's tets (rgb
  // as `color`, which it equals up to rounding; a = 2 where the previous frame's tet of the reprojected pixel
  // holds the point, 1 on other geometry, 0 on background).
  Image temporal;
  RenderTimings timings;
  ShaderVariant variant;   // the lighting pass's (levels only)
  std::string deviceName;  // the Vulkan device's (VkPhysicalDeviceProperties::deviceName)
  // With RenderOptions::benchGrid: the textures' format ("rgba32f" or "rgba16f") and bytes (7 texels a node).
  std::string gridTextureFormat;
  uint64_t gridTextureBytes = 0;
};

// Renders `mesh` lit by `level` (whose ProbeQuery `query` provides the start grid) from `view`. Creates its
// own Vulkan instance (no surface) and device (prefers lavapipe, else the first device with a
// graphics+compute queue), and destroys every Vulkan object before returning. Set TETRAPROBE_VK_VALIDATION=1
// to enable VK_LAYER_KHRONOS_validation when installed. Throws std::runtime_error with a one-line message on
// failure (no Vulkan device, bad view size, out of memory, ...).
// Probe kinds (kProbes) come from Level::probeKinds. `options` adds lights (kFull) and frame counts.
RenderResult renderLevel(const RenderMesh& mesh, const Level& level, const ProbeQuery& query,
                         const RenderView& view, const RenderOptions& options = {});

// renderLevel with the grid's trilinear lookup in the lighting pass (same G-buffer, same timings); modes
// kIrradiance and kIndirect only. The local
// frame's origin is glm::round(min + (dims - 1) x step / 2), the grid's centre in whole metres:
// RenderResult::position is relative to it. Throws std::runtime_error as renderLevel, and for dims below 2,
// a step that is not positive or no SH.
RenderResult renderGridVolume(const RenderMesh& mesh, const RenderGrid& grid, const RenderView& view);

// The same with the nearest probe's SH per pixel (shaders/lighting_nearest.comp, which mirrors
// NearestProbe::nearest), for timing the `nearest` method on the GPU. The local frame is nearest.origin.
// Throws std::runtime_error as renderLevel, and for buckets that are empty or do not hold every probe.
RenderResult renderNearestProbe(const RenderMesh& mesh, const RenderNearest& nearest, const RenderView& view);

// Scale that maps the 95th percentile of luminance (Rec. 709 weights) over geometry pixels (a > 0) to 0.8.
// Returns 1 when there is no geometry or the percentile is not positive.
float autoExposure(const Image& image);

// Writes an 8-bit sRGB RGB PNG: per channel v = x * exposure, clamped to >= 0, Reinhard v / (1 + v), then the
// sRGB transfer function, rounded. Written atomically (tetraprobe::writeFileAtomic). Returns false and sets
// `error` (one line) on failure.
bool writePng(const std::string& path, const Image& image, float exposure, std::string* error);

// Writes an 8-bit sRGB RGB PNG without tone mapping: per channel x clamped to [0, 1] (NaN -> 0), then the sRGB
// transfer function, rounded. For false-colour images whose values are already display colours (linear RGB),
// such as the error heat map. Written atomically. Returns false and sets `error` (one line) on failure.
bool writePngLinear(const std::string& path, const Image& image, std::string* error);

// Writes linear 32-bit float RGBA OpenEXR (ZIP compression) atomically. Returns false and sets `error`.
bool writeExr(const std::string& path, const Image& image, std::string* error);

}  // namespace tetraprobe
