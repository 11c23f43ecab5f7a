// The renderer's full mode (shadow-mapped direct light + the probes' indirect light) against closed forms on
// a hand-built scene, its debug views against the data they show, and the per-pass GPU timings.
//
// The scene (level local frame; the world origin is far away so the renderer must subtract it in double):
// a 6 x 6 m floor at y = 0 facing up, and a 1 x 1 m blocker at y = 1 over the floor's centre that faces
// DOWN, so the camera above (back faces culled) sees the floor through it while the shadow pass (both faces)
// still casts its shadow. A point light 2 m above the centre throws the blocker's umbra onto the floor's
// centre square |x|, |z| < 1 (similar triangles: 0.5 x 2 / 1).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <numbers>
#include <stdexcept>
#include <string>

#include <glm/geometric.hpp>
#include <glm/gtc/matrix_transform.hpp>

#include "missing_capability.h"
#include "tetraprobe/render/render.h"
#include "tetraprobe/runtime/face_blend.h"
#include "tetraprobe/runtime/occlusion.h"
#include "tetraprobe/runtime/query.h"
#include "tetraprobe/tetra/tetrahedralize.h"

namespace tetraprobe {
namespace {

const glm::dvec3 kOrigin(-700.0, 30.0, 1200.0);
const glm::vec3 kFloorAlbedo(0.5f, 0.4f, 0.3f);
constexpr float kPi = std::numbers::pi_v<float>;

// 5 x 3 x 5 probes, 2 m apart, jittered, over x, z in [-3.3, 4.7], y in [-1, 3.4]: no probe on the camera's
// axis (x = z = 0). `sh` false: every SH zero (no indirect light), so full = direct alone.
Level makeLevel(bool sh) {
  Level level;
  level.origin = kOrigin;
  std::vector<glm::dvec3> world;
  for (int z = 0; z < 5; ++z)
    for (int y = 0; y < 3; ++y)
      for (int x = 0; x < 5; ++x) {
        const glm::dvec3 local(-3.3 + 2.0 * x + 0.05 * std::sin(1.3 * x + 2.1 * y + 0.7 * z), -1.0 + 2.2 * y,
                               -3.1 + 2.0 * z + 0.06 * std::cos(0.9 * x + 1.7 * y));
        world.push_back(kOrigin + local);
        level.probes.push_back(glm::vec3(local));
        ShRgb s;
        if (sh) {
          s.c[0] = glm::vec3(1.0f + 0.05f * float(x), 0.8f + 0.04f * float(z), 0.6f);
          s.c[2] = glm::vec3(0.2f, 0.1f, 0.05f * float(y));
        }
        level.sh.push_back(s);
      }
  level.tets = buildTetRecords(world, tetrahedralizeDelaunay(world), kOrigin);
  return level;
}

void addQuad(RenderMesh& mesh, glm::vec3 a, glm::vec3 b, glm::vec3 c, glm::vec3 d, glm::vec3 albedo,
             glm::vec3 emission = glm::vec3(0.0f)) {
  const auto base = uint32_t(mesh.positions.size());
  for (glm::vec3 p : {a, b, c, d}) mesh.positions.push_back(glm::vec3(glm::dvec3(p) + kOrigin));
  mesh.triangles.push_back({base, base + 1, base + 2});
  mesh.triangles.push_back({base, base + 2, base + 3});
  for (int i = 0; i < 2; ++i) {
    mesh.triangleAlbedo.push_back(albedo);
    mesh.triangleEmission.push_back(emission);
  }
}

RenderMesh makeMesh(glm::vec3 floorEmission = glm::vec3(0.0f)) {
  RenderMesh m;
  // Counter-clockwise seen from above: normal +y.
  addQuad(m, {-3, 0, 3}, {3, 0, 3}, {3, 0, -3}, {-3, 0, -3}, kFloorAlbedo, floorEmission);
  // Counter-clockwise seen from below: normal -y (culled from the camera above, casts shadows).
  addQuad(m, {-0.5f, 1, -0.5f}, {0.5f, 1, -0.5f}, {0.5f, 1, 0.5f}, {-0.5f, 1, 0.5f}, glm::vec3(0.7f));
  return m;
}

// Straight down from 5 m above the floor's centre; 60 degrees shows |x|, |z| < 2.89 of the floor. An odd
// size puts the image centre on a pixel centre.
RenderView makeView(RenderMode mode, int size = 97) {
  RenderView v;
  v.eye = glm::vec3(kOrigin + glm::dvec3(0, 5, 0));
  v.target = glm::vec3(kOrigin);
  v.up = glm::vec3(0, 0, -1);
  v.fovYDeg = 60;
  v.width = v.height = size;
  v.mode = mode;
  return v;
}

RenderLight pointLight() {
  RenderLight l;
  l.type = RenderLightType::kPoint;
  l.position = glm::vec3(kOrigin + glm::dvec3(0, 2, 0));
  l.intensity = glm::vec3(10.0f, 8.0f, 6.0f);
  return l;
}

bool render(const RenderMesh& mesh, const Level& level, const RenderView& view, const RenderOptions& options,
            RenderResult& out, std::string& skip) {
  try {
    const ProbeQuery query(level);
    out = renderLevel(mesh, level, query, view, options);
    return true;
  } catch (const std::runtime_error& e) {
    const std::string what = e.what();
    if (!test::isNoVulkan(what)) throw;
    skip = what;
    return false;
  }
}

#define RENDER_OR_SKIP(mesh, level, view, options, out)                                  \
  do {                                                                                   \
    std::string skip_;                                                                   \
    if (!render(mesh, level, view, options, out, skip_)) TETRAPROBE_SKIP_MISSING(skip_); \
  } while (0)

glm::vec3 px3(const Image& im, size_t i) {
  return {im.rgba[4 * i], im.rgba[4 * i + 1], im.rgba[4 * i + 2]};
}

double relError(glm::vec3 got, glm::vec3 want) {
  double worst = 0.0;
  for (int c = 0; c < 3; ++c)
    worst = std::max(worst, std::abs(double(got[c]) - want[c]) / std::max(std::abs(double(want[c])), 1e-9));
  return worst;
}

// Outgoing radiance from a point light at `light` (local) reaching floor point p unshadowed:
// albedo / pi x I cos(theta) / r^2.
glm::vec3 pointDirect(glm::vec3 p, glm::vec3 light, glm::vec3 intensity) {
  const glm::vec3 d = light - p;
  const float r2 = glm::dot(d, d);
  const float cosTheta = d.y / std::sqrt(r2);
  return kFloorAlbedo / kPi * intensity * (cosTheta / r2);
}

// Full mode with no indirect light: every floor pixel outside the umbra and its 0.1 m margin (about 25
// shadow-map texels; the normal offset and PCF reach 3) gets exactly the closed form, within 1e-4 relative
// (float rounding of the G-buffer position and the sums; any acne, cube-seam leak or wrong falloff is far
// larger). At least a thousand pixels are checked.
TEST(FullRender, LitPixelMatchesInverseSquareCosine) {
  RenderOptions options;
  options.lights = {pointLight()};
  RenderResult r;
  RENDER_OR_SKIP(makeMesh(), makeLevel(false), makeView(RenderMode::kFull), options, r);
  int checked = 0, bad = 0;
  double worst = 0.0;
  for (size_t i = 0; i < r.color.rgba.size() / 4; ++i) {
    if (r.position.rgba[4 * i + 3] == 0.0f) continue;
    const glm::vec3 p = px3(r.position, i);
    ASSERT_NEAR(p.y, 0.0f, 1e-5f) << "only the floor is visible (the blocker faces away)";
    if (std::max(std::abs(p.x), std::abs(p.z)) < 1.1f) continue;
    const double e = relError(px3(r.color, i), pointDirect(p, {0, 2, 0}, options.lights[0].intensity));
    worst = std::max(worst, e);
    ++checked;
    if (e > 1e-4 && bad++ < 5)
      ADD_FAILURE() << "pixel " << i << " at (" << p.x << ", " << p.z << "): off by " << e;
  }
  std::printf("lit floor pixels: %d, worst relative error %.2e\n", checked, worst);
  EXPECT_GT(checked, 1000);
}

// The blocker's umbra (|x|, |z| < 1, checked inside 0.9) gets no direct light at all: the shadow map works,
// and for a back face too.
TEST(FullRender, PixelInShadowGetsNoDirectLight) {
  RenderOptions options;
  options.lights = {pointLight()};
  RenderResult r;
  RENDER_OR_SKIP(makeMesh(), makeLevel(false), makeView(RenderMode::kFull), options, r);
  int shadowed = 0;
  for (size_t i = 0; i < r.color.rgba.size() / 4; ++i) {
    const glm::vec3 p = px3(r.position, i);
    if (r.position.rgba[4 * i + 3] == 0.0f || std::max(std::abs(p.x), std::abs(p.z)) > 0.9f) continue;
    ++shadowed;
    ASSERT_EQ(px3(r.color, i), glm::vec3(0.0f)) << "pixel at (" << p.x << ", " << p.z << ")";
  }
  EXPECT_GT(shadowed, 200);
}

// Without lights or emission, full is exactly the indirect mode (albedo x E / pi from the probes), which is
// the irradiance mode times albedo / pi.
TEST(FullRender, WithoutLightsEqualsIndirectTimesAlbedo) {
  const Level level = makeLevel(true);
  RenderResult full, indirect, irradiance;
  RENDER_OR_SKIP(makeMesh(), level, makeView(RenderMode::kFull), RenderOptions{}, full);
  RENDER_OR_SKIP(makeMesh(), level, makeView(RenderMode::kIndirect), RenderOptions{}, indirect);
  RENDER_OR_SKIP(makeMesh(), level, makeView(RenderMode::kIrradiance), RenderOptions{}, irradiance);
  int geometry = 0;
  for (size_t i = 0; i < full.color.rgba.size() / 4; ++i) {
    ASSERT_EQ(px3(full.color, i), px3(indirect.color, i)) << "pixel " << i;
    if (full.position.rgba[4 * i + 3] == 0.0f) continue;
    ++geometry;
    EXPECT_LT(relError(px3(full.color, i), kFloorAlbedo * px3(irradiance.color, i) / kPi), 1e-6) << i;
  }
  EXPECT_EQ(geometry, 97 * 97) << "the floor fills the view";
}

// With both, full = direct + indirect: the full render equals the indirect render plus the full render of
// the same light over probes holding nothing (within float rounding of one addition).
TEST(FullRender, IsDirectPlusIndirect) {
  RenderOptions options;
  options.lights = {pointLight()};
  RenderResult both, direct, indirect;
  RENDER_OR_SKIP(makeMesh(), makeLevel(true), makeView(RenderMode::kFull), options, both);
  RENDER_OR_SKIP(makeMesh(), makeLevel(false), makeView(RenderMode::kFull), options, direct);
  RENDER_OR_SKIP(makeMesh(), makeLevel(true), makeView(RenderMode::kIndirect), options, indirect);
  for (size_t i = 0; i < both.color.rgba.size() / 4; ++i)
    ASSERT_LT(relError(px3(both.color, i), px3(direct.color, i) + px3(indirect.color, i)), 1e-6) << i;
}

// Emitters show their emitted radiance on top of the rest.
TEST(FullRender, AddsEmission) {
  const glm::vec3 emission(1.0f, 2.0f, 3.0f);
  RenderResult r;
  RENDER_OR_SKIP(makeMesh(emission), makeLevel(false), makeView(RenderMode::kFull), RenderOptions{}, r);
  EXPECT_EQ(px3(r.color, 48 * 97 + 48), emission);
}

// A spot light away from the blocker's shadow: full intensity inside the inner cone, the bake's smoothstep
// in the cosine between the cones, nothing outside the outer cone. A sun: E cos(theta) everywhere but its
// own shadow of the blocker (offset along the sun's direction).
TEST(FullRender, SpotAndSunMatchClosedForms) {
  RenderLight spot;
  spot.type = RenderLightType::kSpot;
  spot.position = glm::vec3(kOrigin + glm::dvec3(1.5, 2, 1.5));
  spot.direction = glm::vec3(0, -1, 0);
  spot.intensity = glm::vec3(20.0f);
  spot.innerConeRad = glm::radians(20.0f);
  spot.outerConeRad = glm::radians(30.0f);
  RenderOptions options;
  options.lights = {spot};
  RenderResult r;
  RENDER_OR_SKIP(makeMesh(), makeLevel(false), makeView(RenderMode::kFull), options, r);
  int inner = 0, between = 0, outer = 0;
  for (size_t i = 0; i < r.color.rgba.size() / 4; ++i) {
    const glm::vec3 p = px3(r.position, i);
    const glm::vec3 d = glm::vec3(1.5f, 2.0f, 1.5f) - p;
    const float c = d.y / glm::length(d);  // cos of the angle from the spot's axis
    const float c0 = std::cos(spot.outerConeRad), c1 = std::cos(spot.innerConeRad);
    const float t = std::clamp((c - c0) / (c1 - c0), 0.0f, 1.0f);
    const glm::vec3 want = pointDirect(p, {1.5f, 2.0f, 1.5f}, spot.intensity) * (t * t * (3.0f - 2.0f * t));
    const glm::vec3 got = px3(r.color, i);
    if (c > c1) {
      ++inner;
      ASSERT_LT(relError(got, want), 1e-4) << i;
    } else if (c < c0) {
      ++outer;
      ASSERT_EQ(got, glm::vec3(0.0f)) << i;
    } else {
      ++between;
      ASSERT_LT(glm::length(got - want), 1e-4f * glm::length(pointDirect(p, {1.5f, 2, 1.5f}, spot.intensity)))
          << i;
    }
  }
  EXPECT_GT(inner, 100);
  EXPECT_GT(between, 100);
  EXPECT_GT(outer, 100);

  RenderLight sun;
  sun.type = RenderLightType::kDirectional;
  sun.direction = glm::normalize(glm::vec3(0.3f, -1.0f, 0.2f));
  sun.intensity = glm::vec3(3.0f, 2.0f, 1.0f);
  options.lights = {sun};
  RENDER_OR_SKIP(makeMesh(), makeLevel(false), makeView(RenderMode::kFull), options, r);
  // The blocker at y = 1 shadows the floor square around (0.3, 0.2) / 1 of half-width 0.5.
  int lit = 0, shadowed = 0;
  for (size_t i = 0; i < r.color.rgba.size() / 4; ++i) {
    const glm::vec3 p = px3(r.position, i);
    const float dx = std::abs(p.x - 0.3f), dz = std::abs(p.z - 0.2f);
    if (std::max(dx, dz) > 0.6f) {
      ++lit;
      ASSERT_LT(relError(px3(r.color, i), kFloorAlbedo / kPi * sun.intensity * -sun.direction.y), 1e-4) << i;
    } else if (std::max(dx, dz) < 0.4f) {
      ++shadowed;
      ASSERT_EQ(px3(r.color, i), glm::vec3(0.0f)) << i;
    }
  }
  EXPECT_GT(lit, 1000);
  EXPECT_GT(shadowed, 100);
}

// The pixel (column, row) whose centre is nearest to local point p's projection in `view`.
glm::ivec2 projectToPixel(const RenderView& view, glm::vec3 p) {
  const glm::mat4 v = glm::lookAtRH(glm::vec3(glm::dvec3(view.eye) - kOrigin),
                                    glm::vec3(glm::dvec3(view.target) - kOrigin), view.up);
  const glm::mat4 proj = glm::perspectiveRH_ZO(glm::radians(view.fovYDeg), 1.0f, 0.1f, 100.0f);
  const glm::vec4 clip = proj * v * glm::vec4(p, 1.0f);
  const float x = (clip.x / clip.w * 0.5f + 0.5f) * float(view.width);
  const float y = (-clip.y / clip.w * 0.5f + 0.5f) * float(view.height);  // row 0 = top
  return {int(std::floor(x)), int(std::floor(y))};
}

// A probe in front of the floor is a dot in its kind's colour; one under the floor a smaller dot at 35 %;
// a level without recorded kinds draws white dots; away from dots the floor is grey.
TEST(DebugViews, ProbeDotsHaveTheirKindColour) {
  Level level = makeLevel(false);
  level.probeKinds.assign(level.probes.size(), LevelProbeKind::kShell);
  const glm::vec3 visible(0.0f, 0.5f, 0.0f), hidden(0.8f, -0.5f, 0.8f);
  level.probes.push_back(visible);
  level.sh.emplace_back();
  level.probeKinds.push_back(LevelProbeKind::kSurface);
  level.probes.push_back(hidden);
  level.sh.emplace_back();
  level.probeKinds.push_back(LevelProbeKind::kFiller);
  const RenderView view = makeView(RenderMode::kProbes);
  RenderResult r;
  RENDER_OR_SKIP(makeMesh(), level, view, RenderOptions{}, r);
  auto at = [&](glm::vec3 p) {
    const glm::ivec2 px = projectToPixel(view, p);
    return px3(r.color, size_t(px.y) * size_t(view.width) + size_t(px.x));
  };
  EXPECT_EQ(projectToPixel(view, visible), glm::ivec2(48, 48));
  EXPECT_EQ(at(visible), glm::vec3(0.1f, 0.85f, 0.1f)) << "surface: green";
  const glm::vec3 dim = at(hidden);
  EXPECT_NEAR(dim.r, 0.35f * 0.1f, 1e-6f) << "filler: blue, hidden: 35 %";
  EXPECT_NEAR(dim.g, 0.35f * 0.25f, 1e-6f);
  EXPECT_NEAR(dim.b, 0.35f * 1.0f, 1e-6f);
  const glm::vec3 floor = at({-1.2f, 0.0f, 1.1f});
  EXPECT_EQ(floor.r, floor.g);
  EXPECT_EQ(floor.g, floor.b);
  EXPECT_LT(floor.r, 0.4f);

  level.probeKinds.clear();
  RENDER_OR_SKIP(makeMesh(), level, view, RenderOptions{}, r);
  EXPECT_EQ(at(visible), glm::vec3(1.0f)) << "no kinds recorded: white";
}

// Each pixel's colour is its tet's (as the CPU locates the pixel's point): pixels of one tet share a hue
// (the colour up to the facing-ratio shading), and tets differ; pixels on a tet face are dark.
TEST(DebugViews, TetColourFollowsTheTetHoldingThePixel) {
  const Level level = makeLevel(false);
  const ProbeQuery query(level);
  RenderResult r;
  RENDER_OR_SKIP(makeMesh(), level, makeView(RenderMode::kTets, 161), RenderOptions{}, r);
  std::map<int32_t, glm::vec3> hue;  // tet -> colour / its largest channel
  int interior = 0, mismatched = 0, dark = 0, pixels = 0;
  for (size_t i = 0; i < r.color.rgba.size() / 4; ++i) {
    if (r.position.rgba[4 * i + 3] == 0.0f) continue;
    ++pixels;
    const glm::vec3 c = px3(r.color, i);
    const float m = std::max(c.r, std::max(c.g, c.b));
    const Location loc = query.locate(level.origin + glm::dvec3(px3(r.position, i)));
    ASSERT_GE(loc.tet, 0);
    ASSERT_LT(loc.outerCell, 0) << "the floor lies inside the hull";
    if (std::min(std::min(loc.weights.x, loc.weights.y), std::min(loc.weights.z, loc.weights.w)) < 0.05f) {
      dark += m < 0.15f;
      continue;  // near a face: may be a line, or the neighbour on a float tie
    }
    ++interior;
    const auto [it, fresh] = hue.emplace(loc.tet, c / m);
    if (!fresh && glm::length(it->second - c / m) > 1e-3f) ++mismatched;
  }
  EXPECT_EQ(mismatched, 0) << "of " << interior << " interior pixels";
  EXPECT_GE(hue.size(), 8u);
  int distinct = 0;
  for (auto a = hue.begin(); a != hue.end(); ++a)
    for (auto b = std::next(a); b != hue.end(); ++b) distinct += glm::length(a->second - b->second) > 1e-3f;
  const size_t pairs = hue.size() * (hue.size() - 1) / 2;
  EXPECT_GE(double(distinct), 0.95 * double(pairs)) << "hashed colours of different tets differ";
  EXPECT_GT(dark, pixels / 200) << "tet faces show as dark lines";
}

// Occlusion: every tet gets a record by t % 4: none; one plane with every probe visible on both sides;
// shadow maps that meet nothing; one plane with no probe visible on either side. Each pixel shows its tet's
// kind: grey, blue, green; the last kind falls back (red) where its neighbours see nothing either (the face
// blend takes their sight otherwise), so it is checked on a level where every tet sees nothing.
TEST(DebugViews, OcclusionShowsKindAndFallback) {
  Level level = makeLevel(true);
  LevelOcclusion& occ = level.occlusion;
  for (size_t t = 0; t < level.tets.size(); ++t) {
    const size_t k = t % 4;
    if (k == 0) {
      occ.tets.push_back(TetOcclusion{});
    } else if (k == 1 || k == 3) {
      occ.tets.push_back(
          makeTetOcclusion(kOcclusionPlanes, 1, uint32_t(occ.planes.size()), k == 1 ? 0xFFu : 0x00u));
      occ.planes.push_back(makeOcclusionPlane(1.0, -1.0, 0.0, 0.0));
    } else {
      occ.tets.push_back(makeTetOcclusion(kOcclusionShadowMaps, 0,
                                          uint32_t(occ.shadowMaps.size() / kShadowMapBlockBytes), 0));
      occ.shadowMaps.insert(occ.shadowMaps.end(), kShadowMapBlockBytes, kShadowMapNoHit);
    }
  }
  ASSERT_TRUE(validateLevel(level)) << validateLevel(level).message;
  const ProbeQuery query(level);
  RenderResult r;
  RENDER_OR_SKIP(makeMesh(), level, makeView(RenderMode::kOcclusion, 161), RenderOptions{}, r);
  int seen[4] = {}, wrong = 0;
  for (size_t i = 0; i < r.color.rgba.size() / 4; ++i) {
    if (r.position.rgba[4 * i + 3] == 0.0f) continue;
    const Location loc = query.locate(level.origin + glm::dvec3(px3(r.position, i)));
    const float wMin =
        std::min(std::min(loc.weights.x, loc.weights.y), std::min(loc.weights.z, loc.weights.w));
    if (wMin < 1e-3f) continue;  // a float tie may name the neighbour
    const glm::vec3 c = px3(r.color, i);
    const size_t k = size_t(loc.tet) % 4;
    // A tet that sees nothing takes its neighbours' sight across its faces (face_blend.h, a band of
    // kFaceBlendFallbackBand, the whole tet): checked below with every tet seeing nothing.
    if (k == 3) continue;
    const bool ok = k == 0   ? c.r == c.g && c.g == c.b
                    : k == 1 ? c.b > 2.0f * c.r && c.b > 2.0f * c.g
                    : k == 2 ? c.g > 3.0f * c.r && c.g > 3.0f * c.b
                             : c.r > 5.0f * c.g && c.r > 5.0f * c.b;
    ++seen[k];
    if (!ok && wrong++ < 5)
      ADD_FAILURE() << "pixel " << i << " in tet " << loc.tet << " (kind " << k << "): colour " << c.r << " "
                    << c.g << " " << c.b;
  }
  for (int k = 0; k < 3; ++k) EXPECT_GT(seen[k], 50) << "kind " << k;
  // Every tet with one plane and no probe visible on either side: no neighbour sees anything either, so
  // every pixel falls back and shows red.
  occ.shadowMaps.clear();
  occ.planes.clear();
  for (size_t t = 0; t < level.tets.size(); ++t) {
    occ.tets[t] = makeTetOcclusion(kOcclusionPlanes, 1, uint32_t(t), 0x00u);
    occ.planes.push_back(makeOcclusionPlane(1.0, -1.0, 0.0, 0.0));
  }
  ASSERT_TRUE(validateLevel(level)) << validateLevel(level).message;
  RENDER_OR_SKIP(makeMesh(), level, makeView(RenderMode::kOcclusion, 161), RenderOptions{}, r);
  int red = 0, other = 0;
  for (size_t i = 0; i < r.color.rgba.size() / 4; ++i) {
    if (r.position.rgba[4 * i + 3] == 0.0f) continue;
    const glm::vec3 c = px3(r.color, i);
    (c.r > 5.0f * c.g && c.r > 5.0f * c.b ? red : other)++;
  }
  EXPECT_GT(red, 1000);
  EXPECT_EQ(other, 0);
}

// Every pass of the mode has a GPU time, the median over the timed frames, in the order the frame runs them.
TEST(RenderTimings, EveryPassOfTheModeHasAMedianTime) {
  RenderOptions options;
  options.lights = {pointLight()};
  options.warmupFrames = 1;
  options.timedFrames = 3;
  RenderResult r;
  RENDER_OR_SKIP(makeMesh(), makeLevel(true), makeView(RenderMode::kFull), options, r);
  if (r.timings.passes.empty()) TETRAPROBE_SKIP_MISSING("the queue has no timestamps");
  std::vector<std::string> names;
  for (const PassTiming& p : r.timings.passes) {
    names.push_back(p.name);
    EXPECT_GE(p.ms, 0.0) << p.name;
  }
  EXPECT_EQ(names,
            (std::vector<std::string>{"shadow_maps", "gbuffer", "lighting_warmup", "lighting", "direct"}));
  EXPECT_EQ(r.timings.timedFrames, 3);
  EXPECT_EQ(r.timings.lightingMs, r.timings.passes[3].ms);

  options.lights.clear();
  RENDER_OR_SKIP(makeMesh(), makeLevel(true), makeView(RenderMode::kProbes), options, r);
  names.clear();
  for (const PassTiming& p : r.timings.passes) names.push_back(p.name);
  EXPECT_EQ(names, (std::vector<std::string>{"gbuffer", "surface", "probe_dots"}));
}

}  // namespace
}  // namespace tetraprobe
