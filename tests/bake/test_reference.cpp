// referenceIrradiance: the oracle the evaluation trusts, checked against closed forms.
#include <algorithm>
#include <cmath>
#include <numbers>

#include <gtest/gtest.h>
#include <glm/geometric.hpp>

#include "test_scenes.h"
#include "tetraprobe/bake/bake.h"
#include "tetraprobe/common/error.h"
#include "tetraprobe/runtime/luminance.h"

namespace tetraprobe {
namespace {

constexpr double kPi = std::numbers::pi;

BakeOptions opts(int bounces, uint32_t content) {
  BakeOptions o;
  o.bounces = bounces;
  o.content = content;
  o.progress = false;
  return o;
}

// Point, spot and sun light on a large plane: E = I cos / r^2 (+ spot, + E_sun cos) with nothing random in
// it (no sky, nothing above the plane to bounce from), so it must be exact to float precision (1e-5
// relative).
TEST(Reference, PunctualIrradianceIsInverseSquareCosine) {
  Scene s;
  const uint32_t m = test::addMaterial(s, glm::vec3(0.8f));
  test::addGround(s, 0.0f, 100.0f, m);
  Light point;
  point.position = {0.3f, 2.0f, -0.5f};
  point.intensity = {10.0f, 20.0f, 30.0f};
  Light spot;
  spot.type = LightType::kSpot;
  spot.position = {1.5f, 3.0f, 0.5f};
  spot.direction = {0, -1, 0};
  spot.intensity = {7.0f, 0.0f, 1.0f};
  spot.innerConeRad = 0.5f;
  spot.outerConeRad = 0.8f;
  Light sun;
  sun.type = LightType::kDirectional;
  sun.direction = glm::normalize(glm::vec3(0.5f, -1.0f, 0.25f));
  sun.intensity = {4.0f, 3.0f, 2.0f};
  s.lights = {point, spot, sun};
  SceneTracer tracer(s);
  const glm::dvec3 x(1.0, 0.0, 0.5);
  const ReferenceIrradiance r = referenceIrradiance(tracer, x, {0, 1, 0}, 64, 1, opts(2, kContentAll));
  auto inverseSquare = [&](const Light& l) {
    const glm::dvec3 d = glm::dvec3(l.position) - x;
    const double r2 = glm::dot(d, d);
    return glm::dvec3(l.intensity) * (d.y / std::sqrt(r2) / r2);
  };
  // The spot's axis is 0.5 m off the point at 3 m height: angle atan(0.5/3) < inner cone, full intensity.
  const glm::dvec3 exact =
      inverseSquare(point) + inverseSquare(spot) + glm::dvec3(sun.intensity) * double(-sun.direction.y);
  for (int ch = 0; ch < 3; ++ch) {
    EXPECT_NEAR(r.irradiance[ch], exact[ch], 1e-5 * exact[ch]) << "channel " << ch;
    EXPECT_NEAR(r.stderror[ch], 0.0f, 1e-6 * exact[ch]);
  }
  // Without the DirectPunctual flag the same point gets nothing (no bounce can reach it).
  const ReferenceIrradiance d = referenceIrradiance(tracer, x, {0, 1, 0}, 64, 1, opts(2, kContentDefault));
  EXPECT_EQ(d.irradiance, glm::vec3(0.0f));
}

// Spot cone falloff and a sun disc with an angular radius: between the cones the spot follows
// smoothstep(cos outer, cos inner, cos angle); the sun disc, sampled uniformly in its cone of half-angle r
// around an axis at angle t0 from the normal, averages E cos = E cos(t0) (1 + cos r) / 2. Tolerance 4 sigma +
// 1e-5 relative.
TEST(Reference, SpotFalloffAndSunDiscAverageMatchClosedForms) {
  Scene s;
  const uint32_t m = test::addMaterial(s, glm::vec3(0.8f));
  test::addGround(s, 0.0f, 100.0f, m);
  Light spot;
  spot.type = LightType::kSpot;
  spot.position = {0.0f, 2.0f, 0.0f};
  spot.direction = {0, -1, 0};
  spot.intensity = {8.0f, 8.0f, 8.0f};
  spot.innerConeRad = 0.3f;
  spot.outerConeRad = 0.6f;
  Light sun;
  sun.type = LightType::kDirectional;
  sun.direction = glm::normalize(glm::vec3(0.6f, -1.0f, 0.0f));
  sun.intensity = {0.0f, 5.0f, 0.0f};  // green only, so the red channel checks the spot alone
  sun.angularRadiusRad = 0.1f;
  s.lights = {spot, sun};
  SceneTracer tracer(s);
  const glm::dvec3 x(0.9, 0.0, 0.0);  // 24.2 degrees off the spot axis: inside the falloff band
  const ReferenceIrradiance r = referenceIrradiance(tracer, x, {0, 1, 0}, 4096, 2, opts(0, kContentAll));
  const glm::dvec3 d = glm::dvec3(spot.position) - x;
  const double dist = glm::length(d), c = d.y / dist;
  const double t = std::clamp((c - std::cos(0.6)) / (std::cos(0.3) - std::cos(0.6)), 0.0, 1.0);
  const double spotE = 8.0 * t * t * (3 - 2 * t) * c / (dist * dist);
  ASSERT_GT(t, 0.05);
  ASSERT_LT(t, 0.95);
  EXPECT_NEAR(r.irradiance.x, spotE, 1e-5 * spotE);
  const double sunE = 5.0 * double(-sun.direction.y) * (1.0 + std::cos(0.1)) / 2.0;
  EXPECT_NEAR(r.irradiance.y, spotE + sunE, 4 * r.stderror.y + 1e-5 * sunE);
}

// A gradient sky (zenith Z at +Y, horizon H at and below the horizon, linear in y) integrates in closed form:
// on an upward plane E = pi H + 2 pi (Z - H) / 3; for a probe in open space L00 = Y00 (4 pi H + pi (Z - H))
// and L1,-1 (the y coefficient) = Y1 2 pi (Z - H) / 3. Tolerance 4 sigma + 1e-5 relative for E (cosine rays
// are random), 2e-4 relative for the probe (Fibonacci quadrature of a kinked function, 4096 directions).
TEST(Reference, GradientSkyIntegratesToClosedForm) {
  Scene s;
  const uint32_t m = test::addMaterial(s, glm::vec3(0.8f));
  test::addGround(s, 0.0f, 100.0f, m);
  s.skyRadiance = {2.0f, 1.0f, 0.5f};
  s.skyHorizonRadiance = {0.5f, 1.0f, 1.0f};
  SceneTracer tracer(s);
  const ReferenceIrradiance r =
      referenceIrradiance(tracer, {1.0, 0.0, 2.0}, {0, 1, 0}, 4096, 8, opts(2, kContentSky));
  for (int ch = 0; ch < 3; ++ch) {
    const double z = s.skyRadiance[ch], h = s.skyHorizonRadiance[ch];
    const double exact = kPi * h + 2.0 * kPi * (z - h) / 3.0;
    EXPECT_NEAR(r.irradiance[ch], exact, 4 * r.stderror[ch] + 1e-5 * exact) << "channel " << ch;
  }
  // The probe: sky alone, in a scene of one tiny far-away triangle (a tracer needs geometry).
  Scene open;
  const uint32_t mo = test::addMaterial(open, glm::vec3(0.8f));
  test::addTriangle(open, {1000, 1000, 1000}, {1000.1f, 1000, 1000}, {1000, 1000.1f, 1000}, mo);
  open.skyRadiance = s.skyRadiance;
  open.skyHorizonRadiance = s.skyHorizonRadiance;
  SceneTracer openTracer(open);
  BakeOptions o = opts(2, kContentSky);
  o.samplesPerProbe = 4096;
  const auto sh = bakeProbes(openTracer, {glm::dvec3(0.0)}, o);
  for (int ch = 0; ch < 3; ++ch) {
    const double z = s.skyRadiance[ch], h = s.skyHorizonRadiance[ch];
    const double l00 = sh_const::kY00 * (4.0 * kPi * h + kPi * (z - h));
    const double l1y = sh_const::kY1 * 2.0 * kPi * (z - h) / 3.0;
    EXPECT_NEAR(sh[0].c[0][ch], l00, 2e-4 * l00) << "channel " << ch;
    EXPECT_NEAR(sh[0].c[1][ch], l1y, 2e-4 * l00) << "channel " << ch;
  }
}

// A ground plane under a uniform sky of radiance S: E = pi S (the cosine-weighted hemisphere integral).
// Tolerance 4 sigma + 1e-6 relative (every cosine ray escapes, so sigma is ~0 here).
TEST(Reference, UniformSkyOnGroundIsPiTimesSkyRadiance) {
  Scene s;
  const uint32_t m = test::addMaterial(s, glm::vec3(0.8f));
  test::addGround(s, 0.0f, 100.0f, m);
  s.skyRadiance = {0.5f, 1.0f, 1.5f};
  SceneTracer tracer(s);
  const ReferenceIrradiance r =
      referenceIrradiance(tracer, {2.0, 0.0, -3.0}, {0, 1, 0}, 1024, 5, opts(2, kContentAll));
  EXPECT_EQ(r.samples, 1024);
  for (int ch = 0; ch < 3; ++ch) {
    const double exact = kPi * s.skyRadiance[ch];
    EXPECT_NEAR(r.irradiance[ch], exact, 4 * r.stderror[ch] + 1e-6 * exact) << "channel " << ch;
  }
}

// Lambert's contour integral for the irradiance from a uniformly emitting polygon (front face towards x):
// E = Le / 2 sum_i angle(r_i, r_i+1) n . unit(r_i x r_i+1).
double polygonIrradiance(const std::vector<glm::dvec3>& poly, const glm::dvec3& x, const glm::dvec3& n,
                         double le) {
  double sum = 0;
  for (size_t i = 0; i < poly.size(); ++i) {
    const glm::dvec3 a = glm::normalize(poly[i] - x), b = glm::normalize(poly[(i + 1) % poly.size()] - x);
    sum += std::acos(std::clamp(glm::dot(a, b), -1.0, 1.0)) * glm::dot(n, glm::normalize(glm::cross(a, b)));
  }
  return std::fabs(0.5 * le * sum);
}

// An emissive quad lighting a point: light sampling by power + cosine sampling, combined by MIS, must
// reproduce Lambert's exact polygon formula. Any error in the pdf conversion (area -> solid angle) or the
// MIS weights shows here. Tolerance 4 sigma + 1e-4 relative.
TEST(Reference, EmissiveQuadMatchesLambertPolygonFormula) {
  Scene s;
  const uint32_t ground = test::addMaterial(s, glm::vec3(0.5f));
  const glm::vec3 le(3.0f, 2.0f, 1.0f);
  const uint32_t lamp = test::addMaterial(s, glm::vec3(0.5f), le);
  test::addGround(s, 0.0f, 20.0f, ground);
  const std::vector<glm::dvec3> quad = {
      {-0.5, 1.5, 0.3}, {-0.5, 1.5, -0.7}, {1.0, 1.2, -0.7}, {1.0, 1.2, 0.3}};
  // Front face towards -Y-ish (counter-clockwise seen from below).
  test::addQuad(s, glm::vec3(quad[0]), glm::vec3(quad[1]), glm::vec3(quad[2]), glm::vec3(quad[3]), lamp, 3);
  SceneTracer tracer(s);
  ASSERT_LT(tracer.intersect({0.2f, 0.5f, -0.2f}, {0, 1, 0}, 0.0f, 10.0f).geometricNormal.y, 0.0f);
  const glm::dvec3 x(0.4, 0.0, 0.6);
  for (int bounces : {0, 2}) {
    const ReferenceIrradiance r =
        referenceIrradiance(tracer, x, {0, 1, 0}, 4096, 11, opts(bounces, kContentEmissive));
    for (int ch = 0; ch < 3; ++ch) {
      const double exact = polygonIrradiance(quad, x, {0, 1, 0}, le[ch]);
      EXPECT_NEAR(r.irradiance[ch], exact, 4 * r.stderror[ch] + 1e-4 * exact) << "channel " << ch;
      EXPECT_GT(r.stderror[ch], 0.0f);
      EXPECT_LT(r.stderror[ch], 0.05 * exact) << "MIS should make this an easy integral";
    }
  }
}

// Furnace for the oracle: on the inner wall of a closed emissive sphere the irradiance is
// pi Le sum_{k<=B} a^k. Tolerance 4 sigma + 2e-4 relative.
TEST(Reference, FurnaceIrradianceIsPiTimesGeometricSeries) {
  Scene s;
  const float a = 0.6f;
  const glm::vec3 le(1.0f, 0.5f, 2.0f);
  const uint32_t m = test::addMaterial(s, glm::vec3(a), le);
  test::addSphere(s, glm::vec3(0.0f), 1.0f, true, m);
  SceneTracer tracer(s);
  // A point on a triangle of the sphere (its centroid), normal towards the inside.
  const glm::uvec3 t = s.triangles[200];
  const glm::vec3 c = (s.positions[t.x] + s.positions[t.y] + s.positions[t.z]) / 3.0f;
  const glm::vec3 n =
      glm::normalize(glm::cross(s.positions[t.y] - s.positions[t.x], s.positions[t.z] - s.positions[t.x]));
  ASSERT_LT(glm::dot(n, c), 0.0f);
  for (int bounces : {0, 1, 3}) {
    double series = 0;
    for (int k = 0; k <= bounces; ++k) series += std::pow(a, k);
    const ReferenceIrradiance r =
        referenceIrradiance(tracer, glm::dvec3(c), n, 4096, 3, opts(bounces, kContentAll));
    for (int ch = 0; ch < 3; ++ch) {
      const double exact = kPi * le[ch] * series;
      EXPECT_NEAR(r.irradiance[ch], exact, 4 * r.stderror[ch] + 2e-4 * exact) << "bounces " << bounces;
    }
  }
}

// The unbiased oracle (and bake): paths end by Russian roulette only, so inside a closed emissive sphere of
// albedo 0.9 the irradiance converges to the infinite series pi Le / (1 - a) = 10 pi Le, which any fixed
// depth misses (8 bounces give 1 - 0.9^9 = 61 % of it). Tolerance 4 sigma + 2e-4 relative; the probe at the
// centre sees Le / (1 - a) in every direction. A path's length is geometric here (relative standard deviation
// ~0.95 per path), so 4096 paths leave ~1.5 % noise: tolerance 6 % (4 sigma).
TEST(Reference, WhiteFurnaceWithUnboundedDepthConvergesToInfiniteSeries) {
  Scene s;
  const float a = 0.9f;
  const glm::vec3 le(1.0f, 0.5f, 2.0f);
  const uint32_t m = test::addMaterial(s, glm::vec3(a), le);
  test::addSphere(s, glm::vec3(0.0f), 1.0f, true, m);
  SceneTracer tracer(s);
  const glm::uvec3 t = s.triangles[200];
  const glm::vec3 c = (s.positions[t.x] + s.positions[t.y] + s.positions[t.z]) / 3.0f;
  const glm::vec3 n =
      glm::normalize(glm::cross(s.positions[t.y] - s.positions[t.x], s.positions[t.z] - s.positions[t.x]));
  const BakeOptions o = opts(kUnboundedBounces, kContentAll);
  EXPECT_EQ(BakeOptions{}.bounces, kUnboundedBounces) << "the default depth is unbiased";
  const ReferenceIrradiance r = referenceIrradiance(tracer, glm::dvec3(c), n, 8192, 5, o);
  for (int ch = 0; ch < 3; ++ch) {
    const double exact = kPi * le[ch] / (1.0 - a);
    EXPECT_NEAR(r.irradiance[ch], exact, 4 * r.stderror[ch] + 2e-4 * exact) << "channel " << ch;
    // and a fixed depth of 8 is measurably dark: it must not pass the same test
    const ReferenceIrradiance r8 =
        referenceIrradiance(tracer, glm::dvec3(c), n, 2048, 5, opts(8, kContentAll));
    EXPECT_LT(r8.irradiance[ch] + 4 * r8.stderror[ch], 0.7 * exact);
  }
  BakeOptions probe = o;
  probe.samplesPerProbe = 4096;
  const ShRgb sh = bakeProbes(tracer, {glm::dvec3(0.0)}, probe)[0];
  for (const glm::vec3& dir : {glm::vec3(0, 1, 0), glm::vec3(1, 0, 0), glm::vec3(0, 0, -1)}) {
    const glm::vec3 e = shIrradiance(sh, dir);
    for (int ch = 0; ch < 3; ++ch)
      EXPECT_NEAR(e[ch], kPi * le[ch] / (1.0 - a), 0.06 * kPi * le[ch] / (1 - a));
  }
}

// Probe and oracle agree: the irradiance reconstructed from a baked probe just above a sky-lit ground plane
// matches the reference at the point below it (L2 is exact for this smooth, low-frequency field up to the
// ringing bound; tolerance 3 % + 4 sigma).
TEST(Reference, AgreesWithProbeIrradianceUnderSky) {
  Scene s;
  const uint32_t m = test::addMaterial(s, glm::vec3(0.5f));
  test::addGround(s, 0.0f, 200.0f, m);
  s.skyRadiance = {1.0f, 1.0f, 1.0f};
  SceneTracer tracer(s);
  BakeOptions o = opts(1, kContentDefault);
  o.samplesPerProbe = 4096;
  const auto sh = bakeProbes(tracer, {glm::dvec3(0, 0.01, 0)}, o);
  const glm::vec3 e = shIrradiance(sh[0], {0, 1, 0});
  const ReferenceIrradiance r = referenceIrradiance(tracer, {0, 0, 0}, {0, 1, 0}, 1024, 9, o);
  for (int ch = 0; ch < 3; ++ch)
    EXPECT_NEAR(e[ch], r.irradiance[ch], 0.03 * r.irradiance[ch] + 4 * r.stderror[ch]);
}

// The adaptive oracle stops as soon as the luminance's relative standard error is at most the target (on a
// batch boundary), is the fixed-count oracle at the sample count it stopped at (same streams), and respects
// maxSamples. A point in the dark stops at minSamples.
TEST(Reference, ToErrorStopsAtTheTargetAndEqualsFixedCount) {
  Scene s;
  const uint32_t m = test::addMaterial(s, glm::vec3(0.5f));
  test::addGround(s, 0.0f, 200.0f, m);
  test::addQuad(s, {-1, 2, -1}, {1, 2, -1}, {1, 2, 1}, {-1, 2, 1}, m);  // a roof: some variance
  s.skyRadiance = {1.0f, 0.8f, 0.6f};
  SceneTracer tracer(s);
  const BakeOptions o = opts(2, kContentDefault);
  const glm::dvec3 p(0.9, 0.0, 0.3);
  const glm::vec3 n(0, 1, 0);
  const auto lum = [](const glm::vec3& c) { return luminance(glm::dvec3(c)); };
  for (double target : {0.05, 0.01}) {
    const ReferenceIrradiance r = referenceIrradianceToError(tracer, p, n, target, 1 << 20, 17, o);
    EXPECT_GE(r.samples, 64);
    EXPECT_EQ((r.samples - 64) % 32, 0);
    const ReferenceIrradiance fixed = referenceIrradiance(tracer, p, n, r.samples, 17, o);
    EXPECT_EQ(r.irradiance, fixed.irradiance);
    EXPECT_EQ(r.stderror, fixed.stderror);
    // (the luminance stderr is not the luminance of the channel stderrors; check the stop loosely)
    EXPECT_LT(lum(r.stderror), 1.5 * target * lum(r.irradiance)) << target;
    if (r.samples > 64) {
      const ReferenceIrradiance before = referenceIrradiance(tracer, p, n, r.samples - 32, 17, o);
      EXPECT_GT(lum(before.stderror), 0.5 * target * lum(before.irradiance)) << "stopped late";
    }
  }
  const ReferenceIrradiance capped = referenceIrradianceToError(tracer, p, n, 1e-6, 100, 17, o);
  EXPECT_EQ(capped.samples, 100);
  Scene dark;
  test::addGround(dark, 0.0f, 10.0f, test::addMaterial(dark, glm::vec3(0.5f)));
  SceneTracer darkTracer(dark);
  EXPECT_EQ(referenceIrradianceToError(darkTracer, p, n, 0.01, 1000, 1, o).samples, 64);
  EXPECT_THROW(referenceIrradianceToError(tracer, p, n, -1.0, 100, 1, o), InputError);
  EXPECT_THROW(referenceIrradianceToError(tracer, p, n, 0.01, 0, 1, o), InputError);
}

}  // namespace
}  // namespace tetraprobe
