// bakeProbes: furnace radiance, content flags, analytic punctual deltas and thread-count determinism.
#include <array>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <memory>
#include <numbers>
#include <string>

#include <gtest/gtest.h>
#include <glm/geometric.hpp>

#include "test_scenes.h"
#include "tetraprobe/bake/bake.h"
#include "tetraprobe/bake/bench_rays.h"
#include "tetraprobe/common/error.h"
#include "tetraprobe/runtime/luminance.h"

namespace tetraprobe {
namespace {

BakeOptions quiet(int bounces, int samples, uint32_t content = kContentDefault) {
  BakeOptions o;
  o.bounces = bounces;
  o.samplesPerProbe = samples;
  o.content = content;
  o.progress = false;
  o.threads = 2;
  return o;
}

// Mean and standard error over probes of one coefficient/channel.
struct Stat {
  double mean = 0, se = 0;
};
Stat statOf(const std::vector<ShRgb>& sh, int coeff, int ch) {
  double s = 0, s2 = 0;
  const double n = double(sh.size());
  for (const ShRgb& p : sh) {
    s += p.c[coeff][ch];
    s2 += double(p.c[coeff][ch]) * p.c[coeff][ch];
  }
  Stat st;
  st.mean = s / n;
  st.se = std::sqrt(std::max(0.0, (s2 - s * s / n) / (n - 1)) / n);
  return st;
}

// The white furnace: inside a closed sphere of albedo a and emission Le, radiance is Le sum_{k<=B} a^k in
// every direction at every point, for B bounces. It pins the bounce count, the NEE + MIS weights (any double
// counting or missing weight shifts the mean), Russian roulette (unbiased) and the 4 pi / N projection.
// Tolerance: 4 standard errors over 24 probes + 2e-4 relative (float radiance, Fibonacci quadrature).
TEST(WhiteFurnace, ProbeRadianceIsGeometricSeriesOfAlbedo) {
  Scene s;
  const float a = 0.5f;
  const glm::vec3 le(1.0f, 2.0f, 0.5f);
  const uint32_t m = test::addMaterial(s, glm::vec3(a), le);
  test::addSphere(s, glm::vec3(0.0f), 1.0f, true, m);
  SceneTracer tracer(s);
  std::vector<glm::dvec3> probes;
  for (int i = 0; i < 24; ++i)
    probes.push_back(0.5 * glm::dvec3(std::sin(i * 1.3), std::cos(i * 2.1), std::sin(i * 0.7 + 1.0)) / 1.8);
  for (int bounces : {0, 1, 3}) {
    double series = 0;
    for (int k = 0; k <= bounces; ++k) series += std::pow(a, k);
    const std::vector<ShRgb> sh = bakeProbes(tracer, probes, quiet(bounces, 512));
    for (int ch = 0; ch < 3; ++ch) {
      const double exact = le[ch] * series * std::sqrt(4.0 * std::numbers::pi);
      const Stat l00 = statOf(sh, 0, ch);
      EXPECT_NEAR(l00.mean, exact, 4 * l00.se + 2e-4 * exact) << "bounces " << bounces << " channel " << ch;
      for (int i = 1; i < kShCoeffCount; ++i) {
        const Stat c = statOf(sh, i, ch);
        EXPECT_NEAR(c.mean, 0.0, 4 * c.se + 2e-3 * exact) << "bounces " << bounces << " coefficient " << i;
      }
    }
  }
}

// An open room: emissive walls, a point light, a gradient sky through the missing ceiling.
Scene openRoom() {
  Scene s;
  const uint32_t wall = test::addMaterial(s, glm::vec3(0.6f, 0.5f, 0.4f));
  const uint32_t glow = test::addMaterial(s, glm::vec3(0.5f), glm::vec3(2.0f, 1.0f, 0.5f));
  test::addBox(s, {-2, 0, -2}, {2, 3, 2}, true, wall, 2);
  // Remove the ceiling (face 3, 8 triangles with n = 2) so the sky is visible.
  s.triangles.erase(s.triangles.begin() + 24, s.triangles.begin() + 32);
  s.triangleMaterial.erase(s.triangleMaterial.begin() + 24, s.triangleMaterial.begin() + 32);
  test::addQuad(s, {-1.9f, 0.5f, -0.5f}, {-1.9f, 0.5f, 0.5f}, {-1.9f, 1.5f, 0.5f}, {-1.9f, 1.5f, -0.5f},
                glow);
  Light point;
  point.position = {1.0f, 2.0f, 0.5f};
  point.intensity = {5.0f, 5.0f, 4.0f};
  s.lights.push_back(point);
  Light sun;
  sun.type = LightType::kDirectional;
  sun.direction = glm::normalize(glm::vec3(0.3f, -1.0f, 0.2f));
  sun.intensity = {3.0f, 3.0f, 2.5f};
  sun.angularRadiusRad = 0.02f;
  s.lights.push_back(sun);
  s.skyRadiance = {0.3f, 0.5f, 1.0f};
  s.skyHorizonRadiance = {0.8f, 0.8f, 0.7f};
  return s;
}

std::vector<glm::dvec3> roomProbes() {
  std::vector<glm::dvec3> p;
  for (int i = 0; i < 9; ++i) p.push_back({-1.5 + 0.37 * i, 0.4 + 0.3 * i, 1.2 - 0.29 * i});
  return p;
}

// Same seed, any thread count: bit-identical output (the bake must be reproducible on any machine size).
TEST(Determinism, BakeIsBitIdenticalForAnyThreadCount) {
  const Scene s = openRoom();
  SceneTracer tracer(s);
  BakeOptions o = quiet(3, 64, kContentAll);
  o.threads = 1;
  const std::vector<ShRgb> one = bakeProbes(tracer, roomProbes(), o);
  o.threads = 2;
  const std::vector<ShRgb> two = bakeProbes(tracer, roomProbes(), o);
  o.threads = 5;
  const std::vector<ShRgb> five = bakeProbes(tracer, roomProbes(), o);
  ASSERT_EQ(one.size(), two.size());
  EXPECT_EQ(std::memcmp(one.data(), two.data(), one.size() * sizeof(ShRgb)), 0);
  EXPECT_EQ(std::memcmp(one.data(), five.data(), one.size() * sizeof(ShRgb)), 0);
  o.seed += 1;  // and the seed matters
  const std::vector<ShRgb> other = bakeProbes(tracer, roomProbes(), o);
  EXPECT_NE(std::memcmp(one.data(), other.data(), one.size() * sizeof(ShRgb)), 0);
}

void expectSumEquals(const std::vector<ShRgb>& parts0, const std::vector<ShRgb>& parts1,
                     const std::vector<ShRgb>& parts2, const std::vector<ShRgb>& whole) {
  for (size_t p = 0; p < whole.size(); ++p)
    for (int i = 0; i < kShCoeffCount; ++i)
      for (int ch = 0; ch < 3; ++ch) {
        const float sum = parts0[p].c[i][ch] + parts1[p].c[i][ch] + parts2[p].c[i][ch];
        EXPECT_NEAR(sum, whole[p].c[i][ch], 1e-5f * (1.0f + std::fabs(whole[p].c[0][ch])))
            << "probe " << p << " coefficient " << i;
      }
}

// The content flags partition the light: a probe in a closed emissive box holds emissive-direct plus
// indirect = default. The random streams do not depend on the flags, so the split is exact up to float
// rounding (tolerance 1e-5 relative to L00), not just statistically.
TEST(ContentFlags, EmissiveAndIndirectAddUpToDefault) {
  Scene s;
  const uint32_t m = test::addMaterial(s, glm::vec3(0.7f, 0.6f, 0.5f), glm::vec3(1.0f, 0.8f, 0.3f));
  const uint32_t dark = test::addMaterial(s, glm::vec3(0.4f));
  test::addBox(s, {-1, -1, -1}, {1, 1, 1}, true, m, 2);
  test::addQuad(s, {-0.3f, -0.9f, -0.3f}, {0.3f, -0.9f, -0.3f}, {0.3f, -0.9f, 0.3f}, {-0.3f, -0.9f, 0.3f},
                dark);
  SceneTracer tracer(s);
  const std::vector<glm::dvec3> probes = {{0, 0, 0}, {0.5, -0.3, 0.2}, {-0.7, 0.6, -0.1}};
  const auto emissive = bakeProbes(tracer, probes, quiet(3, 128, kContentEmissive));
  const auto indirect = bakeProbes(tracer, probes, quiet(3, 128, kContentIndirect));
  const auto none = bakeProbes(tracer, probes, quiet(3, 128, 0));
  const auto def = bakeProbes(tracer, probes, quiet(3, 128, kContentDefault));
  expectSumEquals(emissive, indirect, none, def);
  for (const ShRgb& p : none)
    for (int i = 0; i < kShCoeffCount; ++i) EXPECT_EQ(p.c[i], glm::vec3(0.0f));
}

// The same partition with every kind of light: emissive + sky + indirect = default, and default + direct
// punctual = all.
TEST(ContentFlags, AllFlagsPartitionTheLight) {
  const Scene s = openRoom();
  SceneTracer tracer(s);
  const std::vector<glm::dvec3> probes = roomProbes();
  const auto emissive = bakeProbes(tracer, probes, quiet(2, 64, kContentEmissive));
  const auto sky = bakeProbes(tracer, probes, quiet(2, 64, kContentSky));
  const auto indirect = bakeProbes(tracer, probes, quiet(2, 64, kContentIndirect));
  const auto punctual = bakeProbes(tracer, probes, quiet(2, 64, kContentDirectPunctual));
  const auto none = bakeProbes(tracer, probes, quiet(2, 64, 0));
  const auto def = bakeProbes(tracer, probes, quiet(2, 64, kContentDefault));
  const auto all = bakeProbes(tracer, probes, quiet(2, 64, kContentAll));
  expectSumEquals(emissive, sky, indirect, def);
  expectSumEquals(def, punctual, none, all);
}

// For a probe, a point light is a delta: with only kContentDirectPunctual it holds exactly
// (I / r^2) Y(d) + E_sun Y(sun), and nothing once an occluder blocks both (tolerance: float rounding).
TEST(DirectPunctual, ProbeHoldsExactDeltaProjection) {
  Scene s;
  const uint32_t m = test::addMaterial(s, glm::vec3(0.5f));
  test::addGround(s, -5.0f, 50.0f, m);
  Light point;
  point.position = {1.0f, 2.0f, -1.0f};
  point.intensity = {10.0f, 20.0f, 30.0f};
  s.lights.push_back(point);
  Light sun;
  sun.type = LightType::kDirectional;
  sun.direction = glm::normalize(glm::vec3(-0.2f, -1.0f, 0.4f));
  sun.intensity = {2.0f, 1.0f, 0.5f};
  s.lights.push_back(sun);
  SceneTracer tracer(s);
  const glm::dvec3 probe(0.2, 0.5, 0.3);
  const auto sh = bakeProbes(tracer, {probe}, quiet(2, 16, kContentDirectPunctual));
  const glm::vec3 d = point.position - glm::vec3(probe);
  const float r2 = glm::dot(d, d);
  const glm::vec3 w = glm::normalize(d), ws = -sun.direction;
  const auto y = shBasis<double>(w.x, w.y, w.z), ys = shBasis<double>(ws.x, ws.y, ws.z);
  for (int i = 0; i < kShCoeffCount; ++i)
    for (int ch = 0; ch < 3; ++ch) {
      const double exact = point.intensity[ch] / r2 * y[i] + sun.intensity[ch] * ys[i];
      EXPECT_NEAR(sh[0].c[i][ch], exact, 1e-5 * (1 + std::fabs(exact))) << "coefficient " << i;
    }
  // A large roof above the probe shadows both lights.
  Scene roofed = s;
  test::addQuad(roofed, {-20, 1.5f, -20}, {20, 1.5f, -20}, {20, 1.5f, 20}, {-20, 1.5f, 20}, m);
  SceneTracer roofTracer(roofed);
  const auto shadowed = bakeProbes(roofTracer, {probe}, quiet(2, 16, kContentDirectPunctual));
  for (int i = 0; i < kShCoeffCount; ++i) EXPECT_EQ(shadowed[0].c[i], glm::vec3(0.0f));
}

// A small emitter seen directly from a probe (a 0.1 m square 2 m away: 2e-4 of the sphere, so 64 sphere
// directions almost never meet it) holds its exact projection at every probe, because the bake also draws
// points on the emitters (MIS-weighted against the directions). The truth is a 128 x 128 midpoint quadrature
// of Le Y(w) cos / r^2 over the square (relative error ~1e-5). A probe behind an opaque blocker gets exactly
// 0, and so does every probe once the emitter faces away (emission is front-face only). Tolerance per probe
// and coefficient: 3 % of (|coefficient| + L00) (band 2 varies by tens of % across the square seen from 2 m:
// up to 2 % over 64 points), for the set bake and the adaptive one; the directions alone give 0 for most probes and
// ~80x too much for the rest.
TEST(EmitterSampling, SmallEmitterSeenDirectlyIsExactAtEveryProbe) {
  Scene s;
  const glm::vec3 le(40.0f, 30.0f, 20.0f);
  const uint32_t lamp = test::addMaterial(s, glm::vec3(0.0f), le);
  const uint32_t black = test::addMaterial(s, glm::vec3(0.0f));
  const float h = 0.05f;  // half side; the square faces -z at z = 2
  test::addQuad(s, {-h, -h, 2}, {-h, h, 2}, {h, h, 2}, {h, -h, 2}, lamp);
  test::addQuad(s, {-9, -2, -2}, {-9, 2, -2}, {-4, 2, -2}, {-4, -2, -2}, black);  // a blocker
  SceneTracer tracer(s);
  std::vector<glm::dvec3> probes;
  for (int i = 0; i < 12; ++i)
    probes.emplace_back(0.3 * std::sin(i * 1.7), 0.3 * std::cos(i * 1.1), 0.05 * i);
  probes.emplace_back(-7.0, 0.0, -3.0);  // under the blocker: the lamp at z = 2 is hidden
  auto exact = [&](const glm::dvec3& p) {
    std::array<double, kShCoeffCount> sum{};
    const int n = 128;
    const double cell = 2.0 * h / n;
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < n; ++i) {
        const glm::dvec3 q(-h + (i + 0.5) * cell, -h + (j + 0.5) * cell, 2.0);
        const glm::dvec3 d = q - p;
        const double r2 = glm::dot(d, d), r = std::sqrt(r2);
        const glm::dvec3 w = d / r;
        const double solid = cell * cell * w.z / r2;  // the square's normal is -z, w.z = cos at the light
        const auto y = shBasis<double>(w.x, w.y, w.z);
        for (int k = 0; k < kShCoeffCount; ++k) sum[size_t(k)] += solid * y[size_t(k)];
      }
    return sum;
  };
  for (double target : {0.0, 0.02}) {
    BakeOptions o = quiet(0, 64, kContentEmissive);
    o.targetRelError = target;
    o.maxSamplesPerProbe = 4096;
    const std::vector<ShRgb> sh = bakeProbes(tracer, probes, o);
    for (size_t p = 0; p + 1 < probes.size(); ++p) {
      const auto truth = exact(probes[p]);
      for (int k = 0; k < kShCoeffCount; ++k)
        for (int ch = 0; ch < 3; ++ch)
          EXPECT_NEAR(sh[p].c[k][ch], le[ch] * truth[size_t(k)],
                      0.03 * le[ch] * (std::fabs(truth[size_t(k)]) + truth[0]))
              << "probe " << p << " coefficient " << k << " channel " << ch << " target " << target;
    }
    for (int k = 0; k < kShCoeffCount; ++k)
      EXPECT_EQ(sh.back().c[k], glm::vec3(0.0f)) << "behind the blocker";
  }
  // Behind a pane that passes 40 % (thin glass, black otherwise), every probe holds 40 % of the projection:
  // both strategies cross the pane (directions by a random pass, emitter points by the shadow ray's
  // transmittance) and their MIS weights still add up to one. Tolerance: 3 % as above, plus 4 % of L00 for
  // the sphere rays' random passes.
  Scene glass = s;
  const uint32_t pane = test::addMaterial(glass, glm::vec3(0.0f));
  glass.materials[pane].transmission = 0.4f;
  test::addQuad(glass, {-1, -1, 1.5f}, {1, -1, 1.5f}, {1, 1, 1.5f}, {-1, 1, 1.5f}, pane);
  SceneTracer glassTracer(glass);
  const std::vector<ShRgb> dimmed = bakeProbes(glassTracer, probes, quiet(0, 256, kContentEmissive));
  for (size_t p = 0; p + 1 < probes.size(); ++p) {
    const auto truth = exact(probes[p]);
    for (int k = 0; k < kShCoeffCount; ++k)
      EXPECT_NEAR(dimmed[p].c[k][0], 0.4 * le[0] * truth[size_t(k)],
                  0.4 * le[0] * (0.03 * std::fabs(truth[size_t(k)]) + 0.07 * truth[0]))
          << "behind glass: probe " << p << " coefficient " << k;
  }
  // Turned to face away from the probes, the same emitter gives them nothing by either strategy.
  Scene away;
  test::addQuad(away, {-h, -h, 2}, {h, -h, 2}, {h, h, 2}, {-h, h, 2},
                test::addMaterial(away, glm::vec3(0.0f), le));
  SceneTracer awayTracer(away);
  const std::vector<ShRgb> none = bakeProbes(awayTracer, probes, quiet(0, 64, kContentEmissive));
  for (const ShRgb& p : none)
    for (int k = 0; k < kShCoeffCount; ++k) EXPECT_EQ(p.c[k], glm::vec3(0.0f)) << "back-facing emitter";
}

// --sh-order 1: coefficients 4..8 are exactly zero and 0..3 are the L2 bake's, bit for bit (the same random
// streams; the truncation happens after projection).
TEST(ShOrder, L1BakeIsTheL2BakeWithoutBandTwo) {
  const Scene s = openRoom();
  SceneTracer tracer(s);
  BakeOptions o = quiet(2, 64, kContentAll);
  const std::vector<ShRgb> l2 = bakeProbes(tracer, roomProbes(), o);
  o.shOrder = 1;
  const std::vector<ShRgb> l1 = bakeProbes(tracer, roomProbes(), o);
  ASSERT_EQ(l1.size(), l2.size());
  bool anyBandTwo = false;
  for (size_t p = 0; p < l1.size(); ++p) {
    for (int i = 0; i < 4; ++i) EXPECT_EQ(l1[p].c[i], l2[p].c[i]) << "probe " << p << " coefficient " << i;
    for (int i = 4; i < kShCoeffCount; ++i) {
      EXPECT_EQ(l1[p].c[i], glm::vec3(0.0f)) << "probe " << p << " coefficient " << i;
      anyBandTwo = anyBandTwo || l2[p].c[i] != glm::vec3(0.0f);
    }
  }
  EXPECT_TRUE(anyBandTwo);
  o.shOrder = 3;
  EXPECT_THROW(bakeProbes(tracer, roomProbes(), o), InputError);
}

// Ray counts are summed per probe: the same for any thread count, and the stats do not change the SH.
// Every path starts with one closest-hit ray, so there are at least samples x probes of them.
TEST(BakeStats, RayCountsAreDeterministic) {
  const Scene s = openRoom();
  SceneTracer tracer(s);
  BakeOptions o = quiet(3, 64, kContentDefault);
  BakeStats one, two;
  o.threads = 1;
  const std::vector<ShRgb> a = bakeProbes(tracer, roomProbes(), o, &one);
  o.threads = 2;
  const std::vector<ShRgb> b = bakeProbes(tracer, roomProbes(), o, &two);
  const std::vector<ShRgb> c = bakeProbes(tracer, roomProbes(), o);
  EXPECT_EQ(std::memcmp(a.data(), b.data(), a.size() * sizeof(ShRgb)), 0);
  EXPECT_EQ(std::memcmp(a.data(), c.data(), a.size() * sizeof(ShRgb)), 0);
  EXPECT_EQ(one.intersectRays, two.intersectRays);
  EXPECT_EQ(one.occludedRays, two.occludedRays);
  EXPECT_GE(one.intersectRays, uint64_t(64 * roomProbes().size()));
  EXPECT_GT(one.occludedRays, 0u);
  EXPECT_GT(one.seconds, 0.0);
}

// The recorder sees exactly the rays the bake counts, and bare Embree gives the same answers on replay.
TEST(BenchRays, RecordedRaysMatchTheCountAndReplayAgrees) {
  const Scene s = openRoom();
  SceneTracer tracer(s);
  BakeOptions o = quiet(3, 64, kContentAll);
  BakeStats stats;
  const std::vector<glm::dvec3> probes = roomProbes();
  bakeProbes(tracer, probes, o, &stats);
  std::vector<size_t> indices(probes.size());
  for (size_t i = 0; i < indices.size(); ++i) indices[i] = i;
  const std::vector<RecordedRay> rays = recordBakeRays(tracer, probes, indices, o);
  ASSERT_EQ(rays.size(), stats.rays());
  uint64_t occluded = 0;
  for (const RecordedRay& r : rays) occluded += r.occluded;
  EXPECT_EQ(occluded, stats.occludedRays);
  const ReplayResult replay = replayRays(tracer, rays, 2, 0.0);
  EXPECT_EQ(replay.rays, rays.size());
  EXPECT_EQ(replay.mismatches, 0u);
  EXPECT_THROW(recordBakeRays(tracer, probes, {0}, o), InputError);
}

}  // namespace
}  // namespace tetraprobe

