// Deringing: the per-probe window makes reconstructed irradiance non-negative with the smallest strength on
// its grid, keeps L00, leaves smooth fields alone, and `none` changes nothing.
#include <cmath>
#include <cstring>
#include <numbers>
#include <random>

#include <gtest/gtest.h>
#include <glm/geometric.hpp>

#include "tetraprobe/bake/bake.h"
#include "tetraprobe/common/error.h"

namespace tetraprobe {
namespace {

constexpr double kStep = 1.0 / kDeringStepsPerUnit;

ShRgb deltaSh(glm::vec3 dir, glm::vec3 irradiance) {
  ShRgb sh;
  addDeltaToSh(sh, glm::normalize(dir), irradiance);
  return sh;
}

double maxMean(const ShRgb& sh) {
  double m = 0;
  for (int c = 0; c < 3; ++c) m = std::max(m, std::numbers::pi * sh_const::kY00 * sh.c[0][c]);
  return m;
}

// Brute-force minimum of E over 200k random normals through the runtime's shIrradiance (independent of the
// deringer's own check set and refinement).
double bruteMinIrradiance(const ShRgb& sh) {
  std::mt19937 gen(7);
  std::normal_distribution<float> g;
  double m = INFINITY;
  for (int k = 0; k < 200000; ++k) {
    const glm::vec3 n = glm::normalize(glm::vec3(g(gen), g(gen), g(gen)));
    const glm::vec3 e = shIrradiance(sh, n);
    m = std::min({m, double(e.x), double(e.y), double(e.z)});
  }
  return m;
}

// The classic case (REFERENCES.md section 5): one directional source rings to E = E0 (1/4 + cos/2 +
// 5/32 (3 cos^2 - 1)), whose minimum is -0.0396 E0 at cos = -8/15. The minimum finder must find that value,
// and after auto deringing the field is non-negative everywhere while L00 keeps every bit.
TEST(Dering, BrightDeltaBecomesNonNegativeAndKeepsL00) {
  const float e0 = 1e6f;  // W/m^2
  for (const glm::vec3 dir : {glm::vec3(0, 1, 0), glm::vec3(0.3f, -0.5f, 0.8f), glm::vec3(-1, 0.2f, 0.1f)}) {
    std::vector<ShRgb> sh = {deltaSh(dir, glm::vec3(e0, 0.5f * e0, 0.25f * e0))};
    const ShRgb before = sh[0];
    const double x = -8.0 / 15.0, exactMin = e0 * (0.25 + 0.5 * x + 5.0 / 32.0 * (3 * x * x - 1));
    EXPECT_NEAR(minShIrradiance(before), exactMin, 1e-5 * e0);
    EXPECT_NEAR(bruteMinIrradiance(before), exactMin, 1e-3 * e0);  // the random set only gets close

    const DeringStats stats = deringProbes(sh, DeringOptions{});
    EXPECT_EQ(stats.deringedProbes, 1u);
    EXPECT_EQ(stats.unfixableProbes, 0u);
    EXPECT_NEAR(stats.minIrradianceBefore, exactMin, 1e-5 * e0);
    const double tol = kDeringTolerance * maxMean(before);
    EXPECT_GE(stats.minIrradianceAfter, -tol);
    EXPECT_GE(minShIrradiance(sh[0]), -tol);
    EXPECT_GE(bruteMinIrradiance(sh[0]), -tol);
    EXPECT_EQ(sh[0].c[0], before.c[0]) << "L00 (the mean) must not change";
    // A single delta needs exactly strength 1: the kernel (1 + cos)/4 touches zero at the antipode.
    EXPECT_EQ(stats.maxStrength, 1.0);
  }
}

// Smallest on the grid: strength s passes and s - 1/256 leaves a negative, for deltas mixed with ambient
// light and a second source (fields whose strength is not a round number).
TEST(Dering, AutoStrengthIsTheSmallestThatWorks) {
  std::mt19937 gen(3);
  std::uniform_real_distribution<float> u(-1.0f, 1.0f);
  int checked = 0;
  for (int k = 0; k < 40; ++k) {
    ShRgb sh = deltaSh({u(gen), u(gen), u(gen)}, glm::vec3(1e6f, 8e5f, 6e5f));
    addDeltaToSh(sh, glm::normalize(glm::vec3(u(gen), u(gen), u(gen))), glm::vec3(3e5f * (1 + u(gen))));
    sh.c[0] += glm::vec3(2e4f * (1 + u(gen)));  // ambient
    bool fixable = false;
    const double s = autoDeringStrength(sh, &fixable);
    EXPECT_TRUE(fixable);
    const double tol = kDeringTolerance * maxMean(sh);
    if (s == 0.0) {
      EXPECT_GE(minShIrradiance(sh), -tol);
      continue;
    }
    ++checked;
    EXPECT_EQ(s * kDeringStepsPerUnit, std::round(s * kDeringStepsPerUnit)) << "on the 1/256 grid";
    EXPECT_GE(minShIrradiance(sh, s), -tol) << "strength " << s;
    EXPECT_LT(minShIrradiance(sh, s - kStep), -tol) << "strength " << s << " is not the smallest";
  }
  EXPECT_GT(checked, 20);
}

// A smooth field (constant plus a small gradient) has no ringing: strength 0 and the SH keep every bit.
TEST(Dering, SmoothFieldIsLeftUntouched) {
  ShRgb sh;
  sh.c[0] = glm::vec3(1.0f, 0.8f, 0.6f);
  sh.c[1] = glm::vec3(0.1f, -0.05f, 0.02f);
  sh.c[3] = glm::vec3(-0.08f, 0.04f, 0.03f);
  sh.c[6] = glm::vec3(0.02f, 0.01f, -0.01f);
  EXPECT_EQ(autoDeringStrength(sh), 0.0);
  std::vector<ShRgb> v = {sh};
  const DeringStats stats = deringProbes(v, DeringOptions{});
  EXPECT_EQ(stats.deringedProbes, 0u);
  EXPECT_EQ(stats.maxStrength, 0.0);
  EXPECT_GT(stats.minIrradianceBefore, 0.0f);
  EXPECT_EQ(stats.minIrradianceBefore, stats.minIrradianceAfter);
  EXPECT_EQ(std::memcmp(&v[0], &sh, sizeof sh), 0);
}

// `none` leaves ringing SH bit-identical but still reports the (negative) minimum.
TEST(Dering, NoneLeavesShBitIdentical) {
  std::vector<ShRgb> sh = {deltaSh({0, 0, 1}, glm::vec3(1e6f)), deltaSh({1, 1, 0}, glm::vec3(5.0f))};
  const std::vector<ShRgb> copy = sh;
  DeringOptions o;
  o.mode = DeringMode::kNone;
  const DeringStats stats = deringProbes(sh, o);
  EXPECT_EQ(std::memcmp(sh.data(), copy.data(), sh.size() * sizeof(ShRgb)), 0);
  EXPECT_EQ(stats.deringedProbes, 0u);
  EXPECT_LT(stats.minIrradianceBefore, 0.0f);
  EXPECT_EQ(stats.minIrradianceBefore, stats.minIrradianceAfter);
}

// The window: identity at 0, (1, 1/2, 0) at 1, only L00 at 2; never increases a band; L00 factor is 1.
TEST(Dering, WindowKeepsMeanAndShrinksBandsMonotonically) {
  EXPECT_EQ(deringWindow(0.0), (std::array<double, 3>{1.0, 1.0, 1.0}));
  const auto w1 = deringWindow(1.0);
  EXPECT_EQ(w1[0], 1.0);
  EXPECT_NEAR(w1[1], 0.5, 1e-15);
  EXPECT_NEAR(w1[2], 0.0, 1e-15);
  const auto w2 = deringWindow(2.0);
  EXPECT_NEAR(w2[1], 0.0, 1e-15);
  EXPECT_NEAR(w2[2], 0.0, 1e-15);
  for (int k = 1; k <= 512; ++k) {
    const auto a = deringWindow((k - 1) * kStep), b = deringWindow(k * kStep);
    EXPECT_EQ(b[0], 1.0);
    EXPECT_LE(b[1], a[1]);
    EXPECT_LE(b[2], a[2]);
  }
}

// Fixed strength windows every probe with the same factors and rejects strengths outside [0, 2].
TEST(Dering, FixedStrengthAppliesToEveryProbeAndIsRangeChecked) {
  std::vector<ShRgb> sh = {deltaSh({0, 1, 0}, glm::vec3(2.0f)), deltaSh({1, 0, 0}, glm::vec3(3.0f))};
  const std::vector<ShRgb> copy = sh;
  DeringOptions o;
  o.mode = DeringMode::kFixed;
  o.strength = 0.5;
  const DeringStats stats = deringProbes(sh, o);
  EXPECT_EQ(stats.deringedProbes, 2u);
  const auto w = deringWindow(0.5);
  for (size_t p = 0; p < sh.size(); ++p)
    for (int i = 0; i < kShCoeffCount; ++i)
      EXPECT_EQ(sh[p].c[i], copy[p].c[i] * float(i == 0 ? 1.0 : w[i < 4 ? 1 : 2])) << p << " " << i;
  for (double bad : {-0.1, 2.5, double(NAN)}) {
    o.strength = bad;
    EXPECT_THROW(deringProbes(sh, o), InputError) << bad;
  }
}

// A negative mean cannot be fixed by a window; it is windowed fully and counted.
TEST(Dering, NegativeMeanIsCountedAsUnfixable) {
  std::vector<ShRgb> sh(1);
  sh[0].c[0] = glm::vec3(-1.0f, 1.0f, 1.0f);
  sh[0].c[2] = glm::vec3(0.3f);
  const DeringStats stats = deringProbes(sh, DeringOptions{});
  EXPECT_EQ(stats.unfixableProbes, 1u);
  EXPECT_EQ(stats.maxStrength, kDeringMaxStrength);
  EXPECT_EQ(sh[0].c[2], glm::vec3(0.0f));
  EXPECT_EQ(sh[0].c[0], glm::vec3(-1.0f, 1.0f, 1.0f));
}

// Same input, any thread count: bit-identical SH and statistics.
TEST(Dering, DeterministicForAnyThreadCount) {
  std::mt19937 gen(11);
  std::uniform_real_distribution<float> u(-1.0f, 1.0f);
  std::vector<ShRgb> a;
  for (int k = 0; k < 300; ++k) {
    ShRgb sh = deltaSh({u(gen), u(gen), u(gen)}, glm::vec3(1.0f + u(gen)));
    sh.c[0] += glm::vec3(0.2f * (1 + u(gen)));
    a.push_back(sh);
  }
  std::vector<ShRgb> b = a;
  DeringOptions o;
  o.threads = 1;
  const DeringStats sa = deringProbes(a, o);
  o.threads = 3;
  const DeringStats sb = deringProbes(b, o);
  EXPECT_EQ(std::memcmp(a.data(), b.data(), a.size() * sizeof(ShRgb)), 0);
  EXPECT_EQ(sa.deringedProbes, sb.deringedProbes);
  EXPECT_EQ(sa.minIrradianceBefore, sb.minIrradianceBefore);
  EXPECT_EQ(sa.minIrradianceAfter, sb.minIrradianceAfter);
  EXPECT_GT(sa.deringedProbes, 0u);
}

}  // namespace
}  // namespace tetraprobe
