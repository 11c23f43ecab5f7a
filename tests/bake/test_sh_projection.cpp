// The bake's SH projection (bakeSphereDirections + projectToSh, addDeltaToSh) against closed forms.
// Tolerance 1e-4 absolute: the spherical Fibonacci set with 2^20 points integrates these functions far more
// accurately than that (error ~N^-3/4 for the kinked cosine lobe), and float directions add ~1e-7.
#include <cmath>
#include <numbers>

#include <gtest/gtest.h>
#include <glm/geometric.hpp>

#include "tetraprobe/bake/bake.h"

namespace tetraprobe {
namespace {

constexpr int kDirections = 1 << 20;
constexpr double kTol = 1e-4;

// A constant environment lives in the DC term only: L00 = c sqrt(4 pi), everything else zero.
TEST(ShProjection, ConstantRadianceProjectsToL00Only) {
  const std::vector<glm::vec3> dirs = bakeSphereDirections(kDirections, 123);
  const glm::vec3 c(0.5f, 1.0f, 2.0f);
  const ShRgb sh = projectToSh(dirs, std::vector<glm::vec3>(dirs.size(), c));
  const double s = std::sqrt(4.0 * std::numbers::pi);
  for (int ch = 0; ch < 3; ++ch) {
    EXPECT_NEAR(sh.c[0][ch], c[ch] * s, kTol * c[ch] * s);
    for (int i = 1; i < kShCoeffCount; ++i) EXPECT_NEAR(sh.c[i][ch], 0.0, kTol) << "coefficient " << i;
  }
}

// The clamped cosine lobe max(0, z) is the textbook zonal function: L00 = sqrt(pi)/2, L10 = sqrt(pi/3),
// L20 = sqrt(5 pi)/8, the rest zero. It checks the basis ordering (index 2 is z, 6 is 3z^2-1) and the
// 4 pi / N normalisation together.
TEST(ShProjection, ClampedCosineMatchesAnalyticCoefficients) {
  const std::vector<glm::vec3> dirs = bakeSphereDirections(kDirections, 99);
  std::vector<glm::vec3> radiance(dirs.size());
  for (size_t k = 0; k < dirs.size(); ++k) radiance[k] = glm::vec3(std::max(0.0f, dirs[k].z));
  const ShRgb sh = projectToSh(dirs, radiance);
  const double pi = std::numbers::pi;
  const double expected[kShCoeffCount] = {
      std::sqrt(pi) / 2, 0, std::sqrt(pi / 3), 0, 0, 0, std::sqrt(5 * pi) / 8, 0, 0};
  for (int i = 0; i < kShCoeffCount; ++i)
    for (int ch = 0; ch < 3; ++ch) EXPECT_NEAR(sh.c[i][ch], expected[i], kTol) << "coefficient " << i;
}

// A delta (what a point light or the sun is for a probe) projects to the basis evaluated at its direction.
TEST(ShProjection, DeltaProjectsToBasisAtItsDirection) {
  const glm::vec3 d = glm::normalize(glm::vec3(0.3f, -0.5f, 0.8f));
  ShRgb sh;
  addDeltaToSh(sh, d, glm::vec3(1.0f, 2.0f, 3.0f));
  const auto y = shBasis<double>(d.x, d.y, d.z);
  for (int i = 0; i < kShCoeffCount; ++i)
    for (int ch = 0; ch < 3; ++ch) EXPECT_NEAR(sh.c[i][ch], (ch + 1) * y[i], 1e-6) << "coefficient " << i;
}

// The direction set is a rotated spherical Fibonacci set: unit vectors, and different keys give
// different rotations while the same key repeats exactly.
TEST(ShProjection, SphereDirectionsAreUnitAndKeyed) {
  const std::vector<glm::vec3> a = bakeSphereDirections(256, 1), b = bakeSphereDirections(256, 1),
                               c = bakeSphereDirections(256, 2);
  ASSERT_EQ(a.size(), 256u);
  for (size_t k = 0; k < a.size(); ++k) {
    EXPECT_NEAR(glm::length(a[k]), 1.0f, 1e-6f);
    EXPECT_EQ(a[k], b[k]);
  }
  EXPECT_NE(a[0], c[0]);
}

}  // namespace
}  // namespace tetraprobe