namespace tetraprobe {
namespace {

// Adaptive sampling reaches its target on a closed form: inside a closed emissive sphere of albedo 0.5 every
// probe sees Le / (1 - a) from every direction (E(n) = pi Le / (1 - a)), with path lengths random under
// Russian roulette. Each probe must stop with its own estimate at or below the target, and the estimates must
// be honest: the RMS relative error of E at the six axis normals over 24 probes against the closed form is at
// most 1.5 x the target (it is ~0.6 x: the criterion takes the worst axis). A tighter target costs more paths.
// The result is bit-identical at 1 and 2 threads.
TEST(AdaptiveSampling, ReachesTargetErrorOnClosedForm) {
  Scene s;
  const float a = 0.5f;
  const glm::vec3 le(1.0f, 0.8f, 0.6f);
  test::addSphere(s, glm::vec3(0.0f), 1.0f, true, test::addMaterial(s, glm::vec3(a), le));
  SceneTracer tracer(s);
  std::vector<glm::dvec3> probes;
  for (int i = 0; i < 24; ++i)
    probes.emplace_back(0.5 * std::sin(i * 1.3), 0.5 * std::cos(i * 0.7), 0.4 * std::sin(i * 2.1));
  BakeOptions o = quiet(kUnboundedBounces, 128, kContentAll);
  o.targetRelError = 0.02;
  o.maxSamplesPerProbe = 1 << 16;
  BakeStats stats;
  const std::vector<ShRgb> sh = bakeProbes(tracer, probes, o, &stats);
  EXPECT_EQ(stats.probesAtCap, 0u);
  EXPECT_LE(stats.maxRelError, 0.02);
  EXPECT_GT(stats.meanRelError, 0.0);
  const glm::vec3 axes[6] = {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}};
  double sq = 0.0;
  int count = 0;
  for (const ShRgb& p : sh)
    for (const glm::vec3& n : axes) {
      const glm::vec3 e = shIrradiance(p, n);
      for (int c = 0; c < 3; ++c) {
        const double exact = std::numbers::pi * le[c] / (1.0 - a);
        sq += (e[c] / exact - 1.0) * (e[c] / exact - 1.0);
        ++count;
      }
    }
  EXPECT_LE(std::sqrt(sq / count), 1.5 * 0.02);

