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

#include "lookup_scene.h"
#include "tetraprobe/render/render.h"
#include "tetraprobe/runtime/occlusion.h"
#include "tetraprobe/runtime/query.h"
#include "tetraprobe/tetra/tetrahedralize.h"

namespace tetraprobe {
namespace {

using namespace tetraprobe::test;

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
// seen 1.3e-5 on lavapipe), the all-occluded fallback's pixels included.
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

  int inside = 0, outside = 0, bad = 0, occluded = 0, fallback = 0;
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
      float share = 0.0f;
      applyOcclusion(loc.weights, vis, &share);
      fallback += share > 0.0f;
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
    std::printf(
        "occlusion: %d pixels with an occluded probe, %d in the all-occluded fallback, %d beyond 1e-4\n",
        occluded, fallback, bad);
    EXPECT_GT(occluded, 1000) << "the synthetic occlusion must hide probes on plenty of pixels";
    EXPECT_GT(fallback, 100) << "the fallback (probeFront, occludedIrradiance) must be compared too";
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
    if (isNoVulkan(what)) TETRAPROBE_SKIP_MISSING(what);
    EXPECT_NE(what.find("tet 3"), std::string::npos) << what;
  }
}

}  // namespace
}  // namespace tetraprobe
