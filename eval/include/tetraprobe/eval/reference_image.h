// Path-traced reference irradiance per pixel, at the camera of the Vulkan renderer (render/render.h), and the
// probe lookup at the same surface points: the ground truth a level designer compares the probes with
// (`tetraprobe render --mode reference|error`). Build side: traces with Embree through SceneTracer.
//
// Frames and units: the scene, the view and every position are in world metres (right-handed, the frame the
// scene loader produced); irradiance is in W/m^2 with the light content the caller asks for (normally the
// level's, Level::content). Images are row-major, row 0 = top: index = y * width + x.
#pragma once

#include <cstdint>
#include <vector>

#include <glm/vec3.hpp>

#include "tetraprobe/bake/bake.h"
#include "tetraprobe/bake/tracer.h"
#include "tetraprobe/render/render.h"
#include "tetraprobe/runtime/level.h"
#include "tetraprobe/runtime/query.h"

namespace tetraprobe {

// Path depth: kUnboundedBounces (bake/bake.h), Russian roulette only, is the unbiased reference.

// What the pixel-centre primary ray of each pixel meets first, back faces stepped through as the Vulkan
// renderer culls them (a cut-away view shows the room behind the back of its ceiling in both).
struct ReferenceGBuffer {
  int width = 0, height = 0;
  std::vector<uint8_t> hit;          // 1 where the ray met a triangle, 0 for background
  std::vector<glm::dvec3> position;  // world metres, on the triangle (from barycentrics); 0 for background
  std::vector<glm::vec3> normal;   // unit geometric normal (front face: towards the camera); 0 for background
  std::vector<uint32_t> triangle;  // index into Scene::triangles; 0 for background
  size_t hitCount() const;
};

// Casts the primary ray through every pixel centre of `view` (pixelRayDirection: the renderer's camera) and
// records the first front-face hit in (0, infinity) (a ray stepping through more than 64 back faces counts as
// background). view.width x view.height pixels, each in 1..16384 (else
// InputError). Allocates the four per-pixel arrays. Parallel over rows on up to `threads` threads (0 = all
// cores); the result does not depend on the thread count.
ReferenceGBuffer traceReferenceGBuffer(const SceneTracer& tracer, const RenderView& view, int threads = 0);

struct ReferenceImageOptions {
  int samplesPerPixel = 64;  // paths per hit pixel (the budget's cap); >= 1
  double maxSeconds =
      0.0;                 // > 0: stop after the first pass that ends past this wall time (G-buffer included)
  int samplesPerPass = 8;  // paths per pixel per pass (the last pass may take fewer); >= 1
  int bounces = kUnboundedBounces;     // BakeOptions::bounces for referenceIrradiance
  uint32_t content = kContentDefault;  // ProbeContent flags: pass Level::content to compare with a level
  uint64_t seed = 0x2e5e2e11ceull;
  int threads = 0;       // 0 = all cores; never changes the result
  bool progress = true;  // progress bar on a terminal
};

struct ReferenceImage {
  ReferenceGBuffer gbuffer;
  std::vector<glm::vec3> irradiance;  // W/m^2 per pixel: mean of the paths; 0 for background
  std::vector<glm::vec3> stderror;    // standard error of that mean per channel; 0 for background
  int samplesPerPixel = 0;            // paths every hit pixel received (the same for all)
  int passes = 0;
  double seconds = 0.0;  // wall time of the whole call
  // Mean over hit pixels of stderr(Y) / sqrt(Y^2 + 0.01) (Y = Rec. 709 luminance; evaluation's floor): how
  // far to trust the image. 0 without hit pixels.
  double meanRelStderr() const;
};

// The reference irradiance at every hit pixel of `view`: referenceIrradiance (bake/bake.h) at the G-buffer's
// point with its camera-facing normal, options.content and options.bounces, progressively: passes of
// options.samplesPerPass paths per pixel merged into a running mean and variance (Chan et al.'s pairwise
// update) until options.samplesPerPixel paths, or until options.maxSeconds has passed at the end of a
// pass (at least one pass always runs). Each pixel's pass k is seeded from (options.seed, pixel index, k)
// alone, so for a given number of passes the image does not depend on the thread count or on other pixels;
// under a time limit the number of passes is what depends on the machine. Parallel over pixels
// (parallelFor). Throws InputError for samplesPerPixel or samplesPerPass < 1, bounces < 0, maxSeconds < 0 or
// a bad view size. Allocates the G-buffer and two vec3 arrays per pixel (plus 48 bytes per pixel while
// running).
ReferenceImage renderReferenceImage(const SceneTracer& tracer, const RenderView& view,
                                    const ReferenceImageOptions& options);

// The CPU probe lookup at every hit pixel of `gbuffer`: query.irradiance(position, normal) (W/m^2, the
// level's stored occlusion applied as the runtime applies it), 0 for background. The same surface points and
// normals the reference used; per pixel it matches the GPU lookup of shaders/tetraprobe.glsl within 1e-4
// where the renderer sees the same front face. Allocates one vec3 per pixel. Up to `threads` threads.
std::vector<glm::vec3> probeLookupImage(const ProbeQuery& query, const ReferenceGBuffer& gbuffer,
                                        int threads = 0);

}  // namespace tetraprobe