  BakeOptions loose = o;
  loose.targetRelError = 0.08;
  BakeStats looseStats;
  bakeProbes(tracer, probes, loose, &looseStats);
  EXPECT_LT(looseStats.paths * 4, stats.paths) << "error ~ 1/sqrt(paths): 4x the error, ~1/16 the paths";

  BakeOptions one = o;
  one.threads = 1;
  const std::vector<ShRgb> single = bakeProbes(tracer, probes, one);
  ASSERT_EQ(single.size(), sh.size());
  EXPECT_EQ(std::memcmp(single.data(), sh.data(), sh.size() * sizeof(ShRgb)), 0);
}

// The path budget: probes that stop at maxSamplesPerProbe above the target get the unspent paths, reach the
// target that the cap alone misses, never spend more than the budget (plus one batch per probe of rounding),
// and the result stays bit-identical for any thread count.
TEST(AdaptiveSampling, PathBudgetConvergesProbesStoppedAtTheCap) {
  Scene s;
  const float a = 0.5f;
  test::addSphere(s, glm::vec3(0.0f), 1.0f, true, test::addMaterial(s, glm::vec3(a), glm::vec3(1.0f)));
  SceneTracer tracer(s);
  std::vector<glm::dvec3> probes;
  for (int i = 0; i < 8; ++i) probes.emplace_back(0.3 * std::sin(i * 1.3), 0.3 * std::cos(i * 0.7), 0.0);
  BakeOptions capped = quiet(kUnboundedBounces, 128, kContentAll);
  capped.targetRelError = 0.0125;
  capped.maxSamplesPerProbe = 256;
  BakeStats cappedStats;
  bakeProbes(tracer, probes, capped, &cappedStats);
  ASSERT_EQ(cappedStats.probesAtCap, probes.size()) << "the cap alone must stop every probe above 1.25 %";
  EXPECT_EQ(cappedStats.budgetPaths, 0u);

  BakeOptions budget = capped;
  budget.pathBudget = 400000;
  BakeStats stats;
  const std::vector<ShRgb> sh = bakeProbes(tracer, probes, budget, &stats);
  EXPECT_EQ(stats.probesAtCap, 0u) << "max achieved " << stats.maxRelError;
  EXPECT_LE(stats.maxRelError, 0.0125);
  EXPECT_GT(stats.budgetPaths, 0u);
  EXPECT_LE(stats.paths, budget.pathBudget + probes.size() * kBakeBatchSize);
  EXPECT_LE(stats.maxPathsPerProbe, kBakeBudgetCapFactor * capped.maxSamplesPerProbe);

  BakeOptions small = capped;  // a budget below what the caps spend changes nothing
  small.pathBudget = 1000;
  BakeStats smallStats;
  bakeProbes(tracer, probes, small, &smallStats);
  EXPECT_EQ(smallStats.paths, cappedStats.paths);

  BakeOptions one = budget;
  one.threads = 1;
  const std::vector<ShRgb> single = bakeProbes(tracer, probes, one);
  ASSERT_EQ(single.size(), sh.size());
  EXPECT_EQ(std::memcmp(single.data(), sh.data(), sh.size() * sizeof(ShRgb)), 0);
}

// Bad adaptive options are typed input errors.
TEST(AdaptiveSampling, RejectsNegativeTargetAndCapBelowMinimum) {
  Scene s;
  test::addSphere(s, glm::vec3(0.0f), 1.0f, true, test::addMaterial(s, glm::vec3(0.5f), glm::vec3(1.0f)));
  SceneTracer tracer(s);
  BakeOptions o = quiet(2, 256);
  o.targetRelError = -0.1;
  EXPECT_THROW(bakeProbes(tracer, {glm::dvec3(0.0)}, o), InputError);
  o.targetRelError = 0.02;
  o.maxSamplesPerProbe = 64;
  EXPECT_THROW(bakeProbes(tracer, {glm::dvec3(0.0)}, o), InputError);
}

// A dim closed room (albedo 0.2) lit only by a narrow spot light on a small white floor patch: every probe's
// light is bounce light, most of it from the patch, a small solid angle (the case probe guiding is for).
Scene spotlitRoom() {
  Scene s;
  test::addBox(s, glm::vec3(-3.0f), glm::vec3(3.0f), true, test::addMaterial(s, glm::vec3(0.2f)));
  test::addQuad(s, glm::vec3(-1.0f, -2.99f, -1.0f), glm::vec3(-1.0f, -2.99f, 1.0f),
                glm::vec3(1.0f, -2.99f, 1.0f), glm::vec3(1.0f, -2.99f, -1.0f),
                test::addMaterial(s, glm::vec3(0.9f)));
  Light spot;
  spot.type = LightType::kSpot;
  spot.position = glm::vec3(0.0f, 2.5f, 0.0f);
  spot.direction = glm::vec3(0.0f, -1.0f, 0.0f);
  spot.intensity = glm::vec3(400.0f);
  spot.innerConeRad = 0.15f;
  spot.outerConeRad = 0.18f;
  s.lights.push_back(spot);
  return s;
}

std::vector<glm::dvec3> spotlitProbes() {
  std::vector<glm::dvec3> probes;
  for (int i = 0; i < 12; ++i)
    probes.emplace_back(2.2 * std::sin(i * 1.7), 1.5 * std::cos(i * 0.9), 2.2 * std::cos(i * 1.7));
  return probes;
}

// Luminance of the irradiance at the six axis normals of a probe's SH.
std::array<double, 6> axisLuminance(const ShRgb& sh) {
  const glm::vec3 axes[6] = {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}};
  std::array<double, 6> out{};
  for (int k = 0; k < 6; ++k) out[size_t(k)] = luminance(glm::dvec3(shIrradiance(sh, axes[k])));
  return out;
}

