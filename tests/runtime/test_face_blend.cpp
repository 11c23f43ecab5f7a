// faceBlendVisibility (runtime/face_blend.h): two tets sharing a face, one with occlusion data that hides the
// face's probes, one without. On the face both sides must blend to the same visibility; outside the band,
// across a hull face and between two tets without data nothing changes; the side that sees its probes is
// trusted more than the side that falls back.
#include <algorithm>
#include <cmath>
#include <random>

#include <gtest/gtest.h>
#include <glm/geometric.hpp>

#include "tetraprobe/runtime/face_blend.h"
#include "tetraprobe/runtime/occlusion.h"

namespace tetraprobe {
namespace {

// Tet 0 = probes 0,1,2,3 and tet 1 = probes 4,3,2,1 share the face (1, 2, 3): tet 0's face opposite its
// slot 0, tet 1's opposite its slot 0. Probe 0 lies below the face, probe 4 above.
Level twoTets() {
  Level level;
  level.probes = {{0.3f, 0.2f, -1.0f}, {0, 0, 0}, {2, 0, 0}, {0.5f, 1.7f, 0}, {0.9f, 0.6f, 1.3f}};
  level.sh.resize(level.probes.size());
  level.tets.resize(2);
  level.tets[0] = Tet{{0, 1, 2, 3}, {1, -1, -1, -1}};
  level.tets[1] = Tet{{4, 3, 2, 1}, {0, -1, -1, -1}};
  return level;
}

// Tet 0 stores one plane with both cells seeing only its own probe 0 (slot 0): the face probes hidden.
LevelOcclusion hideFaceProbesInTet0() {
  LevelOcclusion occ;
  occ.planes.push_back(makeOcclusionPlane(1.0, -0.5, -0.5, -0.5));
  occ.tets = {makeTetOcclusion(kOcclusionPlanes, 1, 0, 0x11u), TetOcclusion{}};
  return occ;
}

glm::vec3 facePoint(const Level& level, double u, double v) {
  const glm::dvec3 a(level.probes[1]), b(level.probes[2]), c(level.probes[3]);
  return glm::vec3(a + u * (b - a) + v * (c - a));
}

// The visibility of the face's three probes (by probe index 1, 2, 3) as tet `tet` blends it at x.
glm::vec3 faceProbeVisibility(const Level& level, int32_t tet, const glm::vec3& x, const glm::vec3& n) {
  const BaryFrame f = baryFrame(level.tets[size_t(tet)], level.probes);
  glm::vec4 w = glm::max(baryWeights(f, x), glm::vec4(0.0f));
  w /= w.x + w.y + w.z + w.w;
  const glm::vec4 own = occlusionVisibility(level, level.occlusion, tet, f, x, n);
  const glm::vec4 vis = faceBlendVisibility(level, level.occlusion, tet, w, own, x, n);
  glm::vec3 out(0.0f);
  for (int i = 0; i < 4; ++i) {
    const int32_t p = level.tets[size_t(tet)].v[i];
    if (p >= 1 && p <= 3) out[p - 1] = vis[i];
  }
  return out;
}

TEST(FaceBlend, BothSidesOfASharedFaceUseTheSameVisibility) {
  Level level = twoTets();
  level.occlusion = hideFaceProbesInTet0();
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u01(0.0, 1.0);
  int checked = 0;
  for (int k = 0; k < 200; ++k) {
    double u = u01(rng), v = u01(rng);
    if (u + v > 1.0) u = 1.0 - u, v = 1.0 - v;
    if (std::min({u, v, 1.0 - u - v}) < kFaceBlendBand) continue;  // near an edge: hull faces here
    const glm::vec3 x = facePoint(level, u, v);
    for (const glm::vec3& n : {glm::vec3(0.0f), glm::vec3(0, 0, 1), glm::vec3(0, 0, -1)}) {
      const glm::vec3 a = faceProbeVisibility(level, 0, x, n), b = faceProbeVisibility(level, 1, x, n);
      for (int i = 0; i < 3; ++i) EXPECT_NEAR(a[i], b[i], 1e-5) << "face point " << u << ", " << v;
      // Tet 0 alone hides them (it falls back: trust 0.1) and tet 1 sees them (trust 1): 1 / 1.1.
      for (int i = 0; i < 3; ++i) EXPECT_NEAR(a[i], 1.0f / (1.0f + kFaceBlendFallbackTrust), 1e-4);
      ++checked;
    }
  }
  EXPECT_GT(checked, 60);
}

TEST(FaceBlend, NothingChangesBeyondTheBandOnHullFacesOrBetweenTetsWithoutData) {
  Level level = twoTets();
  level.occlusion = hideFaceProbesInTet0();
  const glm::vec3 n(0, 0, -1);
  // Deep in tet 0 (its slot-0 weight, the shared face's, is 0.4): unchanged, bit for bit.
  const glm::vec4 w(0.4f, 0.2f, 0.2f, 0.2f);
  const glm::vec3 x = 0.4f * level.probes[0] + 0.2f * (level.probes[1] + level.probes[2] + level.probes[3]);
  const glm::vec4 own(0.0f, 0.25f, 0.5f, 0.75f);
  const glm::vec4 out = faceBlendVisibility(level, level.occlusion, 0, w, own, x, n);
  for (int i = 0; i < 4; ++i) EXPECT_EQ(out[i], own[i]);
  // Near tet 0's hull faces only (slots 1..3 small, slot 0 beyond the band): unchanged.
  const glm::vec4 wHull(0.94f, 0.02f, 0.02f, 0.02f);
  const glm::vec3 xHull =
      0.94f * level.probes[0] + 0.02f * (level.probes[1] + level.probes[2] + level.probes[3]);
  const glm::vec4 outHull = faceBlendVisibility(level, level.occlusion, 0, wHull, own, xHull, n);
  for (int i = 0; i < 4; ++i) EXPECT_EQ(outHull[i], own[i]);
  // On the shared face with neither tet storing data: unchanged.
  level.occlusion.tets[0] = TetOcclusion{};
  const glm::vec3 xf = facePoint(level, 0.3, 0.3);
  const glm::vec4 wf(0.0f, 0.4f, 0.3f, 0.3f);
  const glm::vec4 outNone = faceBlendVisibility(level, level.occlusion, 0, wf, glm::vec4(1.0f), xf, n);
  for (int i = 0; i < 4; ++i) EXPECT_EQ(outNone[i], 1.0f);
}

// The probe flag (faceBlendProbeFlag) is cleared on a probe every tet holding it sees at exactly 1 wherever
// its data is evaluated, and set where a tet may hide it; where it is cleared the flagged blend equals the
// blend of every probe bit for bit, at random points on and near the face, with random normals. Three cases
// of data on tet 0 that never hides the face's probes (slots 1..3): one plane whose cells both see them (only
// its own probe 0 is hidden on one side), shadow maps that meet nothing from those probes, and the same
// with tet 1 storing its own such plane.
TEST(FaceBlend, UnflaggedProbeWithDataChangesNoVisibility) {
  Level level = twoTets();
  LevelOcclusion onePlane;
  onePlane.planes.push_back(makeOcclusionPlane(1.0, -0.5, -0.5, -0.5));
  onePlane.tets = {makeTetOcclusion(kOcclusionPlanes, 1, 0, 0xFEu), TetOcclusion{}};
  LevelOcclusion maps;
  maps.shadowMaps.assign(kShadowMapBlockBytes, kShadowMapNoHit);
  for (int b = 0; b < kShadowMapLatticeVertices; ++b)
    maps.shadowMaps[size_t(b)] = 100;  // probe 0 meets a wall
  maps.tets = {makeTetOcclusion(kOcclusionShadowMaps, 0, 0, 0), TetOcclusion{}};
  LevelOcclusion both = onePlane;
  both.planes.push_back(makeOcclusionPlane(-0.5, 1.0, -0.5, -0.5));
  both.tets[1] = makeTetOcclusion(kOcclusionPlanes, 1, 1, 0xEFu);  // tet 1's slot 0 (probe 4) hidden
  std::mt19937 rng(11);
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  std::normal_distribution<float> g(0.0f, 1.0f);
  for (const LevelOcclusion* occ : {&onePlane, &maps, &both}) {
    level.occlusion = *occ;
    for (int i = 1; i < 4; ++i) {  // the face's probes, in either tet
      EXPECT_FALSE(faceBlendProbeFlag(level, level.occlusion, 0, i));
      EXPECT_FALSE(faceBlendProbeFlag(level, level.occlusion, 1, i));
    }
    EXPECT_EQ(faceBlendMask(level, level.occlusion, 0), 1u);  // probe 0 is hidden in one cell or map
    EXPECT_EQ(faceBlendMask(level, level.occlusion, 1),
              occ == &both ? 1u : 0u);  // probe 4 where tet 1 hides it
    int moved = 0;
    for (int s = 0; s < 2000; ++s) {
      const int32_t tet = s % 2;
      glm::vec4 w(std::pow(u(rng), 4.0f), u(rng), u(rng), u(rng));  // slot 0 small: near the shared face
      w /= w.x + w.y + w.z + w.w;
      glm::vec3 x(0.0f);
      for (int i = 0; i < 4; ++i) x += w[i] * level.probes[size_t(level.tets[size_t(tet)].v[i])];
      const glm::vec3 n = glm::normalize(glm::vec3(g(rng), g(rng), g(rng)));
      const BaryFrame f = baryFrame(level.tets[size_t(tet)], level.probes);
      const glm::vec4 own = occlusionVisibility(level, level.occlusion, tet, f, x, n);
      const glm::vec4 flagged =
          faceBlendVisibility(level, level.occlusion, tet, w, own, x, n, kFaceBlendFlaggedProbes);
      const glm::vec4 every = faceBlendVisibility(level, level.occlusion, tet, w, own, x, n);
      for (int i = 0; i < 4; ++i) ASSERT_EQ(flagged[i], every[i]) << "point " << s << " slot " << i;
      moved += own != glm::vec4(1.0f);
    }
    EXPECT_GT(moved, 100);  // the data acts (on the probe opposite the face), just not on the face's probes
  }
  // A plane hiding the face's probes in tet 0 flags them in both tets (a probe's flag is the star's).
  level.occlusion = hideFaceProbesInTet0();
  EXPECT_EQ(faceBlendMask(level, level.occlusion, 0), 14u);
  EXPECT_EQ(faceBlendMask(level, level.occlusion, 1), 14u);
}

// A tet whose own data hides all four probes (it falls back) looks for light its neighbour sees deeper in:
// where the first pass (depths in the thinner tet's units: tet 0's, 1 m over the shared face) leaves it
// blind, the blind pass reaches with kFaceBlendFallbackBand in the reaching tet's own units (tet 1's height
// over the face is 1.3 m). The walk parameter t below is the depth in metres.
TEST(FaceBlend, ATetThatSeesNothingTakesItsNeighboursSightDeeper) {
  Level level = twoTets();
  level.occlusion = hideFaceProbesInTet0();
  level.occlusion.tets[0].cells = 0x00u;  // tet 0 sees none of its probes, on either side of its plane
  const glm::vec3 f = facePoint(level, 0.3, 0.3), p0 = level.probes[0];
  const auto at = [&](float t) { return faceProbeVisibility(level, 0, f + t * (p0 - f), glm::vec3(0.0f)); };
  const float face = 1.3f;  // tet 1's height over the face
  // Beyond the plain band but inside the widened one: some of the neighbour's sight.
  const float t = 0.5f * (kFaceBlendBand + kFaceBlendFallbackBand) * face;
  ASSERT_GT(t, kFaceBlendBand * face);
  const float x = t / (kFaceBlendFallbackBand * face), a = 1.0f - x * x * (3.0f - 2.0f * x);
  const float expected = a / (a + kFaceBlendFallbackTrust);  // tet 0 trusted 0.1, tet 1 1 at reach a
  for (int i = 0; i < 3; ++i) EXPECT_NEAR(at(t)[i], expected, 2e-3f);
  // Past the widened band: the tet's own data alone.
  for (int i = 0; i < 3; ++i) EXPECT_EQ(at(kFaceBlendFallbackBand * face + 0.01f)[i], 0.0f);
}

// A probe behind the surface is never seen from it: where neither side is blind, the neighbour may not raise
// its visibility above the lower side's (a ceiling point on q3 dm4ish took a probe above the ceiling from its
// neighbour's data). A probe in front still gets the trust-weighted mean.
TEST(FaceBlend, TheNeighbourDoesNotRaiseAProbeBehindTheSurface) {
  Level level = twoTets();
  level.occlusion = hideFaceProbesInTet0();
  level.occlusion.tets[0].cells = 0x33u;  // tet 0 sees its probes 0 and 1, hides 2 and 3; tet 1 sees all
  const glm::vec3 x = facePoint(level, 0.3, 0.3), n(-1.0f, 0.0f, 0.0f);  // probe 2 (at x = 2) behind
  const glm::vec3 a = faceProbeVisibility(level, 0, x, n), b = faceProbeVisibility(level, 1, x, n);
  for (int i = 0; i < 3; ++i) EXPECT_NEAR(a[i], b[i], 1e-5) << "probe " << i + 1;
  EXPECT_NEAR(a[0], 1.0f, 1e-5);  // probe 1: both see it
  EXPECT_NEAR(a[1], 0.0f, 1e-5);  // probe 2: behind the surface, hidden by tet 0
  EXPECT_NEAR(a[2], 0.5f, 1e-4);  // probe 3: in front, the mean of two sides that both see (trust 1 each)
}

TEST(FaceBlend, BlendFadesContinuouslyAcrossTheBand) {
  Level level = twoTets();
  level.occlusion = hideFaceProbesInTet0();
  // Walk from the face into tet 0 along the line to probe 0: the blended visibility of probe 1 falls
  // monotonically from 1/1.1 on the face to tet 0's own 0 at the band's end. It is steep where tet 0's own
  // fallback share runs from 1 to 0 (its visible weight, probe 0's, from 0 to kOcclusionFallbackSum), but
  // without a step: ten times finer steps give about ten times smaller largest differences.
  const glm::vec3 f = facePoint(level, 0.3, 0.3), p0 = level.probes[0];
  const auto largestStep = [&](int steps) {
    float prev = 2.0f, largest = 0.0f;
    for (int s = 0; s <= steps; ++s) {
      const float t = 0.3f * float(s) / float(steps);  // tet 0's slot-0 weight
      const glm::vec3 vis = faceProbeVisibility(level, 0, f + t * (p0 - f), glm::vec3(0.0f));
      EXPECT_LE(vis[0], prev + 1e-6f) << "t " << t;
      if (s > 0) largest = std::max(largest, prev - vis[0]);
      prev = vis[0];
    }
    EXPECT_EQ(prev, 0.0f);
    return largest;
  };
  const float coarse = largestStep(200), fine = largestStep(2000);
  EXPECT_GT(coarse, 0.0f);
  EXPECT_LT(fine, 0.2f * coarse) << "coarse " << coarse << ", fine " << fine;
}

}  // namespace
}  // namespace tetraprobe
