// Deringing: the nearest non-negative field (the default) and the per-probe window both make reconstructed
// irradiance non-negative and keep L00; the nearest is no farther from the projected field than the window and
// leaves a one-sided probe's dark side dark; the window takes the smallest strength on its grid; smooth fields
// are left alone, and `none` changes nothing.
#include <cmath>
#include <cstring>
#include <numbers>
#include <random>
#include <vector>

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

// 40 ringing fields: a bright delta from a random direction, a second source and ambient light (fields whose
// window strength is not a round number), drawn from a fixed seed.
std::vector<ShRgb> ringingFields() {
  std::mt19937 gen(3);
  std::uniform_real_distribution<float> u(-1.0f, 1.0f);
  std::vector<ShRgb> fields;
  for (int k = 0; k < 40; ++k) {
    ShRgb sh = deltaSh({u(gen), u(gen), u(gen)}, glm::vec3(1e6f, 8e5f, 6e5f));
    addDeltaToSh(sh, glm::normalize(glm::vec3(u(gen), u(gen), u(gen))), glm::vec3(3e5f * (1 + u(gen))));
    sh.c[0] += glm::vec3(2e4f * (1 + u(gen)));  // ambient
    fields.push_back(sh);
  }
  return fields;
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

    DeringOptions window;
    window.mode = DeringMode::kWindow;
    const DeringStats stats = deringProbes(sh, window);
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
  int checked = 0;
  for (const ShRgb& sh : ringingFields()) {
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

// A negative mean cannot be fixed with L00 held: the window is applied fully, the nearest field drops that
// channel's bands 1-2 (its constant is the nearest) and keeps the channels that were fine; both count it.
TEST(Dering, NegativeMeanIsCountedAsUnfixable) {
  ShRgb in;
  in.c[0] = glm::vec3(-1.0f, 1.0f, 1.0f);
  in.c[2] = glm::vec3(0.3f);
  std::vector<ShRgb> sh = {in};
  DeringOptions window;
  window.mode = DeringMode::kWindow;
  DeringStats stats = deringProbes(sh, window);
  EXPECT_EQ(stats.unfixableProbes, 1u);
  EXPECT_EQ(stats.maxStrength, kDeringMaxStrength);
  EXPECT_EQ(sh[0].c[2], glm::vec3(0.0f));
  EXPECT_EQ(sh[0].c[0], glm::vec3(-1.0f, 1.0f, 1.0f));

  sh = {in};
  stats = deringProbes(sh, DeringOptions{});
  EXPECT_EQ(stats.unfixableProbes, 1u);
  EXPECT_EQ(stats.deringedProbes, 1u);
  EXPECT_EQ(sh[0].c[2], glm::vec3(0.0f, 0.3f, 0.3f));
  EXPECT_EQ(sh[0].c[0], glm::vec3(-1.0f, 1.0f, 1.0f));
}

// ---- The nearest non-negative field (kAuto) ----

// E-space coefficients e_i = A_l L_i of one channel (the L2 distance of E over the sphere is their Euclidean
// distance).
std::array<double, kShCoeffCount> eCoeffs(const ShRgb& sh, int c) {
  std::array<double, kShCoeffCount> e{};
  for (int i = 0; i < kShCoeffCount; ++i) e[size_t(i)] = shCosineLobe(i) * double(sh.c[size_t(i)][c]);
  return e;
}

double distance2(const ShRgb& a, const ShRgb& b) {
  double d = 0.0;
  for (int c = 0; c < 3; ++c) {
    const auto ea = eCoeffs(a, c), eb = eCoeffs(b, c);
    for (int i = 0; i < kShCoeffCount; ++i)
      d += (ea[size_t(i)] - eb[size_t(i)]) * (ea[size_t(i)] - eb[size_t(i)]);
  }
  return d;
}

// Deltas with ambient light and a second source (the window test's fields): the nearest field is non-negative
// by an independent brute-force check, keeps L00 bit for bit, is never farther from the input than the
// smallest window, and is the projection: for feasible fields w (the window at its strength and stronger, the
// constant) the variational inequality (x - x0) . (w - x) >= 0 holds per channel, which no other feasible
// point of a convex set satisfies.
TEST(Dering, NearestIsNonNegativeKeepsL00AndIsTheProjection) {
  const std::vector<ShRgb> fields = ringingFields();
  int changed = 0;
  for (size_t k = 0; k < fields.size(); ++k) {
    const ShRgb& in = fields[k];
    ShRgb x = in;
    bool fixable = false;
    if (!nearestNonNegativeSh(x, &fixable)) continue;
    ++changed;
    EXPECT_TRUE(fixable);
    const double tol = kDeringTolerance * maxMean(in);
    EXPECT_GE(bruteMinIrradiance(x), -tol) << k;
    EXPECT_GE(minShIrradiance(x), -tol) << k;
    EXPECT_EQ(x.c[0], in.c[0]) << "L00 (the mean) must not change";
    const double s = autoDeringStrength(in);
    ASSERT_GT(s, 0.0);
    ShRgb w = in;
    applyDeringWindow(w, s);
    EXPECT_LE(distance2(x, in), distance2(w, in) * (1.0 + 1e-9)) << k;
    for (const double ws : {s, 0.5 * (s + kDeringMaxStrength), kDeringMaxStrength}) {
      ShRgb f = in;
      applyDeringWindow(f, ws);
      for (int c = 0; c < 3; ++c) {
        const auto e0 = eCoeffs(in, c), ex = eCoeffs(x, c), ef = eCoeffs(f, c);
        double vi = 0.0, scale = 0.0;
        for (int i = 1; i < kShCoeffCount; ++i) {
          vi += (ex[size_t(i)] - e0[size_t(i)]) * (ef[size_t(i)] - ex[size_t(i)]);
          scale += e0[size_t(i)] * e0[size_t(i)];
        }
        // Relative to the field's size squared: float coefficients and the bound's slack.
        EXPECT_GE(vi, -1e-5 * scale) << k << " channel " << c << " window " << ws;
      }
    }
  }
  EXPECT_GT(changed, 20);
}

// An L1 field (band 2 zero) has E = b0 + |e1| Y1 cos: its nearest non-negative field with the mean held is band
// 1 scaled until E touches zero at the antipode (the radial projection onto a ball), and band 2 stays zero.
TEST(Dering, NearestOfAnL1FieldScalesBand1ToTouchZeroAndAddsNoBand2) {
  ShRgb in;
  in.c[0] = glm::vec3(1.0f, 2.0f, 0.5f);
  in.c[1] = glm::vec3(0.9f, 0.1f, 0.2f);
  in.c[2] = glm::vec3(-0.7f, 0.2f, 0.3f);
  in.c[3] = glm::vec3(0.4f, 0.1f, -0.5f);
  ShRgb x = in;
  ASSERT_TRUE(nearestNonNegativeSh(x));
  for (int i = 4; i < kShCoeffCount; ++i) EXPECT_EQ(x.c[size_t(i)], glm::vec3(0.0f)) << i;
  for (int c = 0; c < 3; ++c) {
    const double b0 = sh_const::kA0 * sh_const::kY00 * in.c[0][c];
    double n1 = 0.0;
    for (int i = 1; i < 4; ++i) n1 += double(in.c[size_t(i)][c]) * double(in.c[size_t(i)][c]);
    const double amp = sh_const::kA1 * sh_const::kY1 * std::sqrt(n1);  // max |band 1| of E
    const double scale = amp > b0 ? b0 / amp : 1.0;
    for (int i = 1; i < 4; ++i)
      EXPECT_NEAR(x.c[size_t(i)][c], in.c[size_t(i)][c] * scale, 2e-5) << c << " " << i;
  }
  EXPECT_GE(minShIrradiance(x), -kDeringTolerance * maxMean(in));
}

// A field of L00 and Y20 alone, E = b0 + e6 Y20(n), is symmetric about z and so is its nearest non-negative
// field: only e6 shrinks, until E touches zero on the equator (e6 > 0: b0 = e6 kY20) or at the poles (e6 < 0:
// b0 = -2 e6 kY20). Band 1 is zero and the quadratic form's least eigenvalue is double or has no linear
// part along it: the minimum search's hard case.
TEST(Dering, NearestOfAnAxialBand2FieldShrinksOnlyItsOwnCoefficient) {
  for (const float l6 : {6.0f, -2.0f}) {
    ShRgb in;
    in.c[0] = glm::vec3(1.0f);
    in.c[6] = glm::vec3(l6);
    ShRgb x = in;
    ASSERT_TRUE(nearestNonNegativeSh(x)) << l6;
    const double b0 = sh_const::kA0 * sh_const::kY00;
    const double e6 = l6 > 0 ? b0 / sh_const::kY20 : -b0 / (2.0 * sh_const::kY20);
    for (int c = 0; c < 3; ++c)
      for (int i = 1; i < kShCoeffCount; ++i)
        EXPECT_NEAR(x.c[size_t(i)][c], i == 6 ? e6 / sh_const::kA2 : 0.0, 1e-5) << l6 << " " << i;
    EXPECT_GE(bruteMinIrradiance(x), -kDeringTolerance * maxMean(in));
  }
}

// Fields of deltas (a compact cluster of 1-4 bright sources, or light spread over a whole half of the sphere
// with nothing from the other half: a probe in an opening, or over sunlit ground), each against the exact E
// (sum of E_i max(0, n . d_i)): the nearest field is closer to it than the window over the sphere (RMS over
// 4,000 normals) on every field drawn, and where the light fills a half of the sphere (the exact E facing away
// is 0) it stays within 3 % of the peak there. (A compact source's own L2 lobe at its antipode, +6 % of the peak for one delta,
// stays in the nearest field, where the window at strength 1 happens to cancel it while halving the peak:
// What L2 cannot hold, docs/accuracy.md.)
TEST(Dering, NearestIsCloserToTheTrueIrradianceThanTheWindowAndLeavesADarkHalfDark) {
  std::mt19937 gen(5);
  std::uniform_real_distribution<float> u(-1.0f, 1.0f);
  std::normal_distribution<float> g;
  std::vector<glm::vec3> normals;
  for (int k = 0; k < 4000; ++k) normals.push_back(glm::normalize(glm::vec3(g(gen), g(gen), g(gen))));
  int checked = 0, halves = 0;
  for (int field = 0; field < 40; ++field) {
    const bool half = field % 2 == 1;
    std::vector<std::pair<glm::vec3, float>> lights;
    ShRgb sh;
    const int count = half ? 64 : 1 + (field / 2) % 4;
    for (int i = 0; i < count; ++i) {
      glm::vec3 d;
      if (half) {  // anywhere below the horizon
        do d = glm::vec3(g(gen), g(gen), g(gen));
        while (!(d.y < -0.05f * glm::length(d)));
      } else {  // within 60 degrees of straight down
        do d = glm::vec3(u(gen), -1.0f, u(gen));
        while (glm::length(glm::vec2(d.x, d.z)) > std::sqrt(3.0f));
      }
      d = glm::normalize(d);
      const float e = (half ? 0.1f : 1.0f) * (1.0f + 4.0f * (0.5f + 0.5f * u(gen)));
      lights.emplace_back(d, e);
      addDeltaToSh(sh, d, glm::vec3(e));
    }
    auto exact = [&](const glm::vec3& n) {
      double e = 0.0;
      for (const auto& [d, v] : lights) e += v * std::max(0.0f, glm::dot(n, d));
      return e;
    };
    ShRgb nearest = sh, window = sh;
    if (!nearestNonNegativeSh(nearest)) continue;
    applyDeringWindow(window, autoDeringStrength(sh));
    ++checked;
    double rmsNearest = 0.0, rmsWindow = 0.0;
    for (const glm::vec3& n : normals) {
      const double t = exact(n);
      rmsNearest += std::pow(shIrradiance(nearest, n).x - t, 2.0);
      rmsWindow += std::pow(shIrradiance(window, n).x - t, 2.0);
    }
    EXPECT_LT(rmsNearest, rmsWindow) << "field " << field;
    if (!half) continue;
    ++halves;
    const glm::vec3 up(0, 1, 0);
    const double peak = exact(-up);
    EXPECT_LT(std::abs(shIrradiance(nearest, up).x), 0.03 * peak) << "field " << field;
  }
  EXPECT_GT(checked, 25);
  EXPECT_GT(halves, 10);
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