// Two unbiased bakes of the same probes: every probe's luminance at the six axis normals agrees within `sigmas`
// combined standard errors (each bake's achieved relative stderr for the probe, times the first bake's mean
// over the normals, bounds its error at each normal). Returns the sums over probes and normals and a bound on
// the variance of their difference (the normals' errors may be correlated: 6 x the sum of each one's).
struct BakeSums {
  double a = 0.0, b = 0.0, variance = 0.0;
};
BakeSums expectBakesAgree(const std::vector<ShRgb>& a, const BakeStats& aStats, const std::vector<ShRgb>& b,
                          const BakeStats& bStats, double sigmas) {
  BakeSums sums;
  for (size_t i = 0; i < a.size(); ++i) {
    const std::array<double, 6> ea = axisLuminance(a[i]), eb = axisLuminance(b[i]);
    double mean = 0.0;
    for (double e : ea) mean += e / 6.0;
    const double sa = aStats.probeRelError[i] * mean, sb = bStats.probeRelError[i] * mean;
    for (size_t k = 0; k < 6; ++k) {
      EXPECT_LE(std::abs(ea[k] - eb[k]), sigmas * std::sqrt(sa * sa + sb * sb))
          << "probe " << i << " normal " << k << ": " << ea[k] << " vs " << eb[k];
      sums.a += ea[k];
      sums.b += eb[k];
    }
    sums.variance += 6.0 * 6.0 * (sa * sa + sb * sb);
  }
  return sums;
}

