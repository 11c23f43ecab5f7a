// The path-traced reference image (eval/reference_image.h): it sees the pixels the Vulkan renderer sees, it
// equals closed forms, and its randomness is keyed per pixel and pass, never per thread.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numbers>
#include <optional>
#include <stdexcept>
#include <string>

#include <glm/geometric.hpp>

#include "missing_capability.h"
#include "test_levels.h"
#include "tetraprobe/common/error.h"
#include "tetraprobe/eval/reference_image.h"
#include "tetraprobe/runtime/query.h"

namespace tetraprobe {
namespace {

constexpr double kPi = std::numbers::pi;

ReferenceImageOptions quietOptions(int samples) {
  ReferenceImageOptions o;
  o.samplesPerPixel = samples;
  o.progress = false;
  return o;
}

// Under a gradient sky (zenith Z at +Y, horizon H, linear in y) an upward plane receives E = pi H +
// 2 pi (Z - H) / 3 (tests/bake/test_reference.cpp) and nothing else: the plane cannot light itself. Every
// pixel looks at the floor, so the image must be that constant: the mean over pixels within 4 standard errors
// of the mean, and at least 95 % of pixels within 3 of their own standard errors (16 paths each; the
// estimate of a standard error from 16 paths is itself rough, hence not 99.7 %).
TEST(ReferenceImage, FloorUnderGradientSkyMatchesClosedForm) {
  Scene s = test::floorUnderSky(glm::vec3(0.6f), glm::vec3(0.0f));
  s.skyRadiance = {2.0f, 1.5f, 0.5f};
  s.skyHorizonRadiance = {0.5f, 1.0f, 1.0f};
  const SceneTracer tracer(s);
  const RenderView view = test::floorView();
  const ReferenceImage img = renderReferenceImage(tracer, view, quietOptions(16));
  ASSERT_EQ(img.gbuffer.hitCount(), size_t(view.width * view.height)) << "every pixel should see the floor";
  EXPECT_EQ(img.samplesPerPixel, 16);
  EXPECT_EQ(img.passes, 2);
  for (int ch = 0; ch < 3; ++ch) {
    const double z = s.skyRadiance[ch], h = s.skyHorizonRadiance[ch];
    const double exact = kPi * h + 2.0 * kPi * (z - h) / 3.0;
    double sum = 0.0, var = 0.0;
    size_t within = 0;
    const size_t n = img.irradiance.size();
    for (size_t i = 0; i < n; ++i) {
      const double e = img.irradiance[i][ch], se = img.stderror[i][ch];
      sum += e;
      var += se * se;
      within += std::abs(e - exact) <= 3.0 * se + 1e-5 * exact;
      EXPECT_NEAR(img.gbuffer.position[i].y, 0.0, 1e-5) << "pixel " << i;
      EXPECT_EQ(img.gbuffer.normal[i], glm::vec3(0, 1, 0)) << "pixel " << i;
    }
    const double mean = sum / double(n), meanStderr = std::sqrt(var) / double(n);
    EXPECT_NEAR(mean, exact, 4.0 * meanStderr + 1e-6 * exact) << "channel " << ch;
    EXPECT_GT(meanStderr, 0.0) << "channel " << ch << ": the sky gradient should make the paths vary";
    EXPECT_GE(double(within), 0.95 * double(n)) << "channel " << ch;
  }
}

// A uniform sky of radiance L over a plane gives E = pi L on every path (zero variance): the reference must
// be exact per pixel, and background pixels (sky above the horizon) stay 0.
TEST(ReferenceImage, UniformSkyGivesPiLOnEveryFloorPixelAndZeroOnBackground) {
  const glm::vec3 sky(1.0f, 2.0f, 0.25f);
  const Scene scene = test::floorUnderSky(glm::vec3(0.5f), sky);
  const SceneTracer tracer(scene);
  RenderView view = test::floorView(32, 24);
  view.target = {0.0f, 2.5f, -5.0f};  // looking at the horizon: the top of the image is sky
  const ReferenceImage img = renderReferenceImage(tracer, view, quietOptions(4));
  const size_t hits = img.gbuffer.hitCount();
  ASSERT_GT(hits, size_t(0));
  ASSERT_LT(hits, img.irradiance.size());
  for (size_t i = 0; i < img.irradiance.size(); ++i) {
    if (!img.gbuffer.hit[i]) {
      EXPECT_EQ(img.irradiance[i], glm::vec3(0.0f)) << "background pixel " << i;
      continue;
    }
    for (int ch = 0; ch < 3; ++ch) EXPECT_NEAR(img.irradiance[i][ch], kPi * sky[ch], 1e-5 * kPi * sky[ch]);
  }
  // Row 0 is the top: the sky is there, the floor at the bottom.
  EXPECT_FALSE(img.gbuffer.hit[0]);
  EXPECT_TRUE(img.gbuffer.hit[img.gbuffer.hit.size() - 1]);
}

// Passes of 3 paths up to 7 give passes 3, 3, 1; the image is bit-identical on one and on two threads, and
// a time limit already reached stops after the first pass.
TEST(ReferenceImage, ResultDoesNotDependOnThreadsAndTimeLimitStopsAfterAPass) {
  Scene s = test::floorUnderSky(glm::vec3(0.6f), glm::vec3(1.0f));
  s.skyHorizonRadiance = {0.2f, 0.3f, 0.4f};
  const uint32_t box = test::addMaterial(s, glm::vec3(0.7f, 0.4f, 0.2f));
  test::addBox(s, {-0.5f, 0.0f, -0.5f}, {0.5f, 1.0f, 0.5f}, false, box);
  const SceneTracer tracer(s);
  ReferenceImageOptions o = quietOptions(7);
  o.samplesPerPass = 3;
  o.threads = 1;
  const RenderView view = test::floorView(24, 16);
  const ReferenceImage one = renderReferenceImage(tracer, view, o);
  o.threads = 2;
  const ReferenceImage two = renderReferenceImage(tracer, view, o);
  EXPECT_EQ(one.passes, 3);
  EXPECT_EQ(one.samplesPerPixel, 7);
  EXPECT_EQ(one.irradiance, two.irradiance);
  EXPECT_EQ(one.stderror, two.stderror);
  o.maxSeconds = 1e-9;
  const ReferenceImage limited = renderReferenceImage(tracer, view, o);
  EXPECT_EQ(limited.passes, 1);
  EXPECT_EQ(limited.samplesPerPixel, 3);
}

TEST(ReferenceImage, RejectsBadBudgets) {
  const Scene scene = test::floorUnderSky(glm::vec3(0.5f), glm::vec3(1.0f));
  const SceneTracer tracer(scene);
  ReferenceImageOptions o = quietOptions(0);
  EXPECT_THROW(renderReferenceImage(tracer, test::floorView(4, 4), o), InputError);
  o.samplesPerPixel = 4;
  o.bounces = -1;
  EXPECT_THROW(renderReferenceImage(tracer, test::floorView(4, 4), o), InputError);
  o.bounces = 2;
  EXPECT_THROW(renderReferenceImage(tracer, test::floorView(0, 4), o), InputError);
}

// ---- Camera agreement with the Vulkan renderer ----

// A finite floor with three crates of different sizes off-centre, all outward-facing: the camera above
// sees only front faces (the renderer culls back faces; the reference would show them), and the layout has
// no symmetry a flipped or mirrored camera could hide behind.
Scene cratesScene() {
  Scene s;
  const uint32_t floor = test::addMaterial(s, glm::vec3(0.5f));
  const uint32_t crate = test::addMaterial(s, glm::vec3(0.8f, 0.3f, 0.2f));
  test::addGround(s, 0.0f, 3.0f, floor);
  test::addBox(s, {-2.0f, 0.0f, -1.5f}, {-0.8f, 1.6f, -0.2f}, false, crate);
  test::addBox(s, {0.6f, 0.0f, 0.4f}, {1.4f, 0.6f, 1.0f}, false, crate);
  test::addBox(s, {1.2f, 0.0f, -2.5f}, {1.6f, 2.2f, -2.1f}, false, crate);
  s.skyRadiance = glm::vec3(1.0f);
  s.skyHorizonRadiance = glm::vec3(1.0f);
  return s;
}

RenderMesh toRenderMesh(const Scene& scene) {
  RenderMesh mesh;
  mesh.positions = scene.positions;
  mesh.triangles = scene.triangles;
  for (uint32_t m : scene.triangleMaterial) mesh.triangleAlbedo.push_back(scene.materials[m].albedo);
  return mesh;
}

RenderView cratesView() {
  RenderView v;
  v.eye = {3.5f, 4.0f, 6.0f};
  v.target = {-0.3f, 0.4f, -0.5f};
  v.fovYDeg = 45.0f;
  v.width = 64;
  v.height = 48;
  v.mode = RenderMode::kIrradiance;
  return v;
}

// The Vulkan render of `scene` lit by `level`, or nothing (and `why`) on a machine without a Vulkan device.
std::optional<RenderResult> vulkanRender(const Scene& scene, const Level& level, const ProbeQuery& query,
                                         const RenderView& view, std::string& why) {
  try {
    return renderLevel(toRenderMesh(scene), level, query, view);
  } catch (const std::runtime_error& e) {
    if (!test::isNoVulkan(e.what())) throw;
    why = e.what();
    return std::nullopt;
  }
}

// Fraction of pixels whose hit/miss agrees, and fraction of pixels hit by both whose points lie within
// `tolerance` metres.
struct Agreement {
  double mask = 0.0, position = 0.0;
  size_t hitsVulkan = 0, hitsReference = 0;
};

Agreement compare(const RenderResult& vk, const ReferenceGBuffer& g, const glm::dvec3& origin,
                  double tolerance) {
  Agreement a;
  size_t same = 0, both = 0, close = 0;
  for (size_t i = 0; i < g.hit.size(); ++i) {
    const bool hv = vk.position.rgba[4 * i + 3] > 0.0f, hr = g.hit[i] != 0;
    a.hitsVulkan += hv;
    a.hitsReference += hr;
    same += hv == hr;
    if (!(hv && hr)) continue;
    ++both;
    const glm::dvec3 p = origin + glm::dvec3(vk.position.rgba[4 * i], vk.position.rgba[4 * i + 1],
                                             vk.position.rgba[4 * i + 2]);
    close += glm::length(p - g.position[i]) <= tolerance;
  }
  a.mask = double(same) / double(g.hit.size());
  a.position = both ? double(close) / double(both) : 0.0;
  return a;
}

// The reference G-buffer hits what the Vulkan G-buffer rasterizes: the same hit/miss mask on >= 99 % of
// pixels (they differ only where a triangle edge passes within rounding of a pixel centre) and, where both
// hit, the same point within 2 mm on >= 99 % of them. A pixel spans about 8 cm on the crates here, so a
// camera shifted by half a pixel (pixel corners instead of centres), flipped or mirrored fails both. The
// same check rejects an upside-down view: proof that it can fail.
TEST(ReferenceImage, GBufferAgreesWithVulkanRenderer) {
  const Scene scene = cratesScene();
  const SceneTracer tracer(scene);
  std::vector<glm::dvec3> probes = test::probeGrid();
  const Level level = test::bakedLevel(tracer, probes, 64);
  const ProbeQuery query(level);
  const RenderView view = cratesView();
  std::string why;
  const std::optional<RenderResult> vk = vulkanRender(scene, level, query, view, why);
  if (!vk) TETRAPROBE_SKIP_MISSING(why);
  const ReferenceGBuffer g = traceReferenceGBuffer(tracer, view);
  const Agreement a = compare(*vk, g, level.origin, 2e-3);
  std::printf("mask agreement %.4f, position agreement %.4f (%zu Vulkan hits, %zu reference hits of %d)\n",
              a.mask, a.position, a.hitsVulkan, a.hitsReference, view.width * view.height);
  EXPECT_GE(a.mask, 0.99);
  EXPECT_GE(a.position, 0.99);
  EXPECT_GT(a.hitsVulkan, size_t(view.width * view.height / 4))
      << "the crates and floor should fill the view";
  EXPECT_LT(a.hitsVulkan, size_t(view.width * view.height)) << "some background should frame the silhouette";

  RenderView flipped = view;
  flipped.up = -view.up;  // the image turned upside down
  const Agreement f = compare(*vk, traceReferenceGBuffer(tracer, flipped), level.origin, 2e-3);
  EXPECT_LT(f.mask, 0.99);
  EXPECT_LT(f.position, 0.5);

  // Rays through pixel corners instead of centres (half a pixel off): the silhouettes still mostly agree,
  // the points do not.
  size_t close = 0, both = 0;
  for (int y = 0; y < view.height; ++y)
    for (int x = 0; x < view.width; ++x) {
      const size_t i = size_t(y) * view.width + x;
      if (!(vk->position.rgba[4 * i + 3] > 0.0f)) continue;
      const Hit h = tracer.intersect(view.eye, glm::vec3(pixelRayDirection(view, x, y)), 0.0f, 1e30f);
      if (!h.hit) continue;
      ++both;
      const glm::dvec3 p = glm::dvec3(view.eye) + glm::dvec3(pixelRayDirection(view, x, y)) * double(h.t);
      const glm::dvec3 q(vk->position.rgba[4 * i], vk->position.rgba[4 * i + 1],
                         vk->position.rgba[4 * i + 2]);
      close += glm::length(p - (level.origin + q)) <= 2e-3;
    }
  EXPECT_LT(double(close), 0.5 * double(both)) << "a half-pixel shift must not pass the position check";
}

// A cut-away view: the crates inside a closed room (faces pointing in), the camera outside above it. The
// rasterizer culls the walls' and ceiling's back faces and shows the crates; the reference G-buffer steps
// through the back faces and meets the same points (the agreement above), all front faces. Without the
// stepping most pixels would be the room's unlit outside: the first hit of most rays is a back face here.
TEST(ReferenceImage, GBufferStepsThroughBackFacesLikeTheRasterizer) {
  Scene scene = cratesScene();
  // Around the 6 m ground, clear of it (coincident surfaces would leave the rasterizer's depth test to
  // rounding).
  test::addBox(scene, {-3.3f, -0.05f, -3.3f}, {3.3f, 2.6f, 3.3f}, true, scene.triangleMaterial[0]);
  const SceneTracer tracer(scene);
  const Level level = test::bakedLevel(tracer, test::probeGrid(), 16);
  const ProbeQuery query(level);
  const RenderView view = cratesView();
  size_t backFirst = 0;
  for (int y = 0; y < view.height; ++y)
    for (int x = 0; x < view.width; ++x) {
      const Hit h = tracer.intersect(view.eye, glm::vec3(pixelRayDirection(view, x + 0.5, y + 0.5)), 0.0f,
                                     std::numeric_limits<float>::infinity());
      backFirst += h.hit && !h.frontFace;
    }
  ASSERT_GT(backFirst, size_t(view.width * view.height / 4)) << "the view must look through back faces";
  std::string why;
  const std::optional<RenderResult> vk = vulkanRender(scene, level, query, view, why);
  if (!vk) TETRAPROBE_SKIP_MISSING(why);
  const ReferenceGBuffer g = traceReferenceGBuffer(tracer, view);
  const Agreement a = compare(*vk, g, level.origin, 2e-3);
  std::printf("%zu of %d rays meet a back face first; mask agreement %.4f, position agreement %.4f\n",
              backFirst, view.width * view.height, a.mask, a.position);
  EXPECT_GE(a.mask, 0.99);
  EXPECT_GE(a.position, 0.99);
  for (size_t i = 0; i < g.hit.size(); ++i) {
    if (!g.hit[i]) continue;
    const glm::dvec3 toEye = glm::dvec3(view.eye) - g.position[i];
    ASSERT_GT(glm::dot(glm::dvec3(g.normal[i]), toEye), 0.0) << "pixel " << i << ": a back face";
  }
}

}  // namespace
}  // namespace tetraprobe
