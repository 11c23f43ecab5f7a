// SH L2 evaluation (runtime/sh.h): the basis is orthonormal, and the irradiance of known radiance fields
// matches closed forms (Ramamoorthi & Hanrahan 2001; REFERENCES.md §5).
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include <glm/geometric.hpp>

#include "tetraprobe/runtime/sh.h"

using namespace tetraprobe;

namespace {

// Integrates f over the sphere with a midpoint rule in (cos theta, phi). Exact in phi for these
// trigonometric polynomials; in z the error is O(h^2): about 3e-5 for the z^4 term of Y20^2 at n = 400.
template <typename F>
double sphereIntegral(F f, int n = 400) {
  double sum = 0.0;
  for (int i = 0; i < n; ++i) {
    const double z = -1.0 + (i + 0.5) * 2.0 / n;
    const double r = std::sqrt(1.0 - z * z);
    for (int j = 0; j < 2 * n; ++j) {
      const double phi = (j + 0.5) * std::numbers::pi / n;
      sum += f(r * std::cos(phi), r * std::sin(phi), z);
    }
  }
  return sum * (2.0 / n) * (std::numbers::pi / n);
}

}  // namespace

// <Y_i, Y_j> = delta_ij: a wrong constant or a sign slip in one basis function breaks this.
TEST(Sh, BasisIsOrthonormal) {
  for (int i = 0; i < kShCoeffCount; ++i)
    for (int j = i; j < kShCoeffCount; ++j) {
      const double v = sphereIntegral([&](double x, double y, double z) {
        const auto b = shBasis<double>(x, y, z);
        return b[i] * b[j];
      });
      EXPECT_NEAR(v, i == j ? 1.0 : 0.0, 1e-4) << i << "," << j;
    }
}

// Constant radiance L gives irradiance pi * L for every normal.
TEST(Sh, ConstantRadianceGivesPiTimesRadiance) {
  ShRgb sh;
  sh.c[0] = glm::vec3(2.0f, 1.0f, 0.5f) * float(std::sqrt(4.0 * std::numbers::pi));
  for (glm::vec3 n : {glm::vec3(0, 1, 0), glm::vec3(1, 0, 0), glm::normalize(glm::vec3(-1, 2, 3))}) {
    const glm::vec3 e = shIrradiance(sh, n);
    EXPECT_NEAR(e.x, 2.0 * std::numbers::pi, 1e-5);
    EXPECT_NEAR(e.y, 1.0 * std::numbers::pi, 1e-5);
    EXPECT_NEAR(e.z, 0.5 * std::numbers::pi, 1e-5);
  }
}

// Radiance L = max(0, z) (a sky brightening toward the zenith): project it, evaluate irradiance, and compare
// with the irradiance integrated directly at several normals. Tolerance: 2 % of the peak (2pi/3); the L2
// truncation error after cosine convolution of so smooth a field is well under that.
TEST(Sh, IrradianceOfClampedCosineSkyMatchesIntegral) {
  ShRgb sh;
  for (int i = 0; i < kShCoeffCount; ++i) {
    const double c = sphereIntegral(
        [&](double x, double y, double z) { return std::max(0.0, z) * shBasis<double>(x, y, z)[i]; });
    sh.c[i] = glm::vec3(float(c));
  }
  for (glm::vec3 n :
       {glm::vec3(0, 0, 1), glm::vec3(1, 0, 0), glm::normalize(glm::vec3(0, 1, -1)), glm::vec3(0, 0, -1)}) {
    const double exact = sphereIntegral([&](double x, double y, double z) {
      return std::max(0.0, z) * std::max(0.0, x * n.x + y * n.y + z * n.z);
    });
    EXPECT_NEAR(shIrradiance(sh, n).x, exact, 0.02 * 2.0 * std::numbers::pi / 3.0) << n.x << n.y << n.z;
  }
}

// Blending with barycentric weights is linear: blend(a,b; w, 1-w) = w a + (1-w) b coefficient by coefficient.
TEST(Sh, BlendIsLinear) {
  ShRgb a, b;
  for (int i = 0; i < kShCoeffCount; ++i) {
    a.c[i] = glm::vec3(float(i), 1.0f, -float(i));
    b.c[i] = glm::vec3(2.0f, float(i * i), 0.5f);
  }
  const ShRgb* p[2] = {&a, &b};
  const float w[2] = {0.25f, 0.75f};
  const ShRgb m = shBlend(p, w, 2);
  for (int i = 0; i < kShCoeffCount; ++i)
    for (int c = 0; c < 3; ++c) EXPECT_FLOAT_EQ(m.c[i][c], 0.25f * a.c[i][c] + 0.75f * b.c[i][c]);
}