// The spotlit room, its probes, and its uniform bake: 8,192 paths a probe exactly (a target never reached), no
// guide.
struct SpotlitBake {
  Scene scene = spotlitRoom();
  SceneTracer tracer{scene};
  std::vector<glm::dvec3> probes = spotlitProbes();
  BakeOptions off = [] {
    BakeOptions o = quiet(kUnboundedBounces, 128, kContentDefault);
    o.targetRelError = 1e-4;
    o.maxSamplesPerProbe = 8192;
    o.guide = false;
    return o;
  }();
};

// Guiding draws directions from a histogram, but every direction is weighted by the mixture's density, so
// the estimate's expectation is the unguided one's: on the spotlit room, with both at 8,192 paths a probe,
// the irradiance at the six axis normals of every probe agrees within 4 combined standard errors (each
// probe's achieved relative stderr bounds its own; 12 x 6 comparisons, so 4 sigma leaves ~0.5 % chance of
// a false alarm overall). The guided bake's noise at the same paths is lower (the gain guiding is for), it is
// bit-identical for 1 and 2 threads, and a bake that stops at its first samplesPerProbe paths (no guided
// batch) is bit-identical to the unguided one.
TEST(ProbeGuiding, UnbiasedLessNoisyAndDeterministic) {
  const SpotlitBake room;
  BakeOptions on = room.off;
  on.guide = true;
  BakeStats offStats, onStats;
  const std::vector<ShRgb> a = bakeProbes(room.tracer, room.probes, room.off, &offStats);
  const std::vector<ShRgb> b = bakeProbes(room.tracer, room.probes, on, &onStats);
  ASSERT_EQ(offStats.paths, onStats.paths);
  expectBakesAgree(a, offStats, b, onStats, 4.0);
  std::printf(
      "probe guiding, spotlit room, %llu paths a bake: mean relative stderr %.4f uniform, %.4f guided\n",
      static_cast<unsigned long long>(onStats.paths), offStats.meanRelError, onStats.meanRelError);
  EXPECT_LT(onStats.meanRelError, 0.8 * offStats.meanRelError)
      << "guided " << onStats.meanRelError << ", uniform " << offStats.meanRelError;

  BakeOptions one = on;
  one.threads = 1;
  const std::vector<ShRgb> single = bakeProbes(room.tracer, room.probes, one);
  EXPECT_EQ(std::memcmp(single.data(), b.data(), b.size() * sizeof(ShRgb)), 0);

  BakeOptions firstOnly = room.off;
  firstOnly.maxSamplesPerProbe = firstOnly.samplesPerProbe;
  BakeOptions firstOnlyGuided = firstOnly;
  firstOnlyGuided.guide = true;
  const std::vector<ShRgb> c = bakeProbes(room.tracer, room.probes, firstOnly);
  const std::vector<ShRgb> d = bakeProbes(room.tracer, room.probes, firstOnlyGuided);
  EXPECT_EQ(std::memcmp(c.data(), d.data(), c.size() * sizeof(ShRgb)), 0);
}

