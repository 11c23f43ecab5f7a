// The error image (eval/error_image.h): probes that are right are neutral, probes scaled by a known factor
// show exactly that many stops in the right colour, and the fixed scale and the floor behave as documented.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "test_levels.h"
#include "tetraprobe/eval/error_image.h"
#include "tetraprobe/eval/reference_image.h"
#include "tetraprobe/runtime/query.h"

namespace tetraprobe {
namespace {

// A black floor (albedo 0) under a uniform sky of radiance L: every path from the floor reaches the sky, so
// the reference is exactly pi L on every floor pixel, and each probe above the floor sees a hemisphere of
// radiance L over black. The L2 irradiance of that step, facing up, is exactly pi L too (bands 0 and 1 give
// pi L / 2 each, band 2 vanishes), and every probe holds it, so the lookup at the floor (below the hull,
// through the outer cells) is pi L up to the bake's quadrature noise.
struct BlackFloor {
  Scene scene = test::floorUnderSky(glm::vec3(0.0f), glm::vec3(0.8f, 1.0f, 1.3f));
  SceneTracer tracer{scene};
  Level level = test::bakedLevel(tracer, test::probeGrid());
  ReferenceImage reference = [this] {
    ReferenceImageOptions o;
    o.samplesPerPixel = 2;
    o.progress = false;
    return renderReferenceImage(tracer, test::floorView(), o);
  }();

  ErrorImage errorWithProbesScaledBy(float factor) {
    Level scaled = level;
    for (ShRgb& sh : scaled.sh)
      for (glm::vec3& c : sh.c) c *= factor;
    const ProbeQuery query(scaled);
    return computeErrorImage(reference.gbuffer, probeLookupImage(query, reference.gbuffer),
                             reference.irradiance);
  }
};

void expectEveryPixelNear(const ErrorImage& e, double stops, double tolerance) {
  ASSERT_GT(e.stats.pixels, size_t(0));
  for (size_t i = 0; i < e.hit.size(); ++i) {
    if (!e.hit[i]) continue;
    ASSERT_NEAR(e.log2Ratio[i], stops, tolerance) << "pixel " << i;
  }
}

TEST(ErrorImage, RightProbesAreNeutral) {
  BlackFloor f;
  const ErrorImage e = f.errorWithProbesScaledBy(1.0f);
  expectEveryPixelNear(e, 0.0, 0.02);
  EXPECT_EQ(e.stats.gross, 0.0);
  EXPECT_EQ(e.stats.darkHoles, 0.0);
  const Image heat = errorHeatMap(e);
  for (size_t i = 0; i < e.hit.size(); ++i) {  // near-white: #f7f7f7 and its neighbours
    EXPECT_GT(heat.rgba[4 * i + 0], 0.8f);
    EXPECT_GT(heat.rgba[4 * i + 2], 0.8f);
  }
}

// Probes twice too bright: +1 stop on every lit pixel, drawn red (red above blue), counted too bright only
// when beyond 2x, so exactly 2x sits on the boundary and 3x is gross.
TEST(ErrorImage, ProbesTwiceTooBrightAreRedAtPlusOneStop) {
  BlackFloor f;
  const ErrorImage e = f.errorWithProbesScaledBy(2.0f);
  expectEveryPixelNear(e, 1.0, 0.02);
  EXPECT_NEAR(e.stats.meanLog2, 1.0, 0.02);
  EXPECT_EQ(e.stats.darkHoles, 0.0);
  const Image heat = errorHeatMap(e);
  for (size_t i = 0; i < e.hit.size(); ++i) {
    EXPECT_GT(heat.rgba[4 * i + 0], 2.0f * heat.rgba[4 * i + 2]) << "pixel " << i << " should be red";
    EXPECT_EQ(heat.rgba[4 * i + 3], 1.0f);
  }
  const ErrorImage three = f.errorWithProbesScaledBy(3.0f);
  EXPECT_EQ(three.stats.gross, 1.0);
  EXPECT_EQ(three.stats.tooBright, 1.0);
  EXPECT_EQ(three.stats.tooDark, 0.0);
}

// Probes at a fifth: -2.32 stops, all gross, all dark holes, drawn blue.
TEST(ErrorImage, ProbesAtAFifthAreBlueDarkHoles) {
  BlackFloor f;
  const ErrorImage e = f.errorWithProbesScaledBy(0.2f);
  expectEveryPixelNear(e, std::log2(0.2), 0.02);
  EXPECT_EQ(e.stats.gross, 1.0);
  EXPECT_EQ(e.stats.tooDark, 1.0);
  EXPECT_EQ(e.stats.darkHoles, 1.0);
  const Image heat = errorHeatMap(e);
  for (size_t i = 0; i < e.hit.size(); ++i)
    EXPECT_GT(heat.rgba[4 * i + 2], 2.0f * heat.rgba[4 * i + 0]) << "pixel " << i << " should be blue";
  const Image values = errorValues(e);
  EXPECT_NEAR(values.rgba[0], std::log2(0.2), 0.02) << "EXR values are the unclamped ratio";
}

// Below the 0.01 W/m^2 floor both sides count as the floor: black in both (or nearly) is neutral, and a
// lookup of 0 against a reference of 0.02 is one stop too dark, not minus infinity.
TEST(ErrorImage, PixelsBlackInBothAreNeutral) {
  EXPECT_EQ(signedLog2Error(glm::vec3(0.0f), glm::vec3(0.0f)), 0.0f);
  EXPECT_EQ(signedLog2Error(glm::vec3(0.001f), glm::vec3(0.004f)), 0.0f);
  EXPECT_EQ(signedLog2Error(glm::vec3(-0.5f), glm::vec3(0.0f)), 0.0f) << "negative (ringing) lookups: 0";
  EXPECT_NEAR(signedLog2Error(glm::vec3(0.0f), glm::vec3(0.02f)), -1.0f, 1e-6f);
}

// The scale is fixed: e = 0 is the scheme's neutral #f7f7f7, +-2 its end classes, beyond clamps, and the
// two halves are red and blue.
TEST(ErrorImage, ColourScaleIsFixedAndDiverging) {
  auto srgb = [](float byte) {
    const float v = byte / 255.0f;
    return v <= 0.04045f ? v / 12.92f : std::pow((v + 0.055f) / 1.055f, 2.4f);
  };
  const glm::vec3 white = errorColor(0.0f), red = errorColor(2.0f), blue = errorColor(-2.0f);
  for (int c = 0; c < 3; ++c) EXPECT_NEAR(white[c], srgb(0xf7), 1e-6f);
  EXPECT_NEAR(red.r, srgb(0x67), 1e-6f);
  EXPECT_NEAR(red.b, srgb(0x1f), 1e-6f);
  EXPECT_NEAR(blue.r, srgb(0x05), 1e-6f);
  EXPECT_NEAR(blue.b, srgb(0x61), 1e-6f);
  EXPECT_EQ(errorColor(7.0f), red);
  EXPECT_EQ(errorColor(-7.0f), blue);
  for (float e : {0.25f, 0.5f, 1.0f, 1.5f}) {
    EXPECT_GT(errorColor(e).r, errorColor(e).b) << e;
    EXPECT_GT(errorColor(-e).b, errorColor(-e).r) << -e;
  }
}

}  // namespace
}  // namespace tetraprobe
