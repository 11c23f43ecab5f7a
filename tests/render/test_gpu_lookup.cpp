// The GPU lookup (shaders/tetraprobe.glsl via the headless renderer) against the CPU query, and the
// renderer's own invariants: lighting modes, background, back-face culling.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <numbers>
#include <random>
#include <stdexcept>
#include <string>

#include <glm/common.hpp>

#include "tetraprobe/render/render.h"
#include "tetraprobe/runtime/occlusion.h"
#include "tetraprobe/runtime/query.h"
#include "tetraprobe/tetra/tetrahedralize.h"

namespace tetraprobe {
namespace {

// Far from the world origin on purpose: the renderer must subtract it in double.
const glm::dvec3 kOrigin(1000.0, -20.0, 500.0);

// 4x3x4 probes on a 1 m grid over local [0,3]x[0,2]x[0,3], slightly jittered (no cospherical ties), with
// distinct SH per probe: a linear field in L00 plus position-dependent L1 and L2 terms. E stays positive
// (L00 dominates), so a relative error is meaningful everywhere.
Level makeLevel() {
  Level level;
  level.origin = kOrigin;
  std::vector<glm::dvec3> world;
  for (int z = 0; z < 4; ++z)
    for (int y = 0; y < 3; ++y)
      for (int x = 0; x < 4; ++x) {
        const glm::dvec3 local(x + 0.07 * std::sin(1.3 * x + 2.1 * y + 0.7 * z),
                               y + 0.05 * std::cos(0.9 * x + 1.7 * z),
                               z + 0.06 * std::sin(2.3 * y + 0.4 * x));
        world.push_back(kOrigin + local);
        level.probes.push_back(glm::vec3(local));
        ShRgb sh;
        const glm::vec3 p(local);
        sh.c[0] = glm::vec3(2.0f + 0.4f * p.x, 1.5f + 0.3f * p.y, 1.0f + 0.2f * p.z);
        sh.c[1] = glm::vec3(0.2f * p.y, -0.1f, 0.05f * p.x);
        sh.c[2] = glm::vec3(-0.15f, 0.1f * p.z, 0.2f);
        sh.c[3] = glm::vec3(0.1f * p.x, 0.05f, -0.1f * p.z);
        for (int i = 4; i < 9; ++i)
          sh.c[i] = glm::vec3(0.03f * float(i - 6) + 0.01f * p.x, 0.02f * p.y, -0.02f * float(i - 5));
        level.sh.push_back(sh);
      }
  const TetMesh mesh = tetrahedralizeDelaunay(world);
  level.tets = buildTetRecords(world, mesh, kOrigin);
  return level;
}

// Synthetic occlusion on every tet of `level` (no geometry needed): tets alternate 1..3 random planes, each
// cell seeing a random non-empty probe set, and random shadow maps, so the GPU mirror of
// evaluateTetOcclusion, the normal bias and applyOcclusion is exercised on every pixel inside the hull.
LevelOcclusion syntheticOcclusion(const Level& level) {
  LevelOcclusion occ;
  std::mt19937 rng(11);
  std::uniform_real_distribution<float> u(-1.0f, 1.0f);
  for (size_t t = 0; t < level.tets.size(); ++t) {
    if (t % 4 != 3) {
      const uint32_t count = uint32_t(t % 4) + 1;
      uint32_t cells = 0;
      for (uint32_t c = 0; c < (1u << count); ++c) cells |= (1u + uint32_t(rng()) % 15u) << (4 * c);
      occ.tets.push_back(makeTetOcclusion(kOcclusionPlanes, count, uint32_t(occ.planes.size()), cells));
      for (uint32_t k = 0; k < count; ++k) {
        OcclusionPlane p;
        float m = 0.0f;
        for (float& c : p.c) m = std::max(m, std::abs(c = u(rng)));
        for (float& c : p.c) c /= m;
        occ.planes.push_back(p);
      }
    } else {
      occ.tets.push_back(makeTetOcclusion(kOcclusionShadowMaps, 0,
                                          uint32_t(occ.shadowMaps.size() / kShadowMapBlockBytes), 0));
      for (int b = 0; b < kShadowMapBlockBytes; ++b)
        occ.shadowMaps.push_back(b % 16 == 15 ? kShadowMapNoHit : uint8_t(60 + rng() % 196));
    }
  }
  return occ;
}

void addQuad(RenderMesh& mesh, glm::vec3 a, glm::vec3 b, glm::vec3 c, glm::vec3 d, glm::vec3 albedo) {
  // a b c d counter-clockwise seen from the front.
  const auto base = uint32_t(mesh.positions.size());
  for (glm::vec3 p : {a, b, c, d}) mesh.positions.push_back(glm::vec3(kOrigin) + p);
  mesh.triangles.push_back({base, base + 1, base + 2});
  mesh.triangles.push_back({base, base + 2, base + 3});
  mesh.triangleAlbedo.push_back(albedo);
  mesh.triangleAlbedo.push_back(albedo);
}

// Local coordinates written relative to the origin; the mesh stores world positions (float: the origin is
// exactly representable, and so are these small offsets' sums to within float rounding).
RenderMesh makeMesh() {
  RenderMesh m;
  // Inside the hull: a floor at y = 0.5 facing up, a tilted panel, a wall facing +z.
  addQuad(m, {0.3f, 0.5f, 2.7f}, {2.7f, 0.5f, 2.7f}, {2.7f, 0.5f, 0.3f}, {0.3f, 0.5f, 0.3f},
          {0.8f, 0.6f, 0.4f});
  addQuad(m, {0.4f, 0.9f, 1.6f}, {1.6f, 0.9f, 1.6f}, {1.6f, 1.7f, 0.6f}, {0.4f, 1.7f, 0.6f},
          {0.3f, 0.7f, 0.9f});
  addQuad(m, {1.8f, 0.6f, 1.2f}, {2.6f, 0.6f, 1.2f}, {2.6f, 1.8f, 1.2f}, {1.8f, 1.8f, 1.2f},
          {0.9f, 0.9f, 0.9f});
  // Outside the hull: a slab above it, a wall beyond -x, a floor in front of +z.
  addQuad(m, {0.5f, 2.6f, 2.5f}, {2.0f, 2.6f, 2.5f}, {2.0f, 2.6f, 1.0f}, {0.5f, 2.6f, 1.0f},
          {0.5f, 0.5f, 0.5f});
  addQuad(m, {-0.8f, 0.0f, 3.2f}, {-0.8f, 0.0f, 0.2f}, {-0.8f, 2.4f, 0.2f}, {-0.8f, 2.4f, 3.2f},
          {0.7f, 0.3f, 0.3f});
  addQuad(m, {0.0f, -0.4f, 4.5f}, {3.5f, -0.4f, 4.5f}, {3.5f, -0.4f, 3.3f}, {0.0f, -0.4f, 3.3f},
          {0.2f, 0.8f, 0.2f});
  return m;
}

RenderView makeView(RenderMode mode, int width = 320, int height = 180) {
  RenderView v;
  v.eye = glm::vec3(kOrigin + glm::dvec3(5.5, 5.0, 8.0));
  v.target = glm::vec3(kOrigin + glm::dvec3(1.2, 0.8, 1.6));
  v.fovYDeg = 55;
  v.width = width;
  v.height = height;
  v.mode = mode;
  return v;
}

// Renders, or returns false after GTEST_SKIP-worthy failure (no Vulkan device).
bool render(const RenderMesh& mesh, const Level& level, const ProbeQuery& query, const RenderView& view,
            RenderResult& out, std::string& skip) {
  try {
    out = renderLevel(mesh, level, query, view);
    return true;
  } catch (const std::runtime_error& e) {
    const std::string what = e.what();
    if (what.find("no Vulkan") != std::string::npos) {
      skip = what;
      return false;
    }
    throw;
  }
}

#define RENDER_OR_SKIP(mesh, level, query, view, out)                         \
  do {                                                                        \
    std::string skip_;                                                        \
    if (!render(mesh, level, query, view, out, skip_)) GTEST_SKIP() << skip_; \
  } while (0)

glm::vec3 px3(const Image& im, size_t i) {
  return {im.rgba[4 * i], im.rgba[4 * i + 1], im.rgba[4 * i + 2]};
}

// Every geometry pixel's GPU irradiance equals ProbeQuery::irradiance at the G-buffer's position and normal,
// inside and outside the probe hull, with no exception. Tolerance: relative 1e-4 per channel. The CPU walks
// and weighs in double on the exact local point, the GPU in float (the rows are float on both sides) and they
// sum in different orders, so they differ by a few float ulps (~1e-6 relative); 1e-4 leaves room for SH sums
// with some cancellation while catching any wrong tet, cell, weight, constant, coefficient order or band
// factor. Outside the hull both continue across the outer cells, whose answer does not depend on the hull
// face a walk leaves by, so a float/double tie in the walk can no longer change the answer there.
//
// With occlusion (synthetic data on every tet), the GPU mirrors evaluateTetOcclusion + applyOcclusion + the
// normal bias operation for operation in float (`precise`), and the same 1e-4 holds with no exception (worst
// seen 1.3e-5 on lavapipe).
void expectGpuMatchesCpu(float cellSize, bool occlusion = false) {
  Level level = makeLevel();
  if (occlusion) level.occlusion = syntheticOcclusion(level);
  const ProbeQuery query(level, cellSize);
  const RenderView view = makeView(RenderMode::kIrradiance, 960, 540);
  RenderResult r;
  RENDER_OR_SKIP(makeMesh(), level, query, view, r);
  std::printf("render %dx%d: total %.1f ms, G-buffer %.2f ms, lighting warm-up %.2f ms, lighting %.2f ms\n",
              view.width, view.height, r.timings.totalMs, r.timings.gbufferMs, r.timings.lightingWarmupMs,
              r.timings.lightingMs);

  int inside = 0, outside = 0, bad = 0, occluded = 0;
  double worst = 0.0;
  for (size_t i = 0; i < size_t(view.width) * view.height; ++i) {
    if (r.position.rgba[4 * i + 3] == 0.0f) continue;
    const glm::dvec3 local(px3(r.position, i));
    const glm::dvec3 world = level.origin + local;
    const glm::vec3 n = px3(r.normal, i);
    const glm::vec3 cpu = query.irradiance(world, n);
    const glm::vec3 gpu = px3(r.color, i);
    const Location loc = query.locate(world);
    (loc.inside ? inside : outside)++;
    if (occlusion && loc.outerCell < 0) {
      const glm::vec4 vis = occlusionVisibility(level, level.occlusion, loc.tet, glm::vec3(local), n);
      occluded += vis != glm::vec4(1.0f);
    }
    if (!loc.inside) {
      EXPECT_GE(loc.outerCell, 0) << "outside answers come from an outer cell";
    }
    double rel = 0.0;
    for (int c = 0; c < 3; ++c)
      rel = std::max(rel, std::abs(double(gpu[c]) - cpu[c]) / std::max(std::abs(double(cpu[c])), 1e-6));
    worst = std::max(worst, rel);
    if (rel >= 1e-4 && bad++ < 10)
      ADD_FAILURE() << "pixel (" << i % size_t(view.width) << ", " << i / size_t(view.width) << "): gpu ("
                    << gpu.x << ", " << gpu.y << ", " << gpu.z << ") cpu (" << cpu.x << ", " << cpu.y << ", "
                    << cpu.z << ") at local (" << local.x << ", " << local.y << ", " << local.z
                    << ") normal (" << n.x << ", " << n.y << ", " << n.z << "), inside " << loc.inside
                    << ", outer cell " << loc.outerCell;
  }
  std::printf("compared %d pixels inside the hull, %d outside; worst relative error %.3g\n", inside, outside,
              worst);
  if (occlusion) {
    std::printf("occlusion: %d pixels with an occluded probe, %d beyond 1e-4\n", occluded, bad);
    EXPECT_GT(occluded, 1000) << "the synthetic occlusion must hide probes on plenty of pixels";
  }
  EXPECT_EQ(bad, 0);
  EXPECT_GT(inside, 1000) << "the scene must show plenty of geometry inside the probe hull";
  EXPECT_GT(outside, 1000) << "the scene must show plenty of geometry outside the probe hull";
}

TEST(GpuLookup, MatchesCpuQueryPerPixel) {
  expectGpuMatchesCpu(16.0f);  // the default cell grid: one or two cells, a BSP in each
}

// The level stores occlusion: GPU == CPU per pixel with it applied (binding + 5).
TEST(GpuLookup, MatchesCpuQueryPerPixelWithOcclusion) {
  expectGpuMatchesCpu(16.0f, true);
}

// Half-metre cells: hundreds of hash slots and cell borders crossing the view, absent cells outside the hull.
TEST(GpuLookup, MatchesCpuQueryPerPixelWithSmallCells) {
  expectGpuMatchesCpu(0.5f);
}

// Mode 1 is mode 0 times albedo / pi, pixel for pixel (same lookup; one multiply and one divide apart).
TEST(Render, IndirectIsAlbedoTimesIrradianceOverPi) {
  const Level level = makeLevel();
  const ProbeQuery query(level);
  const RenderMesh mesh = makeMesh();
  RenderResult e, l;
  RENDER_OR_SKIP(mesh, level, query, makeView(RenderMode::kIrradiance), e);
  RENDER_OR_SKIP(mesh, level, query, makeView(RenderMode::kIndirect), l);
  int geometry = 0;
  for (size_t i = 0; i < e.color.rgba.size() / 4; ++i) {
    if (e.position.rgba[4 * i + 3] == 0.0f) continue;
    ++geometry;
    const glm::vec3 expect = px3(e.albedo, i) * px3(e.color, i) / std::numbers::pi_v<float>;
    const glm::vec3 got = px3(l.color, i);
    for (int c = 0; c < 3; ++c)
      ASSERT_NEAR(got[c], expect[c], 1e-6f * std::abs(expect[c]) + 1e-12f)
          << "pixel " << i << " channel " << c;
    ASSERT_EQ(l.color.rgba[4 * i + 3], 1.0f);
  }
  EXPECT_GT(geometry, 0);
}

// Pixels that no triangle covers are exactly 0 in every channel of the color and G-buffer images.
TEST(Render, BackgroundIsZero) {
  const Level level = makeLevel();
  const ProbeQuery query(level);
  RenderResult r;
  RENDER_OR_SKIP(makeMesh(), level, query, makeView(RenderMode::kIndirect), r);
  int background = 0;
  for (size_t i = 0; i < r.color.rgba.size() / 4; ++i) {
    if (r.position.rgba[4 * i + 3] != 0.0f) continue;
    ++background;
    for (int c = 0; c < 4; ++c) {
      ASSERT_EQ(r.color.rgba[4 * i + c], 0.0f) << "pixel " << i;
      ASSERT_EQ(r.normal.rgba[4 * i + c], 0.0f) << "pixel " << i;
      ASSERT_EQ(r.albedo.rgba[4 * i + c], 0.0f) << "pixel " << i;
    }
  }
  EXPECT_GT(background, 1000) << "the view must show some background";
}

// One quad seen from the front covers pixels; the same quad wound the other way (facing away) covers none.
// The sample scene's cut-away view from above relies on this (ceilings face down, into the rooms).
TEST(Render, BackFacesCulled) {
  const Level level = makeLevel();
  const ProbeQuery query(level);
  RenderView view = makeView(RenderMode::kIrradiance);
  view.eye = glm::vec3(kOrigin + glm::dvec3(1.5, 6.0, 1.6));  // above, looking down
  view.target = glm::vec3(kOrigin + glm::dvec3(1.5, 0.0, 1.5));
  RenderMesh up, down;
  addQuad(up, {0.5f, 1.0f, 2.5f}, {2.5f, 1.0f, 2.5f}, {2.5f, 1.0f, 0.5f}, {0.5f, 1.0f, 0.5f},
          glm::vec3(0.5f));
  addQuad(down, {0.5f, 1.0f, 0.5f}, {2.5f, 1.0f, 0.5f}, {2.5f, 1.0f, 2.5f}, {0.5f, 1.0f, 2.5f},
          glm::vec3(0.5f));
  RenderResult ru, rd;
  RENDER_OR_SKIP(up, level, query, view, ru);
  RENDER_OR_SKIP(down, level, query, view, rd);
  int covered = 0, culled = 0;
  for (size_t i = 0; i < ru.position.rgba.size() / 4; ++i) {
    if (ru.position.rgba[4 * i + 3] != 0.0f) {
      ++covered;
      EXPECT_NEAR(ru.normal.rgba[4 * i + 1], 1.0f, 1e-6f);  // facing the camera above
    }
    if (rd.position.rgba[4 * i + 3] != 0.0f) ++culled;
  }
  EXPECT_GT(covered, 1000);
  EXPECT_EQ(culled, 0);
}

// Row 0 is the top of the view: a quad in the upper half of the view lands in the upper rows.
TEST(Render, RowZeroIsTop) {
  const Level level = makeLevel();
  const ProbeQuery query(level);
  RenderView view = makeView(RenderMode::kIrradiance);
  view.eye = glm::vec3(kOrigin + glm::dvec3(1.5, 1.0, 8.0));
  view.target = glm::vec3(kOrigin + glm::dvec3(1.5, 1.0, 1.5));
  RenderMesh m;  // facing +z (the camera), above the view axis
  addQuad(m, {1.0f, 1.5f, 1.5f}, {2.0f, 1.5f, 1.5f}, {2.0f, 2.0f, 1.5f}, {1.0f, 2.0f, 1.5f}, glm::vec3(0.5f));
  RenderResult r;
  RENDER_OR_SKIP(m, level, query, view, r);
  int top = 0, bottom = 0;
  for (size_t i = 0; i < r.position.rgba.size() / 4; ++i)
    if (r.position.rgba[4 * i + 3] != 0.0f)
      (i / size_t(view.width) < size_t(view.height) / 2 ? top : bottom)++;
  EXPECT_GT(top, 100);
  EXPECT_EQ(bottom, 0);
}

// A level with no tets renders E = 0 on geometry (the shader's empty-level path), not garbage.
TEST(GpuLookup, EmptyLevelGivesZero) {
  Level level;
  level.origin = kOrigin;
  const ProbeQuery query(level);
  RenderResult r;
  RENDER_OR_SKIP(makeMesh(), level, query, makeView(RenderMode::kIrradiance), r);
  int geometry = 0;
  for (size_t i = 0; i < r.color.rgba.size() / 4; ++i) {
    if (r.position.rgba[4 * i + 3] == 0.0f) continue;
    ++geometry;
    for (int c = 0; c < 3; ++c) ASSERT_EQ(r.color.rgba[4 * i + c], 0.0f);
  }
  EXPECT_GT(geometry, 0);
}

// A level whose tets point outside its arrays is refused at upload (the shader reads without bounds checks),
// with a message naming the tet, instead of rendering garbage or faulting.
TEST(Render, RejectsLevelWithIndexOutOfRange) {
  Level level = makeLevel();
  const ProbeQuery query(level);  // built on the valid level; the corruption below is what the upload sees
  level.tets[3].n[1] = int32_t(level.tets.size()) + 7;
  try {
    renderLevel(makeMesh(), level, query, makeView(RenderMode::kIrradiance));
    FAIL() << "expected the upload to refuse the level";
  } catch (const std::runtime_error& e) {
    const std::string what = e.what();
    if (what.find("no Vulkan") != std::string::npos) GTEST_SKIP() << what;
    EXPECT_NE(what.find("tet 3"), std::string::npos) << what;
  }
}

}  // namespace
}  // namespace tetraprobe