// The direction guide goes on from pass to pass (ProbeBakeState::guide): on the spotlit room, every probe
// stopped at 2,048 paths in pass 2 (pass2MaxSamples) and then given the paths 8,192 a probe would have spent,
// shared by the path budget's pass over the states a shard hands on, is unbiased against the uniform bake (4
// combined standard errors, as above), about as converged as one pass of 8,192 (within 10 %; relearning the
// guide from scratch in the budget's pass loses its first batches and the guide learned from the earlier
// ones) and bit-identical for 1 and 2 threads. The
// states after pass 2 hold the guide: every batch after pass 1 recorded, light in some bin; shard and merge
// give the bytes one call gives.
TEST(ProbeGuiding, TheBudgetsPassGoesOnWithTheGuideEarlierPassesLearned) {
  const SpotlitBake room;
  BakeOptions onePass = room.off;
  onePass.guide = true;
  BakeOptions split = onePass;
  split.pass2MaxSamples = 2048;
  split.pathBudget = kBakeBatchSize;  // the caps' spend (flatCapPaths) is the budget
  BakeStats offStats, oneStats, splitStats;
  const std::vector<ShRgb> a = bakeProbes(room.tracer, room.probes, room.off, &offStats);
  bakeProbes(room.tracer, room.probes, onePass, &oneStats);
  const ShardBake states =
      bakeProbesShard(room.tracer, room.probes, split, std::vector<uint8_t>(room.probes.size(), 1), nullptr);
  ASSERT_EQ(states.states.size(), room.probes.size());
  for (const ProbeBakeState& st : states.states) {
    EXPECT_EQ(st.batches, 2048 / kBakeBatchSize);
    EXPECT_EQ(st.guideBatches, st.batches - 2);  // pass 1 (128 paths) learns nothing
    EXPECT_GT(*std::max_element(st.guide.begin(), st.guide.end()), 0.0f);
  }
  const std::vector<ShRgb> b = bakeProbesMerged(room.tracer, room.probes, split, states, &splitStats);
  // The caps' spend, shared by the error (rounded down a batch a probe at most).
  ASSERT_LE(splitStats.paths, oneStats.paths);
  ASSERT_GE(splitStats.paths + room.probes.size() * kBakeBatchSize, oneStats.paths);
  expectBakesAgree(a, offStats, b, splitStats, 4.0);
  std::printf(
      "spotlit room, 8,192 paths a probe: mean relative stderr %.4f one pass, %.4f in two (uniform %.4f)\n",
      oneStats.meanRelError, splitStats.meanRelError, offStats.meanRelError);
  EXPECT_LT(splitStats.meanRelError, 1.1 * oneStats.meanRelError);

  const std::vector<ShRgb> whole = bakeProbes(room.tracer, room.probes, split);  // one call: the same bytes
  EXPECT_EQ(std::memcmp(whole.data(), b.data(), b.size() * sizeof(ShRgb)), 0);
  BakeOptions single = split;
  single.threads = 1;
  const std::vector<ShRgb> one = bakeProbes(room.tracer, room.probes, single);
  EXPECT_EQ(std::memcmp(one.data(), b.data(), b.size() * sizeof(ShRgb)), 0);
}

}  // namespace
}  // namespace tetraprobe

