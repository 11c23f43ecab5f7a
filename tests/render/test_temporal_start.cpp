// The temporal start (shaders/lighting_temporal.comp; RenderOptions::temporalFrames): the lookup started from
// last frame's tet of the reprojected pixel answers as the cold lookup does, whether the hints are right
// (small steps) or often wrong (steps of metres: disoccluded pixels, pixels off screen last frame).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "lookup_scene.h"

namespace tetraprobe {
namespace {

using test::makeLevel;
using test::makeMesh;
using test::makeView;
using test::px3;
using test::syntheticOcclusion;

// Renders a path of `frames` ending at the lookup scene's view, `step` metres a frame, and compares the
// view's temporal answer with its cold one pixel by pixel (the GPU-vs-CPU tolerance, 1e-4 relative).
// Returns the share of geometry pixels whose previous tet held them (a = 2).
double expectTemporalEqualsCold(const Level& level, int frames, glm::vec3 step, RenderMode mode) {
  const ProbeQuery query(level);
  RenderOptions options;
  options.temporalFrames = frames;
  options.temporalStep = step;
  RenderResult r;
  std::string skip;
  if (!test::render(makeMesh(), level, query, makeView(mode, 320, 180), r, skip, options)) return -1.0;
  EXPECT_EQ(r.temporal.rgba.size(), r.color.rgba.size());
  if (r.temporal.rgba.size() != r.color.rgba.size()) return 0.0;
  size_t geometry = 0, bad = 0, held = 0;
  double worst = 0.0;
  for (size_t i = 0; i < r.color.rgba.size() / 4; ++i) {
    if (r.position.rgba[4 * i + 3] == 0.0f) {
      EXPECT_EQ(px3(r.temporal, i), glm::vec3(0.0f));
      continue;
    }
    ++geometry;
    held += r.temporal.rgba[4 * i + 3] == 2.0f;
    const glm::vec3 a = px3(r.color, i), b = px3(r.temporal, i);
    for (int c = 0; c < 3; ++c) {
      const double rel = std::abs(double(a[c]) - b[c]) / std::max(std::abs(double(a[c])), 1e-6);
      worst = std::max(worst, rel);
      if (rel > 1e-4 && bad++ < 5)
        ADD_FAILURE() << "pixel " << i << ": cold " << a[c] << ", temporal " << b[c];
    }
  }
  size_t temporalPasses = 0, firstPasses = 0;
  for (const PassTiming& p : r.timings.passes) {
    temporalPasses += p.name == "lookup_temporal";
    firstPasses += p.name == "lookup_temporal_first";
  }
  const double share = geometry ? double(held) / double(geometry) : 0.0;
  std::printf(
      "temporal start, %d frames of (%g, %g, %g) m: %zu geometry pixels, %.3f held by last frame's tet, "
      "worst "
      "relative difference %.3g\n",
      frames, step.x, step.y, step.z, geometry, share, worst);
  EXPECT_GT(geometry, 4000u);
  EXPECT_EQ(bad, 0u);
  if (!r.timings.passes.empty()) {  // a queue with timestamps: every frame's pass was recorded
    EXPECT_EQ(temporalPasses, size_t(frames - 1));
    EXPECT_EQ(firstPasses, 1u);
  }
  return share;
}

TEST(TemporalStart, AnswersAsTheColdLookupWithGoodHints) {
  Level level = makeLevel();
  level.occlusion = syntheticOcclusion(level);
  const double held = expectTemporalEqualsCold(level, 4, {0.02f, 0.0f, -0.01f}, RenderMode::kIrradiance);
  if (held < 0.0) TETRAPROBE_SKIP_MISSING("no Vulkan device");
  EXPECT_GT(held, 0.8) << "a 2 cm step keeps most points in their tet: the hints must reach the walk";
}

// Steps of metres: reprojection still finds most points (the scene is static), but disoccluded pixels and
// pixels that were off screen get hints from other surfaces or none, which the walk gives up on.
TEST(TemporalStart, AnswersAsTheColdLookupAcrossLargeSteps) {
  Level level = makeLevel();
  level.occlusion = syntheticOcclusion(level);
  const double held = expectTemporalEqualsCold(level, 3, {1.5f, -0.7f, 2.0f}, RenderMode::kIrradiance);
  if (held < 0.0) TETRAPROBE_SKIP_MISSING("no Vulkan device");
  EXPECT_LT(held, 0.8) << "metre steps: many hints must be wrong for this test to test them";
  expectTemporalEqualsCold(makeLevel(), 2, {-2.0f, 0.5f, 0.0f}, RenderMode::kIndirect);
}

TEST(TemporalStart, RefusesAPathOfOneFrame) {
  const Level level = makeLevel();
  const ProbeQuery query(level);
  RenderOptions options;
  options.temporalFrames = 1;
  RenderResult r;
  std::string skip;
  try {
    test::render(makeMesh(), level, query, makeView(RenderMode::kIrradiance, 16, 16), r, skip, options);
    ADD_FAILURE() << "a path of one frame has no previous frame: refused";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("temporal"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace tetraprobe
