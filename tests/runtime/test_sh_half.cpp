// Half-precision SH records (runtime/sh_half.h): the binary16 conversion is exact where it must be and rounds
// to nearest even elsewhere (checked against the two neighbouring halves), quantization stays within the
// stated bound from the dark to the megawatt probe, re-encoding a stored record gives the same bits (so a
// level saved again is the same file), and corrupt records are flagged.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <random>

#include <glm/common.hpp>

#include "tetraprobe/runtime/sh_half.h"

namespace tetraprobe {
namespace {

bool isNan16(uint16_t h) {
  return ((h >> 10) & 0x1f) == 0x1f && (h & 0x3ff) != 0;
}

TEST(ShHalf, EveryHalfRoundTripsThroughFloat) {
  for (uint32_t h = 0; h < 65536; ++h) {
    const float f = halfToFloat(uint16_t(h));
    if (isNan16(uint16_t(h))) {
      EXPECT_TRUE(std::isnan(f)) << h;
      EXPECT_TRUE(isNan16(floatToHalf(f))) << h;
      continue;
    }
    ASSERT_EQ(floatToHalf(f), uint16_t(h)) << "half " << h << " = " << f;
  }
  EXPECT_EQ(halfToFloat(0x3C00), 1.0f);
  EXPECT_EQ(halfToFloat(0x7BFF), 65504.0f);
  EXPECT_EQ(halfToFloat(0x0001), std::ldexp(1.0f, -24));
}

// For floats across the whole half range (every 61st bit pattern from 2^-26 to 70000, both signs), the half
// is the nearest of the two halves around the value, ties to the even one, and values from 65520 up are
// infinite.
TEST(ShHalf, FloatToHalfRoundsToNearestEven) {
  const uint32_t lo = 0x32800000u /* 2^-26 */, hi = 0x4788b800u /* 70000 */;
  int checked = 0;
  for (uint32_t u = lo; u < hi; u += 61) {
    for (const float sign : {1.0f, -1.0f}) {
      float x;
      std::memcpy(&x, &u, 4);
      x *= sign;
      const uint16_t h = floatToHalf(x);
      if (std::fabs(x) >= 65520.0f) {
        EXPECT_EQ(h & 0x7fff, 0x7c00) << x;
        continue;
      }
      const double v = halfToFloat(h), err = std::fabs(v - double(x));
      // The neighbours one step away from zero and towards it (same sign).
      const uint16_t mag = h & 0x7fff;
      for (const int step : {-1, 1}) {
        if ((mag == 0 && step < 0) || mag + step > 0x7bff) continue;
        const uint16_t other = uint16_t((h & 0x8000) | (mag + step));
        const double e2 = std::fabs(double(halfToFloat(other)) - double(x));
        ASSERT_LE(err, e2) << "x " << x << ": half " << v << " is farther than " << halfToFloat(other);
        if (err == e2) {
          ASSERT_EQ(mag & 1, 0) << "tie at " << x << " not rounded to even";
        }
      }
      ++checked;
    }
  }
  EXPECT_GT(checked, 1000000);
}

ShRgb randomSh(std::mt19937& rng, double magnitude) {
  std::uniform_real_distribution<float> u(-1.0f, 1.0f);
  ShRgb s;
  for (auto& c : s.c) c = glm::vec3(u(rng), u(rng), u(rng)) * float(magnitude);
  s.c[0] = glm::abs(s.c[0]) + glm::vec3(float(magnitude));  // L00 dominant, as light is
  return s;
}

// Each coefficient is within 2^-11 of itself (round to nearest at 11 significant bits) or, where it is a
// subnormal half, within 2^-39 of the probe's largest coefficient; from 1e-6 to 1e9 W/(m^2 sr).
TEST(ShHalf, QuantizationErrorIsBoundedFromDarkToMegawatt) {
  std::mt19937 rng(5);
  for (const double magnitude : {1e-6, 1e-3, 0.02, 1.0, 37.0, 1e3, 1e6, 1e9}) {
    for (int k = 0; k < 200; ++k) {
      const ShRgb s = randomSh(rng, magnitude);
      ShHalf h;
      ASSERT_TRUE(encodeShHalf(s, &h)) << magnitude;
      bool valid = false;
      const ShRgb q = decodeShHalf(h, &valid);
      ASSERT_TRUE(valid);
      float m = 0.0f;
      for (const auto& c : s.c)
        m = std::fmax(m, std::fmax(std::fabs(c.x), std::fmax(std::fabs(c.y), std::fabs(c.z))));
      for (int i = 0; i < kShCoeffCount; ++i)
        for (int ch = 0; ch < 3; ++ch) {
          const double x = s.c[size_t(i)][ch], y = q.c[size_t(i)][ch];
          ASSERT_LE(std::fabs(y - x),
                    std::ldexp(std::fabs(x), -11) + std::ldexp(double(m), -39) + std::ldexp(1.0, -49))
              << "magnitude " << magnitude << " coefficient " << i << " channel " << ch;
        }
    }
  }
}

// quantizeSh is what a level stores: encoding its result again gives the same record bit for bit (so saving a
// loaded level reproduces the file), including the probe whose largest coefficient rounds up to 2^15 of its
// scale.
TEST(ShHalf, ReencodingAStoredRecordGivesTheSameBits) {
  std::mt19937 rng(9);
  std::vector<ShRgb> cases;
  for (const double magnitude : {1e-5, 0.3, 1.0, 250.0, 4e7}) cases.push_back(randomSh(rng, magnitude));
  for (const float top : {32759.0f, 32760.0f, 32764.0f, 32767.99f, 16383.9f, 65503.0f}) {
    ShRgb s;
    s.c[0] = glm::vec3(top, 0.5f, -3.25f);
    s.c[4] = glm::vec3(1e-3f, -7.0f, 123.0f);
    cases.push_back(s);
  }
  for (const ShRgb& s : cases) {
    ShHalf a, b;
    ASSERT_TRUE(encodeShHalf(s, &a));
    ASSERT_TRUE(encodeShHalf(decodeShHalf(a), &b));
    EXPECT_EQ(std::memcmp(&a, &b, sizeof a), 0) << "largest " << s.c[0].x;
    const ShRgb q = quantizeSh(s), qq = quantizeSh(q);
    EXPECT_EQ(std::memcmp(&q, &qq, sizeof q), 0);
  }
  // All zero: scale 1, zeros.
  ShHalf z;
  ASSERT_TRUE(encodeShHalf(ShRgb{}, &z));
  EXPECT_EQ(halfToFloat(z.h[27]), 1.0f);
  for (int k = 0; k < 27; ++k) EXPECT_EQ(z.h[k], 0);
}

TEST(ShHalf, RefusesWhatItCannotHoldAndFlagsCorruptRecords) {
  ShRgb s;
  s.c[0] = glm::vec3(1.0f);
  ShHalf h;
  s.c[5].y = std::nanf("");
  EXPECT_FALSE(encodeShHalf(s, &h));
  s.c[5].y = INFINITY;
  EXPECT_FALSE(encodeShHalf(s, &h));
  s.c[5].y = float(kShHalfMaxMagnitude) * 1.01f;
  EXPECT_FALSE(encodeShHalf(s, &h));
  s.c[5].y = -float(kShHalfMaxMagnitude);
  ASSERT_TRUE(encodeShHalf(s, &h));
  EXPECT_EQ(decodeShHalf(h).c[5].y, -float(kShHalfMaxMagnitude));
  bool valid = true;
  ShHalf bad = h;
  bad.h[27] = 0;  // scale 0
  decodeShHalf(bad, &valid);
  EXPECT_FALSE(valid);
  bad.h[27] = 0x3C01;  // 1.0009...: not a power of two
  decodeShHalf(bad, &valid);
  EXPECT_FALSE(valid);
  bad.h[27] = 0xBC00;  // -1
  decodeShHalf(bad, &valid);
  EXPECT_FALSE(valid);
  bad = h;
  bad.h[4] = 0x7C00;  // +inf coefficient
  decodeShHalf(bad, &valid);
  EXPECT_FALSE(valid);
  bad.h[4] = 0x0200;  // a subnormal coefficient is fine
  decodeShHalf(bad, &valid);
  EXPECT_TRUE(valid);
}

}  // namespace
}  // namespace tetraprobe
