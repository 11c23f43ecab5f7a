// halfResolutionError on hand-made image pairs whose figures are known in closed form.
#include <gtest/gtest.h>

#include <algorithm>
#include <stdexcept>

#include "tetraprobe/eval/half_resolution_error.h"

namespace tetraprobe {
namespace {

Image grey(int w, int h, float v, float a) {
  Image im;
  im.width = w;
  im.height = h;
  im.rgba.assign(size_t(w) * size_t(h) * 4, v);
  for (size_t i = 3; i < im.rgba.size(); i += 4) im.rgba[i] = a;
  return im;
}

void setPixel(Image& im, size_t i, float v, float a) {
  im.rgba[4 * i] = im.rgba[4 * i + 1] = im.rgba[4 * i + 2] = v;
  im.rgba[4 * i + 3] = a;
}

TEST(HalfResolutionError, IdenticalImagesHaveNoError) {
  const Image full = grey(10, 10, 2.0f, 1.0f);
  const Image half = grey(10, 10, 2.0f, 2.0f);
  const HalfResolutionError e = halfResolutionError(full, half);
  EXPECT_EQ(e.pixels, 100u);
  EXPECT_DOUBLE_EQ(e.meanRel, 0.0);
  EXPECT_DOUBLE_EQ(e.maxRel, 0.0);
  EXPECT_DOUBLE_EQ(e.copied, 1.0);
  EXPECT_DOUBLE_EQ(e.floor, 0.1);  // 5 % of the mean luminance 2 (grey: Y = the value)
}

// 100 pixels of Y = 1 (floor 0.05): 10 half pixels 20 % brighter, one 50 % darker, the rest exact; the codes
// say 50 interpolated, 25 own, 25 full lookups. Background pixels (full.a = 0) are not scored.
TEST(HalfResolutionError, FiguresCountEachPixelOnceAgainstTheFullValue) {
  Image full = grey(10, 11, 1.0f, 1.0f), half = grey(10, 11, 1.0f, 1.0f);
  for (size_t i = 100; i < 110; ++i) {
    setPixel(full, i, 0.0f, 0.0f);
    setPixel(half, i, 7.0f, 0.0f);  // a background pixel that differs: ignored
  }
  for (size_t i = 0; i < 100; ++i) half.rgba[4 * i + 3] = i < 50 ? 1.0f : i < 75 ? 2.0f : 3.0f;
  for (size_t i = 0; i < 10; ++i) setPixel(half, i, 1.2f, 1.0f);
  setPixel(half, 20, 0.5f, 1.0f);
  const HalfResolutionError e = halfResolutionError(full, half);
  EXPECT_EQ(e.pixels, 100u);
  EXPECT_NEAR(e.floor, 0.05, 1e-12);
  EXPECT_NEAR(e.meanRel, (10 * 0.2 + 0.5) / 100.0, 1e-6);
  EXPECT_NEAR(e.maxRel, 0.5, 1e-6);
  EXPECT_NEAR(e.over5, 0.11, 1e-12);
  EXPECT_NEAR(e.over25, 0.01, 1e-12);
  EXPECT_NEAR(e.p95Rel, 0.2, 1e-6);  // the 95th of 100 sorted values: inside the ten 0.2s
  EXPECT_NEAR(e.interpolated, 0.5, 1e-12);
  EXPECT_NEAR(e.copied, 0.25, 1e-12);
  EXPECT_NEAR(e.fullLookup, 0.25, 1e-12);
}

// Near-black pixels are measured against the floor, not their own value: 0.001 -> 0.002 is 0.001 / floor.
TEST(HalfResolutionError, DarkPixelsAreMeasuredAgainstTheFloor) {
  Image full = grey(2, 1, 1.0f, 1.0f), half = full;
  setPixel(full, 1, 0.001f, 1.0f);
  setPixel(half, 1, 0.002f, 1.0f);
  const HalfResolutionError e = halfResolutionError(full, half);
  const double floor = std::max(0.05 * (1.0 + 0.001) / 2.0, 0.01);
  EXPECT_NEAR(e.floor, floor, 1e-7);
  EXPECT_NEAR(e.maxRel, 0.001 / floor, 1e-5);
}

TEST(HalfResolutionError, RejectsImagesOfDifferentSizes) {
  EXPECT_THROW(halfResolutionError(grey(4, 4, 1.0f, 1.0f), grey(4, 5, 1.0f, 1.0f)), std::invalid_argument);
  const HalfResolutionError none = halfResolutionError(grey(3, 3, 1.0f, 0.0f), grey(3, 3, 1.0f, 0.0f));
  EXPECT_EQ(none.pixels, 0u);
  EXPECT_DOUBLE_EQ(none.meanRel, 0.0);
}

}  // namespace
}  // namespace tetraprobe
