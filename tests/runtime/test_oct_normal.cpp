// The octahedral normal codes of the GPU's outer cells (runtime/oct_normal.h).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <limits>

#include <glm/geometric.hpp>

#include "tetraprobe/runtime/oct_normal.h"

namespace tetraprobe {
namespace {

// A deterministic spread of directions: a Fibonacci sphere plus the axes, the octants' diagonals and
// directions a hair off the equator and the poles, where the fold and the clamp at +-32767 act.
std::vector<glm::dvec3> directions() {
  std::vector<glm::dvec3> out;
  const int n = 20000;
  const double golden = M_PI * (3.0 - std::sqrt(5.0));
  for (int i = 0; i < n; ++i) {
    const double z = 1.0 - 2.0 * (i + 0.5) / n, r = std::sqrt(1.0 - z * z), a = golden * i;
    out.push_back({r * std::cos(a), r * std::sin(a), z});
  }
  for (int a = 0; a < 3; ++a)
    for (double s : {-1.0, 1.0}) {
      glm::dvec3 d(0.0);
      d[a] = s;
      out.push_back(d);
    }
  for (double x : {-1.0, 1.0})
    for (double y : {-1.0, 1.0})
      for (double z : {-1.0, 1.0, 1e-9, -1e-9, 0.0}) out.push_back(glm::normalize(glm::dvec3(x, y, z)));
  for (double e : {1e-3, 1e-6, -1e-6, -1e-3}) {
    out.push_back(glm::normalize(glm::dvec3(1.0, e, -e)));
    out.push_back(glm::normalize(glm::dvec3(e, -e, -1.0)));
    out.push_back(glm::normalize(glm::dvec3(0.3, 0.7 + e, -e)));
  }
  return out;
}

// Every direction comes back within the encoding's bound (5e-5 rad: a 2^-15 step of the octahedron's face
// maps to at most about 2^-15 x 1.5 rad on the sphere, and the best of the four codes around it is taken) and
// as a unit vector to float precision.
TEST(OctNormal, DecodedDirectionIsWithinTheEncodingsBound) {
  double worst = 0.0;
  for (const glm::dvec3& d : directions()) {
    const glm::vec3 q = decodeOctNormal(encodeOctNormal(d));
    EXPECT_NEAR(glm::length(glm::dvec3(q)), 1.0, 1e-6);
    const double angle = std::acos(std::min(1.0, glm::dot(glm::normalize(glm::dvec3(q)), d)));
    worst = std::max(worst, angle);
  }
  EXPECT_LT(worst, 5e-5);
  EXPECT_GT(worst, 1e-6);  // the encoding does quantize (the test would pass an identity otherwise)
}

// Quantizing a quantized normal returns it bit for bit, and its code decodes to it: the CPU's outer cells
// (normals quantized at build) and the GPU's codes (encoded from those floats at upload) name the same
// vectors, and a level's outer cells quantized again on load do not drift.
TEST(OctNormal, QuantizeIsIdempotent) {
  for (const glm::dvec3& d : directions()) {
    const glm::vec3 q = quantizeOctNormal(d);
    const uint32_t code = encodeOctNormal(glm::dvec3(q));
    EXPECT_EQ(decodeOctNormal(code), q);
    EXPECT_EQ(quantizeOctNormal(glm::dvec3(q)), q);
  }
  // Every code along a few lines through the code square, including its edges and the fold.
  for (int y : {-32767, -20000, -1, 0, 1, 16384, 32767})
    for (int x = -32767; x <= 32767; x += 97) {
      const uint32_t code = uint32_t(uint16_t(int16_t(x))) | uint32_t(uint16_t(int16_t(y))) << 16;
      const glm::vec3 q = decodeOctNormal(code);
      EXPECT_EQ(decodeOctNormal(encodeOctNormal(glm::dvec3(q))), q) << "code " << x << ", " << y;
    }
}

// The decode before its normalisation is exact: |x| + |y| + |z| == 1 and every component a multiple of
// 2^-15 (what makes the float GLSL decode and this one agree bit for bit up to normalize).
TEST(OctNormal, RawDecodeIsExactOnTheLattice) {
  for (int y = -32767; y <= 32767; y += 331)
    for (int x = -32767; x <= 32767; x += 257) {
      const uint32_t code = uint32_t(uint16_t(int16_t(x))) | uint32_t(uint16_t(int16_t(y))) << 16;
      const glm::dvec3 r = decodeOctNormalRaw(code);
      EXPECT_EQ(std::abs(r.x) + std::abs(r.y) + std::abs(r.z), 1.0);
      for (int a = 0; a < 3; ++a) {
        const double scaled = r[a] * 32768.0;
        EXPECT_EQ(scaled, std::round(scaled));
        EXPECT_EQ(double(float(r[a])), r[a]);
      }
    }
}

// Degenerate input encodes +z rather than NaN.
TEST(OctNormal, ZeroOrNonFiniteVectorEncodesPlusZ) {
  const double nan = std::numeric_limits<double>::quiet_NaN(), inf = std::numeric_limits<double>::infinity();
  for (const glm::dvec3& d : {glm::dvec3(0.0), glm::dvec3(nan, 0.0, 1.0), glm::dvec3(inf, 0.0, 0.0)})
    EXPECT_EQ(decodeOctNormal(encodeOctNormal(d)), glm::vec3(0.0f, 0.0f, 1.0f));
}

}  // namespace
}  // namespace tetraprobe