namespace tetraprobe {
namespace {

// A closed 6 m room (albedo 0.5) lit only by a sun through a 2 m opening in the middle of its ceiling, no
// sky: the sunlit patch on the floor (and the walls it lights) is every probe's light, one bounce or more
// (the case lit-patch sampling is for).
Scene roofLitRoom() {
  Scene s;
  test::addBox(s, glm::vec3(-3.0f, 0.0f, -3.0f), glm::vec3(3.0f, 3.0f, 3.0f), true,
               test::addMaterial(s, glm::vec3(0.5f, 0.45f, 0.4f)), 3);
  // Face 3 is the ceiling (18 triangles a face with n = 3); its middle cell is triangles 8 and 9.
  s.triangles.erase(s.triangles.begin() + 3 * 18 + 8, s.triangles.begin() + 3 * 18 + 10);
  s.triangleMaterial.erase(s.triangleMaterial.begin() + 3 * 18 + 8, s.triangleMaterial.begin() + 3 * 18 + 10);
  Light sun;
  sun.type = LightType::kDirectional;
  sun.direction = glm::normalize(glm::vec3(0.25f, -1.0f, 0.15f));
  sun.intensity = glm::vec3(100.0f, 95.0f, 80.0f);
  sun.angularRadiusRad = 0.005f;
  s.lights.push_back(sun);
  return s;
}

std::vector<glm::dvec3> roofLitProbes() {
  std::vector<glm::dvec3> probes;
  for (int i = 0; i < 16; ++i)
    probes.emplace_back(2.3 * std::sin(i * 1.7), 1.5 + 1.1 * std::cos(i * 0.9), 2.3 * std::cos(i * 1.3));
  return probes;
}

// Lit-patch sampling draws points on the surfaces a probe's paths found lit and weighs them and the sphere
// directions (and, with kBounces, each of the first hits' points and the cosine direction that follows) by
// the power heuristic, so its expectation is the sphere's alone: at 65,536 paths a probe (1 M paths a bake),
// with either mode, every probe's irradiance at the six axis normals agrees with the bake without it within 4
// combined standard errors (96 comparisons a mode), and the sum over probes and normals within 3; each mode
// is less noisy than the bake without it.
TEST(LitPatches, AgreeWithSphereSamplingAtAMillionPaths) {
  const Scene s = roofLitRoom();
  const SceneTracer tracer(s);
  const std::vector<glm::dvec3> probes = roofLitProbes();
  BakeOptions off = quiet(kUnboundedBounces, 256, kContentDefault);
  off.targetRelError = 1e-6;  // never reached: every probe takes exactly maxSamplesPerProbe paths
  off.maxSamplesPerProbe = 65536;
  off.litPatches = LitPatches::kOff;
  BakeStats offStats;
  const std::vector<ShRgb> a = bakeProbes(tracer, probes, off, &offStats);
  ASSERT_GE(offStats.paths, 1000000u);
  for (const LitPatches mode : {LitPatches::kProbe, LitPatches::kBounces}) {
    BakeOptions on = off;
    on.litPatches = mode;
    BakeStats onStats;
    const std::vector<ShRgb> b = bakeProbes(tracer, probes, on, &onStats);
    ASSERT_EQ(offStats.paths, onStats.paths);
    SCOPED_TRACE("mode " + std::to_string(int(mode)));
    const BakeSums sums = expectBakesAgree(a, offStats, b, onStats, 4.0);
    EXPECT_LE(std::abs(sums.a - sums.b), 3.0 * std::sqrt(sums.variance)) << sums.a << " vs " << sums.b;
    std::printf(
        "lit patches (mode %d), roof-lit room, %llu paths a bake: mean relative stderr %.4f without, "
        "%.4f with\n",
        int(mode), static_cast<unsigned long long>(onStats.paths), offStats.meanRelError,
        onStats.meanRelError);
    EXPECT_LT(onStats.meanRelError, offStats.meanRelError);
  }
}

// On the room lit through its roof (half its light two or more bounces off the sunlit floor), with the default
// target (2 %) and a cap of 65,536 paths, every probe reaches the target with lit-patch sampling at the
// bounces (kBounces), in under half the paths of the bake without it (which leaves probes at the cap); the
// bake is bit-identical for 1 and 2 threads.
TEST(LitPatches, ReachTheTargetOnARoomLitThroughAnOpening) {
  const Scene s = roofLitRoom();
  const SceneTracer tracer(s);
  const std::vector<glm::dvec3> probes = roofLitProbes();
  BakeOptions on = quiet(kUnboundedBounces, 256, kContentDefault);
  on.targetRelError = 0.02;
  on.maxSamplesPerProbe = 65536;
  on.litPatches = LitPatches::kBounces;
  BakeOptions off = on;
  off.litPatches = LitPatches::kOff;
  BakeStats onStats, offStats;
  const std::vector<ShRgb> b = bakeProbes(tracer, probes, on, &onStats);
  bakeProbes(tracer, probes, off, &offStats);
  std::printf(
      "lit patches, roof-lit room, target 0.02: %llu paths, %zu at the cap, mean stderr %.4f with; "
      "%llu paths, %zu at the cap, mean %.4f without\n",
      static_cast<unsigned long long>(onStats.paths), onStats.probesAtCap, onStats.meanRelError,
      static_cast<unsigned long long>(offStats.paths), offStats.probesAtCap, offStats.meanRelError);
  EXPECT_EQ(onStats.probesAtCap, 0u);
  EXPECT_LE(onStats.maxRelError, on.targetRelError);
  EXPECT_GT(offStats.probesAtCap, 0u);
  EXPECT_LT(2 * onStats.paths, offStats.paths);
  BakeOptions one = on;
  one.threads = 1;
  const std::vector<ShRgb> single = bakeProbes(tracer, probes, one);
  EXPECT_EQ(std::memcmp(single.data(), b.data(), b.size() * sizeof(ShRgb)), 0);
}

// With one lit map for every call (BakeOptions::litVoxel) a probe's lit-patch histogram goes on from pass to
// pass as its direction guide does: on the roof-lit room, the states after pass 2 (1,024 paths) hold it; the
// budget's pass over those states (to the 4,096 paths a probe the cap would have spent, shared by the error)
// is as converged as one pass of 4,096 (within 10 %) and gives the bytes one call and one thread give.
// Without a given map nothing is carried (each call's map has its own voxels).
TEST(LitPatches, TheHistogramGoesOnFromPassToPassWithOneMap) {
  const Scene s = roofLitRoom();
  const SceneTracer tracer(s);
  const std::vector<glm::dvec3> probes = roofLitProbes();
  BakeOptions onePass = quiet(kUnboundedBounces, 256, kContentDefault);
  onePass.targetRelError = 1e-4;  // never reached: every probe takes its cap, with lit patches
  onePass.maxSamplesPerProbe = 4096;
  onePass.litVoxel = litMapVoxelEdge(probes, nullptr);
  BakeOptions split = onePass;
  split.pass2MaxSamples = 1024;
  split.pathBudget = kBakeBatchSize;
  const std::vector<uint8_t> all(probes.size(), 1);
  const ShardBake states = bakeProbesShard(tracer, probes, split, all, nullptr);
  for (const ProbeBakeState& st : states.states) {
    EXPECT_FALSE(st.patches.empty());
    EXPECT_GT(st.patchBatches, 0);
    EXPECT_TRUE(std::is_sorted(st.patches.begin(), st.patches.end()));
  }
  BakeStats oneStats, splitStats;
  bakeProbes(tracer, probes, onePass, &oneStats);
  const std::vector<ShRgb> b = bakeProbesMerged(tracer, probes, split, states, &splitStats);
  std::printf("roof-lit room, 4,096 paths a probe: mean relative stderr %.4f one pass, %.4f in two\n",
              oneStats.meanRelError, splitStats.meanRelError);
  EXPECT_LT(splitStats.meanRelError, 1.1 * oneStats.meanRelError);
  const std::vector<ShRgb> whole = bakeProbes(tracer, probes, split);
  EXPECT_EQ(std::memcmp(whole.data(), b.data(), b.size() * sizeof(ShRgb)), 0);
  BakeOptions single = split;
  single.threads = 1;
  const std::vector<ShRgb> one = bakeProbes(tracer, probes, single);
  EXPECT_EQ(std::memcmp(one.data(), b.data(), b.size() * sizeof(ShRgb)), 0);

  BakeOptions ownMap = split;
  ownMap.litVoxel = 0.0;
  for (const ProbeBakeState& st : bakeProbesShard(tracer, probes, ownMap, all, nullptr).states)
    EXPECT_TRUE(st.patches.empty() && st.patchBatches == 0);
}

// A bake whose steps go to a farm (BakeOptions::farm) is the local bake byte for byte, however the farm splits
// a step's probes: here each batch's items are dealt to three TraceRunners (each with its own lit-map cache and
// thread count), on the roof-lit room with lit patches, a cap that stops every probe above the target and
// a path budget, so pass 1, pass 2 and the budget's rounds all go to the farm; with the lit map fixed by
// litVoxel and with each call's own. The stats (rays, paths, per-probe errors) agree too.
TEST(TraceFarm, AFarmedBakeIsTheLocalBakeByteForByte) {
  const Scene s = roofLitRoom();
  const SceneTracer tracer(s);
  const std::vector<glm::dvec3> probes = roofLitProbes();
  std::vector<std::unique_ptr<TraceRunner>> runners;
  for (int k = 0; k < 3; ++k) runners.push_back(std::make_unique<TraceRunner>(tracer));
  std::array<int, 4> steps{};
  TraceFarm farm;
  farm.probes = [&](TraceBatch& batch) {
    ++steps[size_t(batch.step)];
    for (size_t part = 0; part < runners.size(); ++part) {
      TraceBatch mine = batch;
      mine.items.clear();
      for (size_t k = part; k < batch.items.size(); k += runners.size()) mine.items.push_back(batch.items[k]);
      runners[part]->run(mine, int(part) + 1);
      for (size_t k = part, n = 0; k < batch.items.size(); k += runners.size(), ++n)
        batch.items[k] = mine.items[n];
    }
  };
  for (const bool fixedMap : {true, false}) {
    BakeOptions local = quiet(kUnboundedBounces, 128, kContentDefault);
    local.targetRelError = 1e-4;  // never reached: every probe stops at a cap
    local.maxSamplesPerProbe = 1024;
    local.pass2MaxSamples = 256;
    local.pathBudget = kBakeBatchSize;  // pass 3 spends at least what the flat cap would have
    local.litPatches = LitPatches::kBounces;
    local.litVoxel = fixedMap ? litMapVoxelEdge(probes, nullptr) : 0.0;
    BakeOptions farmed = local;
    farmed.farm = &farm;
    steps = {};
    BakeStats a, b;
    const std::vector<ShRgb> here = bakeProbes(tracer, probes, local, &a);
    const std::vector<ShRgb> there = bakeProbes(tracer, probes, farmed, &b);
    EXPECT_EQ(steps[size_t(TraceStep::kPass1)], 1);
    EXPECT_EQ(steps[size_t(TraceStep::kPass2)], 1);
    EXPECT_GE(steps[size_t(TraceStep::kBudget)], 1);
    ASSERT_EQ(here.size(), there.size());
    EXPECT_EQ(std::memcmp(here.data(), there.data(), here.size() * sizeof(ShRgb)), 0)
        << "fixed map " << fixedMap;
    EXPECT_GT(a.budgetPaths, 0u);
    EXPECT_EQ(a.paths, b.paths);
    EXPECT_EQ(a.budgetPaths, b.budgetPaths);
    EXPECT_EQ(a.intersectRays, b.intersectRays);
    EXPECT_EQ(a.occludedRays, b.occludedRays);
    EXPECT_EQ(a.probeRelError, b.probeRelError);
  }
  TraceBatch bad;
  bad.step = TraceStep::kPass1;
  bad.options = quiet(kUnboundedBounces, 128, kContentDefault);
  bad.options.targetRelError = 0.02;
  bad.items.resize(1);
  bad.items[0].position = glm::dvec3(std::nan(""), 0.0, 0.0);
  EXPECT_THROW(runners[0]->run(bad, 1), InputError);
}

}  // namespace
}  // namespace tetraprobe
