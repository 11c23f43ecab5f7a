// Run-time occlusion evaluation (runtime/occlusion.h): shadow-map cell numbering, the bias rule, and the
// renormalization with its all-occluded fallback. No ray tracing here.
#include <algorithm>
#include <cmath>
#include <limits>
#include <random>

#include <gtest/gtest.h>

#include <glm/common.hpp>

#include "test_levels.h"
#include "tetraprobe/runtime/occlusion.h"
#include "tetraprobe/runtime/sh.h"

namespace tetraprobe {
namespace {

// Corners (u, v) of sub-triangle `cell`, derived independently of shadowMapCell from the row layout.
void cellCorners(int cell, glm::vec2 out[3]) {
  int row = 0, k = cell;
  while (k >= 2 * (4 - row) - 1) k -= 2 * (4 - row++) - 1;
  const int iu = k / 2;
  const float u = float(iu) / 4.0f, v = float(row) / 4.0f, h = 0.25f;
  if (k % 2 == 0) {
    out[0] = {u, v}, out[1] = {u + h, v}, out[2] = {u, v + h};
  } else {
    out[0] = {u + h, v}, out[1] = {u + h, v + h}, out[2] = {u, v + h};
  }
}

bool inTriangle(glm::vec2 p, const glm::vec2 t[3], float eps) {
  auto cross = [](glm::vec2 a, glm::vec2 b) { return a.x * b.y - a.y * b.x; };
  const float d0 = cross(t[1] - t[0], p - t[0]), d1 = cross(t[2] - t[1], p - t[1]),
              d2 = cross(t[0] - t[2], p - t[2]);
  return (d0 >= -eps && d1 >= -eps && d2 >= -eps) || (d0 <= eps && d1 <= eps && d2 <= eps);
}

// The build traces toward each sub-triangle's centre and the runtime looks the texel up by cell: the two
// numberings must agree, or every shadow map reads the wrong texel.
TEST(OcclusionRuntime, ShadowMapCellCentresRoundTrip) {
  for (int k = 0; k < kShadowMapTexels; ++k) {
    const glm::vec2 c = shadowMapCellCentre(k);
    EXPECT_EQ(shadowMapCell(c.x, c.y), k) << "centre " << c.x << "," << c.y;
  }
}

// Every point of the face maps to the sub-triangle that contains it, and the 16 tile the face.
TEST(OcclusionRuntime, ShadowMapCellsTileTheFace) {
  const int n = 97;
  int count[kShadowMapTexels] = {};
  for (int j = 0; j <= n; ++j)
    for (int i = 0; i + j <= n; ++i) {
      const float u = float(i) / n, v = float(j) / n;
      const int k = shadowMapCell(u, v);
      ASSERT_GE(k, 0);
      ASSERT_LT(k, kShadowMapTexels);
      glm::vec2 t[3];
      cellCorners(k, t);
      EXPECT_TRUE(inTriangle({u, v}, t, 1e-6f)) << "u=" << u << " v=" << v << " cell " << k;
      ++count[k];
    }
  for (int k = 0; k < kShadowMapTexels; ++k) EXPECT_GT(count[k], 0) << "cell " << k;
  // Outside the face (rounding, points outside the tet): clamped, still a valid cell.
  for (glm::vec2 p : {glm::vec2(-1, 0.5f), glm::vec2(0.7f, 0.7f), glm::vec2(2, 2), glm::vec2(NAN, 0.2f)}) {
    const int k = shadowMapCell(p.x, p.y);
    EXPECT_GE(k, 0);
    EXPECT_LT(k, kShadowMapTexels);
  }
}

// A planar occluder met by every corner ray is reproduced exactly (up to quantization) everywhere on the
// face: 1/depth is affine in the face point for a plane, and the lookup interpolates 1/depth.
TEST(OcclusionRuntime, ShadowMapDepthIsExactForPlanes) {
  // Probe at the origin, face points F(u, v) = A + u (B - A) + v (C - A); plane n.x = 0.2 in front of it.
  const glm::vec3 A(1, 0, 0), B(0, 1, 0), C(0, 0, 1), n = glm::normalize(glm::vec3(1.0f, 0.6f, 0.3f));
  auto exact = [&](float u, float v) {
    const glm::vec3 F = A + u * (B - A) + v * (C - A);
    return 0.2f / glm::dot(n, F);  // the ray t F meets the plane at t = 0.2 / n.F
  };
  uint8_t texels[kShadowMapTexels];
  std::fill(texels, texels + kShadowMapTexels, kShadowMapNoHit);
  for (int b = 0; b <= 4; ++b)
    for (int a = 0; a + b <= 4; ++a)
      texels[shadowMapVertex(a, b)] = uint8_t(std::round(exact(a / 4.0f, b / 4.0f) * kShadowMapScale));
  std::mt19937 rng(3);
  std::uniform_real_distribution<float> uni(0.0f, 1.0f);
  for (int k = 0; k < 2000; ++k) {
    float u = uni(rng), v = uni(rng);
    if (u + v > 1.0f) u = 1.0f - u, v = 1.0f - v;
    const float e = exact(u, v);
    ASSERT_LT(e, 1.0f);
    EXPECT_NEAR(shadowMapDepth(texels, u, v), e, 2.0f / kShadowMapScale) << "u=" << u << " v=" << v;
  }
  // No corner met anything: beyond the face.
  std::fill(texels, texels + kShadowMapTexels, kShadowMapNoHit);
  EXPECT_GT(shadowMapDepth(texels, 0.3f, 0.3f), 1.0f);
}

// The bias moves no barycentric weight by more than kOcclusionBias, keeps the sum 1, ignores the normal's
// length, and a zero normal moves nothing.
TEST(OcclusionRuntime, BiasMovesNoWeightMoreThanTheBias) {
  const Level level = test::makeLevel(test::regularTet());
  const BaryFrame t = baryFrame(level.tets[0], level.probes);
  const glm::vec4 w(0.1f, 0.2f, 0.3f, 0.4f);
  for (glm::vec3 n : {glm::vec3(0, 0, 1), glm::vec3(0.3f, -2.0f, 0.5f), glm::vec3(-1, 1, 1)}) {
    const glm::vec4 b = biasWeights(t, w, n);
    const glm::vec4 b2 = biasWeights(t, w, 7.0f * n);
    float maxMove = 0.0f;
    for (int i = 0; i < 4; ++i) {
      maxMove = std::max(maxMove, std::abs(b[i] - w[i]));
      EXPECT_NEAR(b[i], b2[i], 1e-6f);
    }
    EXPECT_NEAR(maxMove, kOcclusionBias, 1e-6f);
    EXPECT_NEAR(b.x + b.y + b.z + b.w, 1.0f, 1e-5f);
  }
  const glm::vec4 z = biasWeights(t, w, glm::vec3(0.0f));
  for (int i = 0; i < 4; ++i) EXPECT_EQ(z[i], w[i]);
}

// An occluded probe drops out and the rest are renormalized.
TEST(OcclusionRuntime, ApplyOcclusionDropsOccludedProbes) {
  const glm::vec4 r = applyOcclusion(glm::vec4(0.1f, 0.2f, 0.3f, 0.4f), glm::vec4(1, 0, 1, 0));
  EXPECT_NEAR(r.x, 0.25f, 1e-6f);
  EXPECT_EQ(r.y, 0.0f);
  EXPECT_NEAR(r.z, 0.75f, 1e-6f);
  EXPECT_EQ(r.w, 0.0f);
  const glm::vec4 same = applyOcclusion(glm::vec4(0.1f, 0.2f, 0.3f, 0.4f), glm::vec4(1.0f));
  EXPECT_NEAR(same.w, 0.4f, 1e-6f);
}

// Whatever comes in (all occluded, NaN, Inf, negative, zero weights), the result is finite, non-negative and
// sums to 1, and the fallback share is in [0, 1]: 0 with enough visible weight, 1 when every probe is
// occluded (the weights are then the sanitized input), growing continuously as the visible sum falls.
TEST(OcclusionRuntime, ApplyOcclusionNeverNaNAndSumsToOne) {
  const float inf = std::numeric_limits<float>::infinity(), nan = std::numeric_limits<float>::quiet_NaN();
  float f = -1.0f;
  const glm::vec4 all = applyOcclusion(glm::vec4(0.1f, 0.2f, 0.3f, 0.4f), glm::vec4(0.0f), &f);
  EXPECT_NEAR(all.z, 0.3f, 1e-6f);
  EXPECT_EQ(f, 1.0f);
  applyOcclusion(glm::vec4(0.1f, 0.2f, 0.3f, 0.4f), glm::vec4(1, 0, 0, 0), &f);
  EXPECT_EQ(f, 0.0f);
  std::mt19937 rng(6);
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  const float specials[] = {0.0f, 1.0f, -1.0f, nan, inf, -inf, 1e-30f, 1e30f};
  for (int k = 0; k < 20000; ++k) {
    glm::vec4 w, v;
    for (int i = 0; i < 4; ++i) {
      w[i] = (k % 3 == 0) ? specials[rng() % 8] : u(rng);
      v[i] = (k % 2 == 0) ? specials[rng() % 8] : (u(rng) < 0.5f ? 0.0f : u(rng) * 1e-3f);
    }
    const glm::vec4 r = applyOcclusion(w, v, &f);
    ASSERT_TRUE(f >= 0.0f && f <= 1.0f) << f;
    float sum = 0.0f;
    for (int i = 0; i < 4; ++i) {
      ASSERT_TRUE(std::isfinite(r[i])) << "w=" << w[i] << " v=" << v[i];
      ASSERT_GE(r[i], 0.0f);
      sum += r[i];
    }
    ASSERT_NEAR(sum, 1.0f, 1e-5f);
  }
  // Continuity at the fallback threshold: the share is 0 just above it and near 0 just below.
  const glm::vec4 w(0.25f);
  const float s = kOcclusionFallbackSum;
  float fAbove = -1.0f, fBelow = -1.0f;
  applyOcclusion(w, glm::vec4(4.0f * s * 1.001f, 0, 0, 0), &fAbove);
  applyOcclusion(w, glm::vec4(4.0f * s * 0.999f, 0, 0, 0), &fBelow);
  EXPECT_EQ(fAbove, 0.0f);
  EXPECT_NEAR(fBelow, 0.001f, 1e-4f);
}

// The run-time answer: visible probes interpolate; a point that sees none gets the blend dominated by its
// nearest probe (weights^8, renormalized), capped per channel by the unoccluded blend -- not the dimmest probe
// (often across the wall: the dark polygons) and not the unoccluded blend (a leak of the brightest); in
// between the two blend continuously. And where two weights tie the fallback is continuous too.
TEST(OcclusionRuntime, OccludedIrradianceFallsBackToTheNearestProbeCappedByTheBlend) {
  ShRgb sh[4];
  const float dc[4][3] = {{8.0f, 1.0f, 3.0f}, {2.0f, 4.0f, 3.0f}, {5.0f, 5.0f, 0.5f}, {9.0f, 9.0f, 9.0f}};
  for (int i = 0; i < 4; ++i) sh[i].c[0] = glm::vec3(dc[i][0], dc[i][1], dc[i][2]);  // constant radiance
  const ShRgb* probes[4] = {&sh[0], &sh[1], &sh[2], &sh[3]};
  const glm::vec3 n(0.0f, 0.0f, 1.0f);
  auto e = [&](int i) {
    const ShRgb* one[1] = {probes[i]};
    const float unit[1] = {1.0f};
    return shIrradiance(shBlend(one, unit, 1), n);
  };
  auto blendOf = [&](const glm::vec4& w) { return w.x * e(0) + w.y * e(1) + w.z * e(2) + w.w * e(3); };
  const glm::vec4 w(0.1f, 0.2f, 0.3f, 0.4f);
  // Two visible: their renormalized blend.
  const glm::vec3 two = occludedIrradiance(probes, w, glm::vec4(1, 0, 1, 0), n, glm::vec4(1.0f));
  const glm::vec3 expectTwo = 0.25f * e(0) + 0.75f * e(2);
  for (int c = 0; c < 3; ++c) EXPECT_NEAR(two[c], expectTwo[c], 1e-5f * expectTwo[c]);
  // None visible: min(nearest-dominated blend, unoccluded blend), per channel.
  const glm::vec3 none = occludedIrradiance(probes, w, glm::vec4(0.0f), n, glm::vec4(1.0f));
  glm::vec4 p = w * w * w * w;
  p = p * p;
  p /= p.x + p.y + p.z + p.w;
  const glm::vec3 expectNone = glm::min(blendOf(p), blendOf(w));
  for (int c = 0; c < 3; ++c) EXPECT_NEAR(none[c], expectNone[c], 1e-5f * expectNone[c]);
  EXPECT_GT(p.w, 0.9f) << "the nearest probe (largest weight) dominates";
  const glm::vec3 dimmest = glm::min(glm::min(e(0), e(1)), glm::min(e(2), e(3)));
  EXPECT_GT(none.y, 2.0f * dimmest.y) << "not the dimmest probe";
  EXPECT_LE(none.x, blendOf(w).x * (1.0f + 1e-6f)) << "never above the unoccluded blend";
  // Continuous where the two largest weights tie (probe 2 overtakes probe 3): no jump in the fallback.
  glm::vec3 prevTie =
      occludedIrradiance(probes, glm::vec4(0.1f, 0.1f, 0.45f, 0.35f), glm::vec4(0.0f), n, glm::vec4(1.0f));
  for (int k = 1; k <= 200; ++k) {
    const float t = 0.1f * float(k) / 200.0f;
    const glm::vec3 cur = occludedIrradiance(probes, glm::vec4(0.1f, 0.1f, 0.45f - t, 0.35f + t),
                                             glm::vec4(0.0f), n, glm::vec4(1.0f));
    for (int c = 0; c < 3; ++c) ASSERT_LE(std::abs(cur[c] - prevTie[c]), 0.02f * e(3)[c]) << k;
    prevTie = cur;
  }
  // Continuous through the threshold: the answer moves smoothly from the fallback to the visible blend.
  glm::vec3 prev = none;
  for (int k = 1; k <= 400; ++k) {
    const float v = 2.0f * kOcclusionFallbackSum * float(k) / 400.0f / w.x;  // probe 0 alone, fading in
    const glm::vec3 cur = occludedIrradiance(probes, w, glm::vec4(v, 0, 0, 0), n, glm::vec4(1.0f));
    for (int c = 0; c < 3; ++c) ASSERT_LE(std::abs(cur[c] - prev[c]), 0.02f * e(3)[c]) << k;
    prev = cur;
  }
  for (int c = 0; c < 3; ++c) EXPECT_NEAR(prev[c], e(0)[c], 1e-5f * e(0)[c]);
}

// probeFront: 1 for probes rising kOcclusionFrontSine or more above the surface plane, 0 on or behind it,
// linear (so continuous) between, whatever the lengths; 1 for a zero normal (volumes) or a probe at the point.
TEST(OcclusionRuntime, ProbeFrontIsOneInFrontZeroBehindAndContinuous) {
  const glm::vec3 n(0.0f, 0.0f, 2.0f);  // any length
  const glm::vec3 d[4] = {{1, 0, 0.5f}, {3, 0, -0.1f}, {100, 0, 0}, {0, 0, 0}};
  const glm::vec4 f = probeFront(d, n);
  EXPECT_EQ(f, glm::vec4(1.0f, 0.0f, 0.0f, 1.0f));
  EXPECT_EQ(probeFront(d, glm::vec3(0.0f)), glm::vec4(1.0f));
  float prev = 0.0f;
  for (int k = 0; k <= 400; ++k) {  // the elevation's sine from -0.01 to 0.03: one linear ramp
    const float sine = -0.01f + 0.04f * float(k) / 400.0f;
    const glm::vec3 e[4] = {{std::sqrt(1.0f - sine * sine), 0.0f, sine}, d[1], d[2], d[3]};
    const float cur = probeFront(e, n).x;
    EXPECT_NEAR(cur, std::clamp(sine / kOcclusionFrontSine, 0.0f, 1.0f), 1e-5f) << k;
    if (k > 0) {
      ASSERT_LE(std::abs(cur - prev), 0.0001f / kOcclusionFrontSine + 1e-5f) << k;
    }
    prev = cur;
  }
}

// A point on a wall whose data hides all four probes: the nearest probe sits behind the wall (dark), two others
// in front (lit). The fallback takes the nearest probe in front of the surface, not the nearest of all, and
// where none is in front it is the nearest of all again (the rule before).
TEST(OcclusionRuntime, OccludedIrradianceFallbackTakesTheNearestProbeInFrontOfTheSurface) {
  ShRgb sh[4];
  const float dc[4] = {0.01f, 3.0f, 2.0f, 0.02f};  // 0 and 3 behind the wall, 1 and 2 in front
  for (int i = 0; i < 4; ++i) sh[i].c[0] = glm::vec3(dc[i]);
  const ShRgb* probes[4] = {&sh[0], &sh[1], &sh[2], &sh[3]};
  const glm::vec3 n(0.0f, 0.0f, 1.0f);
  auto e = [&](int i) {
    const ShRgb* one[1] = {probes[i]};
    const float unit[1] = {1.0f};
    return shIrradiance(shBlend(one, unit, 1), n).x;
  };
  const glm::vec4 w(0.47f, 0.24f, 0.28f, 0.01f);  // the conference room's spot (docs/accuracy.md)
  const glm::vec3 toProbe[4] = {
      {0.4f, -0.55f, -0.53f}, {0.08f, 1.22f, 0.53f}, {-0.7f, -0.13f, 0.5f}, {-0.84f, 0.04f, -1.72f}};
  const glm::vec4 front = probeFront(toProbe, n);
  ASSERT_EQ(front, glm::vec4(0.0f, 1.0f, 1.0f, 0.0f));
  const float fallback = occludedIrradiance(probes, w, glm::vec4(0.0f), n, front).x;
  const float unoccluded = w.x * e(0) + w.y * e(1) + w.z * e(2) + w.w * e(3);
  EXPECT_GT(fallback, 0.9f * std::min(e(2), unoccluded)) << "light of the side the surface faces";
  EXPECT_LE(fallback, unoccluded * (1.0f + 1e-6f)) << "capped by the unoccluded blend";
  const float allBehind = occludedIrradiance(probes, w, glm::vec4(0.0f), n, glm::vec4(0.0f)).x;
  EXPECT_NEAR(allBehind, occludedIrradiance(probes, w, glm::vec4(0.0f), n, glm::vec4(1.0f)).x, 1e-6f)
      << "no probe in front: the nearest of all";
  EXPECT_LT(allBehind, 0.1f * fallback) << "the rule before took the probe behind the wall";
}

// No occlusion data (or a tet out of range) means every probe is visible: nothing is evaluated.
TEST(OcclusionRuntime, EmptyDataMeansAllVisible) {
  const Level level = test::makeLevel(test::regularTet());
  LevelOcclusion none;
  EXPECT_EQ(none.bytes(), 0u);
  const glm::vec4 v = occlusionVisibility(level, none, 0, glm::vec3(0.5f), glm::vec3(0, 0, 1));
  EXPECT_EQ(v, glm::vec4(1.0f));
  LevelOcclusion one;
  one.tets.resize(1);
  one.planes.push_back(makeOcclusionPlane(1, 1, -1, -1));
  one.tets[0] = makeTetOcclusion(kOcclusionPlanes, 1, 0, 0x0u);  // both cells see nothing
  EXPECT_EQ(occlusionVisibility(level, one, 5, glm::vec3(0.5f), glm::vec3(0.0f)), glm::vec4(1.0f));
  EXPECT_EQ(occlusionVisibility(level, one, -1, glm::vec3(0.5f), glm::vec3(0.0f)), glm::vec4(1.0f));
  // A plane record pointing past the array is answered as all visible, not read.
  one.tets[0] = makeTetOcclusion(kOcclusionPlanes, 3, 0, 0);
  EXPECT_EQ(occlusionVisibility(level, one, 0, glm::vec3(0.5f), glm::vec3(0.0f)), glm::vec4(1.0f));
}

// A hand-written plane record: probes with c > 0 are seen from the positive side only, with a soft band of
// half-width kOcclusionPlaneFalloff across the plane.
TEST(OcclusionRuntime, PlaneCellsSelectByValueWithSoftBand) {
  const Level level = test::makeLevel(test::regularTet());
  const Tet& t = level.tets[0];
  double d[4];
  uint32_t posMask = 0, negMask = 0;
  for (int i = 0; i < 4; ++i) {
    const float z = level.probes[size_t(t.v[i])].z;
    d[i] = z > 0.5f ? 1.0 : -1.0;  // the plane z = 0.5
    (z > 0.5f ? posMask : negMask) |= 1u << i;
  }
  LevelOcclusion occ;
  occ.tets = {makeTetOcclusion(kOcclusionPlanes, 1, 0, negMask | posMask << 4)};
  occ.planes = {makeOcclusionPlane(d[0], d[1], d[2], d[3])};
  auto vis = [&](float z) {
    return occlusionVisibility(level, occ, 0, glm::vec3(0.5f, 0.5f, z), glm::vec3(0.0f));
  };
  for (int i = 0; i < 4; ++i) {
    const bool up = (posMask >> i) & 1u;
    EXPECT_EQ(vis(0.7f)[i], up ? 1.0f : 0.0f);
    EXPECT_EQ(vis(0.3f)[i], up ? 0.0f : 1.0f);
    EXPECT_NEAR(vis(0.5f)[i], 0.5f, 1e-4f);  // on the plane: half of each side
  }
}

}  // namespace
}  // namespace tetraprobe
