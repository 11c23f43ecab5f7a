// Transmission and alpha cutouts in the tracer, the path tracer and the geometric tests: closed forms under a
// sun or a uniform sky through a pane, a checkerboard cutout that passes rays exactly over its holes, a glass
// furnace, determinism, and bit-identity of opaque surfaces.
#include <cmath>
#include <cstring>
#include <limits>
#include <numbers>

#include <gtest/gtest.h>
#include <glm/geometric.hpp>

#include "test_scenes.h"
#include "tetraprobe/bake/bake.h"
#include "tetraprobe/bake/tracer.h"
#include "tetraprobe/common/error.h"

namespace tetraprobe {
namespace {

constexpr float kInf = std::numeric_limits<float>::infinity();
constexpr double kPi = std::numbers::pi;

BakeOptions opts(int bounces, uint32_t content, int samples = 256) {
  BakeOptions o;
  o.bounces = bounces;
  o.content = content;
  o.samplesPerProbe = samples;
  o.progress = false;
  o.threads = 2;
  return o;
}

uint32_t addGlass(Scene& s, glm::vec3 albedo, float transmission) {
  const uint32_t m = test::addMaterial(s, albedo);
  s.materials[m].transmission = transmission;
  return m;
}

// Black ground (y = 0, nothing reflects from it) under a horizontal pane at y = 1 of `paneMaterial`, both
// much larger than the 1 m gap so the pane covers the ground's sky up to 1e-6 of its cosine lobe.
Scene paneOverGround(float transmission, glm::vec3 paneAlbedo = glm::vec3(0.5f)) {
  Scene s;
  const uint32_t black = test::addMaterial(s, glm::vec3(0.0f));
  const uint32_t pane = addGlass(s, paneAlbedo, transmission);
  test::addGround(s, 0.0f, 2000.0f, black);
  test::addGround(s, 1.0f, 1000.0f, pane);
  return s;
}

Light sun() {
  Light l;
  l.type = LightType::kDirectional;
  l.direction = glm::normalize(glm::vec3(0.3f, -1.0f, 0.2f));
  l.intensity = {900.0f, 850.0f, 800.0f};
  return l;
}

// Sun over the pane: the ground's irradiance is transmission x E cos, exactly (shadow rays carry the
// transmittance; the pane's lit top cannot reach the ground and its underside sees no light).
TEST(Tracer, GlassPanePassesLightByItsTransmission) {
  const Light l = sun();
  const double unshadowed = double(-l.direction.y);
  for (float t : {0.0f, 0.3f, 0.75f, 1.0f}) {
    Scene s = paneOverGround(t);
    s.lights = {l};
    SceneTracer tracer(s);
    EXPECT_EQ(tracer.hasTransmission(), t > 0.0f);
    const ReferenceIrradiance r =
        referenceIrradiance(tracer, {0.2, 0.0, -0.1}, {0, 1, 0}, 64, 7, opts(2, kContentAll));
    for (int ch = 0; ch < 3; ++ch) {
      const double exact = double(t) * double(l.intensity[ch]) * unshadowed;
      EXPECT_NEAR(r.irradiance[ch], exact, 1e-5 * double(l.intensity[ch])) << "t " << t << " channel " << ch;
    }
    EXPECT_NEAR(tracer.transmittance({0, 0.5f, 0}, {0, 1, 0}, 0.0f, kInf), t, 1e-7f);
  }
}

// Uniform sky over the pane: E = pi L (t covered + uncovered), estimated by paths that pass the pane with
// probability t; the answer lies within 4 standard errors.
TEST(Reference, SkyThroughGlassPaneIsTransmissionTimesPiL) {
  const glm::vec3 sky(1.0f, 2.0f, 3.0f);
  const float t = 0.4f;
  Scene s = paneOverGround(t, glm::vec3(0.7f));
  s.skyRadiance = sky;
  SceneTracer tracer(s);
  const ReferenceIrradiance r =
      referenceIrradiance(tracer, {0.0, 0.0, 0.0}, {0, 1, 0}, 4096, 3, opts(3, kContentAll));
  const double covered = 1000.0 * 1000.0 / (1.0 + 1000.0 * 1000.0);  // cosine-lobe fraction (disc bound)
  for (int ch = 0; ch < 3; ++ch) {
    const double exact = kPi * sky[ch] * (t * covered + (1.0 - covered));
    EXPECT_GT(r.stderror[ch], 0.0f);
    EXPECT_NEAR(r.irradiance[ch], exact, 4.0 * r.stderror[ch] + 1e-5 * exact) << "channel " << ch;
  }
}

// A furnace whose emissive wall also transmits t to a black outside: it reflects (1 - t) a, so the radiance
// inside is Le sum_{k<=B} ((1 - t) a)^k. Pins that passing is no bounce and the reflection takes no weight.
TEST(WhiteFurnace, GlassWallReflectsOneMinusTransmissionOfItsAlbedo) {
  Scene s;
  const float a = 0.8f, t = 0.5f;
  const glm::vec3 le(1.0f, 2.0f, 0.5f);
  const uint32_t m = test::addMaterial(s, glm::vec3(a), le);
  s.materials[m].transmission = t;
  test::addSphere(s, glm::vec3(0.0f), 1.0f, true, m);
  SceneTracer tracer(s);
  std::vector<glm::dvec3> probes;
  for (int i = 0; i < 24; ++i)
    probes.push_back(0.5 * glm::dvec3(std::sin(i * 1.3), std::cos(i * 2.1), std::sin(i * 0.7 + 1.0)) / 1.8);
  const int bounces = 3;
  double series = 0;
  for (int k = 0; k <= bounces; ++k) series += std::pow((1.0 - t) * a, k);
  const std::vector<ShRgb> sh = bakeProbes(tracer, probes, opts(bounces, kContentDefault, 512));
  for (int ch = 0; ch < 3; ++ch) {
    double sum = 0, sum2 = 0;
    for (const ShRgb& p : sh) {
      sum += p.c[0][ch];
      sum2 += double(p.c[0][ch]) * p.c[0][ch];
    }
    const double n = double(sh.size()), mean = sum / n;
    const double se = std::sqrt(std::max(0.0, (sum2 - sum * sum / n) / (n - 1)) / n);
    const double exact = le[ch] * series * std::sqrt(4.0 * kPi);
    EXPECT_NEAR(mean, exact, 4 * se + 2e-4 * exact) << "channel " << ch;
  }
}

// The probe bake's analytic sun delta is scaled by the pane's transmission (nothing else lights the probe:
// black sky, black ground, black pane).
TEST(BakeProbes, SunThroughGlassScalesTheProbeDeltaByTheTransmission) {
  const std::vector<glm::dvec3> probes = {{0.0, 0.5, 0.0}, {3.0, 0.25, -2.0}};
  Scene clear = paneOverGround(1.0f, glm::vec3(0.0f));
  clear.lights = {sun()};
  SceneTracer clearTracer(clear);
  const std::vector<ShRgb> reference = bakeProbes(clearTracer, probes, opts(2, kContentAll, 64));
  Scene glass = paneOverGround(0.35f, glm::vec3(0.0f));
  glass.lights = {sun()};
  SceneTracer glassTracer(glass);
  const std::vector<ShRgb> sh = bakeProbes(glassTracer, probes, opts(2, kContentAll, 64));
  for (size_t p = 0; p < probes.size(); ++p)
    for (int i = 0; i < kShCoeffCount; ++i)
      for (int ch = 0; ch < 3; ++ch)
        EXPECT_NEAR(sh[p].c[i][ch], 0.35f * reference[p].c[i][ch], 1e-5f * std::abs(reference[p].c[0][ch]))
            << "probe " << p << " coefficient " << i;
}

// Every random decision about glass uses the path's own generator: the bake is bit-identical for any
// thread count, and a reference point for a given seed.
TEST(BakeProbes, GlassBakeIsBitIdenticalForAnyThreadCount) {
  Scene s = paneOverGround(0.5f);
  s.skyRadiance = glm::vec3(1.0f, 0.8f, 0.6f);
  s.lights = {sun()};
  SceneTracer tracer(s);
  std::vector<glm::dvec3> probes;
  for (int i = 0; i < 16; ++i) probes.push_back({0.3 * i - 2.0, 0.1 + 0.12 * i, 0.2 * i - 1.0});
  BakeOptions o = opts(3, kContentAll, 128);
  o.threads = 1;
  const std::vector<ShRgb> one = bakeProbes(tracer, probes, o);
  o.threads = 2;
  const std::vector<ShRgb> two = bakeProbes(tracer, probes, o);
  ASSERT_EQ(one.size(), two.size());
  EXPECT_EQ(std::memcmp(one.data(), two.data(), one.size() * sizeof(ShRgb)), 0);
  const ReferenceIrradiance a = referenceIrradiance(tracer, {0.5, 0.0, 0.5}, {0, 1, 0}, 256, 11, o);
  const ReferenceIrradiance b = referenceIrradiance(tracer, {0.5, 0.0, 0.5}, {0, 1, 0}, 256, 11, o);
  EXPECT_EQ(std::memcmp(&a.irradiance, &b.irradiance, sizeof(a.irradiance)), 0);
}

// Opaque surfaces take the same decisions whether or not some other triangle transmits (then shadow rays
// step through closest hits instead of one any-hit query): the answers are bit-identical.
TEST(Reference, OpaquePaneAnswerIsBitIdenticalWhenTheSceneAlsoHasGlass) {
  Scene opaque = paneOverGround(0.0f);
  opaque.skyRadiance = glm::vec3(0.5f, 1.0f, 2.0f);
  opaque.lights = {sun()};
  Light bulb;
  bulb.position = {0.5f, 0.5f, 0.5f};
  bulb.intensity = glm::vec3(3.0f);
  opaque.lights.push_back(bulb);
  opaque.materials[1].emission = glm::vec3(0.25f);  // the pane glows downwards: emissive NEE too
  Scene withGlass = opaque;
  const uint32_t glass = addGlass(withGlass, glm::vec3(0.5f), 0.5f);
  // Inside the scene's bounds (which set rayEpsilon) but far from the points: never met.
  test::addTriangle(withGlass, {1900, 0.2f, 1900}, {1900.1f, 0.2f, 1900}, {1900, 0.3f, 1900}, glass);
  SceneTracer a(opaque), b(withGlass);
  ASSERT_FALSE(a.hasTransmission());
  ASSERT_TRUE(b.hasTransmission());
  for (const glm::dvec3& x : {glm::dvec3(0.0), glm::dvec3(1.5, 0.0, -0.5)}) {
    const ReferenceIrradiance ra = referenceIrradiance(a, x, {0, 1, 0}, 128, 5, opts(3, kContentAll));
    const ReferenceIrradiance rb = referenceIrradiance(b, x, {0, 1, 0}, 128, 5, opts(3, kContentAll));
    EXPECT_GT(ra.irradiance.x, 0.0f);
    EXPECT_EQ(std::memcmp(&ra.irradiance, &rb.irradiance, sizeof(ra.irradiance)), 0);
    EXPECT_EQ(std::memcmp(&ra.stderror, &rb.stderror, sizeof(ra.stderror)), 0);
  }
}

// Two stacked panes over an opaque floor: intersect's maxTransmission picks which count, and the
// transmittance of a segment is the product of the panes it crosses (0 once it reaches the floor).
TEST(Tracer, QueriesStepOverSurfacesMoreTransmissiveThanAsked) {
  Scene s;
  const uint32_t floor = test::addMaterial(s, glm::vec3(0.5f));
  const uint32_t clear = addGlass(s, glm::vec3(0.5f), 0.8f);
  const uint32_t tinted = addGlass(s, glm::vec3(0.5f), 0.25f);
  test::addGround(s, 0.0f, 10.0f, floor);
  test::addGround(s, 1.0f, 10.0f, tinted);
  test::addGround(s, 2.0f, 10.0f, clear);
  SceneTracer tracer(s);
  const glm::vec3 o(0.1f, 3.0f, 0.2f), down(0, -1, 0);
  EXPECT_NEAR(tracer.intersect(o, down, 0.0f, kInf).t, 1.0f, 1e-5f);
  EXPECT_NEAR(tracer.intersect(o, down, 0.0f, kInf, 0.5f).t, 2.0f, 1e-5f);
  EXPECT_NEAR(tracer.intersect(o, down, 0.0f, kInf, 0.0f).t, 3.0f, 1e-5f);
  EXPECT_FALSE(tracer.occluded(o, down, 0.0f, 2.5f, 0.0f));
  EXPECT_TRUE(tracer.occluded(o, down, 0.0f, 2.5f, 0.5f));
  EXPECT_TRUE(tracer.occluded(o, down, 0.0f, 1.5f));
  EXPECT_FALSE(tracer.occluded(o, down, 0.0f, 1.5f, 0.7f));
  EXPECT_FLOAT_EQ(tracer.transmittance(o, down, 0.0f, 0.5f), 1.0f);
  EXPECT_FLOAT_EQ(tracer.transmittance(o, down, 0.0f, 1.5f), 0.8f);
  EXPECT_FLOAT_EQ(tracer.transmittance(o, down, 0.0f, 2.5f), 0.8f * 0.25f);
  EXPECT_EQ(tracer.transmittance(o, down, 0.0f, kInf), 0.0f);
}

// A unit quad at height 1 (x, z in [0, 1], texture coordinates u = x, v = z) cut by a 4 x 4 checkerboard:
// texel (i, j) is a hole when i + j is even, half the area.
void addCheckerQuad(Scene& s, uint32_t material) {
  const uint32_t first = uint32_t(s.triangles.size());
  test::addQuad(s, {0, 1, 0}, {1, 1, 0}, {1, 1, 1}, {0, 1, 1}, material);
  AlphaTexture tex;
  tex.name = "checker";
  tex.width = tex.height = 4;
  for (uint32_t j = 0; j < 4; ++j)
    for (uint32_t i = 0; i < 4; ++i) tex.alpha.push_back((i + j) % 2 == 0 ? 0 : 255);
  s.materials[material].alphaTexture = int32_t(s.alphaTextures.size());
  s.alphaTextures.push_back(tex);
  // addQuad's triangles: (a, b, c) and (a, c, d) with a..d at uv (0,0) (1,0) (1,1) (0,1).
  s.cutoutTriangles.insert(s.cutoutTriangles.end(), {first, first + 1});
  s.cutoutUvs.insert(s.cutoutUvs.end(), {{0, 0}, {1, 0}, {1, 1}, {0, 0}, {1, 1}, {0, 1}});
}

bool checkerHole(float x, float z) {
  return (int(std::floor(4.0f * x)) + int(std::floor(4.0f * z))) % 2 == 0;
}

// Rays down through the checkerboard pass exactly over its transparent texels (to the floor below) and stop
// on its opaque ones, for intersect, occluded and transmittance alike: half of a 64 x 64 grid of rays.
TEST(Tracer, CutoutQuadPassesRaysThroughItsTransparentTexels) {
  Scene s;
  const uint32_t floor = test::addMaterial(s, glm::vec3(0.5f));
  const uint32_t leaves = test::addMaterial(s, glm::vec3(0.3f, 0.6f, 0.2f));
  test::addGround(s, 0.0f, 10.0f, floor);
  addCheckerQuad(s, leaves);
  SceneTracer tracer(s);
  int through = 0;
  for (int j = 0; j < 64; ++j)
    for (int i = 0; i < 64; ++i) {
      const float x = (float(i) + 0.5f) / 64.0f, z = (float(j) + 0.5f) / 64.0f;
      const glm::vec3 o(x, 2.0f, z), down(0, -1, 0);
      const Hit h = tracer.intersect(o, down, 0.0f, kInf);
      ASSERT_TRUE(h.hit);
      const bool hole = checkerHole(x, z);
      EXPECT_NEAR(h.t, hole ? 2.0f : 1.0f, 1e-5f) << x << ", " << z;
      EXPECT_EQ(s.triangleMaterial[h.triangle], hole ? floor : leaves);
      EXPECT_EQ(tracer.occluded(o, down, 0.0f, 1.5f), !hole);
      EXPECT_EQ(tracer.transmittance(o, down, 0.0f, 1.5f), hole ? 1.0f : 0.0f);
      EXPECT_EQ(tracer.isHole(h.triangle, h.u, h.v), false);
      through += hole;
    }
  EXPECT_EQ(through, 64 * 64 / 2);
  // Random directions from below: the fraction that escapes is the open fraction of the quad they cross.
  int crossed = 0, escaped = 0;
  for (int k = 0; k < 4000; ++k) {
    const float x = 0.1f + 0.8f * float((k * 37) % 1000) / 1000.0f,
                z = 0.1f + 0.8f * float((k * 91) % 997) / 997.0f;
    const glm::vec3 o(0.5f, 0.5f, 0.5f), d = glm::normalize(glm::vec3(x, 1.0f, z) - o);
    ++crossed;
    escaped += !tracer.occluded(o, d, 0.0f, kInf);
  }
  EXPECT_NEAR(double(escaped) / crossed, 0.5, 0.03);
}

// The sun through the checkerboard: a floor point under a hole gets E cos, one under a solid texel nothing.
TEST(Reference, SunReachesTheFloorOnlyUnderCutoutHoles) {
  Scene s;
  const uint32_t floor = test::addMaterial(s, glm::vec3(0.0f));
  const uint32_t leaves = test::addMaterial(s, glm::vec3(0.0f));
  test::addGround(s, 0.0f, 10.0f, floor);
  addCheckerQuad(s, leaves);
  Light l;
  l.type = LightType::kDirectional;
  l.direction = {0, -1, 0};
  l.intensity = glm::vec3(500.0f);
  s.lights = {l};
  SceneTracer tracer(s);
  for (const glm::dvec3& x : {glm::dvec3(0.125, 0, 0.125), glm::dvec3(0.375, 0, 0.125),
                              glm::dvec3(0.625, 0, 0.875), glm::dvec3(0.875, 0, 0.875)}) {
    const ReferenceIrradiance r = referenceIrradiance(tracer, x, {0, 1, 0}, 8, 1, opts(1, kContentAll));
    EXPECT_EQ(r.irradiance.x, checkerHole(float(x.x), float(x.z)) ? 500.0f : 0.0f) << x.x << ", " << x.z;
  }
}

// Geometric tests count only opaque surfaces: a closed glass crate encloses nothing, the same crate opaque
// does; surface points are never drawn in cutout holes.
TEST(InsideGeometry, GlassCrateEnclosesNothing) {
  for (float t : {0.0f, 0.5f}) {
    Scene s;
    const uint32_t m = addGlass(s, glm::vec3(0.5f), t);
    test::addBox(s, {-1, -1, -1}, {1, 1, 1}, false, m, 3);
    SceneTracer tracer(s);
    const std::vector<uint8_t> inside = probesInsideGeometry(tracer, {{0.1, 0.2, -0.3}}, 64, 0.25, 1);
    EXPECT_EQ(inside[0], t > 0.0f ? 0 : 1) << "transmission " << t;
  }
}

TEST(SurfacePoints, NeverLieInCutoutHoles) {
  Scene s;
  const uint32_t leaves = test::addMaterial(s, glm::vec3(0.5f));
  addCheckerQuad(s, leaves);
  s.skyRadiance = glm::vec3(1.0f);
  SceneTracer tracer(s);
  const std::vector<SurfacePoint> points = sampleSurfacePoints(tracer, 200, 3);
  EXPECT_GT(points.size(), 150u);
  for (const SurfacePoint& p : points) EXPECT_FALSE(checkerHole(float(p.position.x), float(p.position.z)));
}

// Inconsistent transparency from outside is an InputError, as any other bad scene.
TEST(Tracer, RejectsInconsistentTransparency) {
  auto base = [] {
    Scene s;
    const uint32_t m = test::addMaterial(s, glm::vec3(0.5f));
    addCheckerQuad(s, m);
    return s;
  };
  EXPECT_NO_THROW(SceneTracer{base()});
  Scene tooClear = base();
  tooClear.materials[0].transmission = 1.5f;
  EXPECT_THROW(SceneTracer{tooClear}, InputError);
  Scene badTexture = base();
  badTexture.materials[0].alphaTexture = 4;
  EXPECT_THROW(SceneTracer{badTexture}, InputError);
  Scene shortUvs = base();
  shortUvs.cutoutUvs.pop_back();
  EXPECT_THROW(SceneTracer{shortUvs}, InputError);
  Scene badTexels = base();
  badTexels.alphaTextures[0].alpha.pop_back();
  EXPECT_THROW(SceneTracer{badTexels}, InputError);
}

}  // namespace
}  // namespace tetraprobe
