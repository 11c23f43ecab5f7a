// Rec. 709 luminance (runtime/luminance.h), the one definition every module calls: the BT.709 weights on
// each primary, and each precision kept (float arithmetic for float colours, double for double), so that the
// call sites that replaced their own copies give the bits they gave.
#include <gtest/gtest.h>

#include <random>

#include "tetraprobe/runtime/luminance.h"

namespace tetraprobe {
namespace {

TEST(Luminance, PrimariesWeighByRec709) {
  EXPECT_EQ(luminance(glm::dvec3(1, 0, 0)), 0.2126);
  EXPECT_EQ(luminance(glm::dvec3(0, 1, 0)), 0.7152);
  EXPECT_EQ(luminance(glm::dvec3(0, 0, 1)), 0.0722);
  EXPECT_EQ(luminance(glm::vec3(1, 0, 0)), 0.2126f);
  EXPECT_EQ(luminance(glm::vec3(0, 1, 0)), 0.7152f);
  EXPECT_EQ(luminance(glm::vec3(0, 0, 1)), 0.0722f);
  EXPECT_NEAR(luminance(glm::dvec3(1.0)), 1.0, 1e-15);  // white keeps its value
}

// Each overload computes in its argument's precision, left to right: the float form is the float
// expression's bits and the double form (of a float colour converted exactly) the double expression's; the two
// differ on some colours, which is why a caller's precision is kept by the overload it calls.
TEST(Luminance, EachPrecisionGivesItsOwnExpressionsBits) {
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<float> u(-10.0f, 1000.0f);
  int differ = 0;
  for (int i = 0; i < 10000; ++i) {
    const glm::vec3 c(u(rng), u(rng), u(rng));
    const float f = 0.2126f * c.r + 0.7152f * c.g + 0.0722f * c.b;
    const double d = 0.2126 * double(c.r) + 0.7152 * double(c.g) + 0.0722 * double(c.b);
    ASSERT_EQ(luminance(c), f) << c.r << ", " << c.g << ", " << c.b;
    ASSERT_EQ(luminance(glm::dvec3(c)), d) << c.r << ", " << c.g << ", " << c.b;
    differ += double(f) != d;
  }
  EXPECT_GT(differ, 1000);
}

}  // namespace
}  // namespace tetraprobe
