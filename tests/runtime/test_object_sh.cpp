// ProbeQuery::interpolatedSh (query.h): the per-object SH an engine feeds its forward shaders. One SH must
// light every normal of the object as the per-normal irradiance does: exactly without occlusion, wherever the
// visibility does not depend on the normal with it, and as a convex blend of the tet's probes everywhere. The
// per-object tet cache changes the speed, not the answer, and a moving object's walk from it is short.
#include <algorithm>
#include <cmath>
#include <cstring>
#include <random>
#include <vector>

#include <gtest/gtest.h>

#include "test_levels.h"
#include "tetraprobe/runtime/lookup_constants.h"
#include "tetraprobe/runtime/occlusion.h"
#include "tetraprobe/runtime/sh.h"
#include "tetraprobe/runtime/shade.h"

namespace tetraprobe {
namespace {

const glm::dvec3 kOrigin(1000.0, -50.0, 3.0);  // a far origin: the local point is taken in double first

Level boxLevel(uint64_t seed) {
  return test::makeLevel(test::randomBoxPoints(150, seed, kOrigin, kOrigin + glm::dvec3(10.0, 6.0, 8.0)),
                         kOrigin, seed);
}

// Query points: random ones in a box 3 m larger than the hull on every side (about half outside), every
// probe (a vertex of several tets), and the centroid and an edge midpoint of a face of random tets.
std::vector<glm::dvec3> queryPoints(const Level& level, uint64_t seed) {
  std::vector<glm::dvec3> pts = test::randomBoxPoints(1500, seed, kOrigin - glm::dvec3(3.0),
                                                      kOrigin + glm::dvec3(13.0, 9.0, 11.0), false);
  for (const glm::vec3& p : level.probes) pts.push_back(kOrigin + glm::dvec3(p));
  std::mt19937_64 rng(seed);
  for (int k = 0; k < 300; ++k) {
    const Tet& t = level.tets[rng() % level.tets.size()];
    const glm::dvec3 a(level.probes[size_t(t.v[0])]), b(level.probes[size_t(t.v[1])]),
        c(level.probes[size_t(t.v[2])]);
    pts.push_back(kOrigin + (a + b + c) / 3.0);
    pts.push_back(kOrigin + (a + b) / 2.0);
  }
  return pts;
}

std::vector<glm::vec3> randomNormals(size_t n, uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<float> g;
  std::vector<glm::vec3> out;
  while (out.size() < n) {
    const glm::vec3 v(g(rng), g(rng), g(rng));
    if (glm::length(v) > 1e-3f) out.push_back(glm::normalize(v));
  }
  return out;
}

bool sameBits(const glm::vec3& a, const glm::vec3& b) {
  return std::memcmp(&a, &b, sizeof a) == 0;
}

bool sameBits(const ShRgb& a, const ShRgb& b) {
  return std::memcmp(&a, &b, sizeof a) == 0;
}

// Random plane occlusion on about two tets in three: one plane through the tet with random probe sides, each
// cell seeing a random non-empty subset of the probes (any subset: the test needs visibility that changes
// across the tet, not a physical wall).
LevelOcclusion randomPlaneOcclusion(const Level& level, uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  LevelOcclusion occ;
  occ.tets.resize(level.tets.size());
  for (TetOcclusion& t : occ.tets) {
    if (rng() % 3 == 0) continue;
    const uint32_t cell0 = 1u + uint32_t(rng() % 15u), cell1 = 1u + uint32_t(rng() % 15u);
    t = makeTetOcclusion(kOcclusionPlanes, 1, uint32_t(occ.planes.size()), cell0 | cell1 << 4);
    occ.planes.push_back(makeOcclusionPlane(u(rng), u(rng), u(rng), u(rng) + 0.2));
  }
  return occ;
}

// Without occlusion the SH is the one irradiance() evaluates for each normal: shIrradiance of it is the same
// float operations on the same values, so the tolerance is zero (bit for bit), inside and outside the hull,
// at probes (vertices) and on faces and edges.
TEST(ObjectSh, LightsEveryNormalAsIrradianceWithoutOcclusion) {
  const Level level = boxLevel(7);
  ASSERT_TRUE(level.occlusion.empty());
  const ProbeQuery query(level);
  const std::vector<glm::vec3> normals = randomNormals(12, 3);
  size_t outside = 0;
  for (const glm::dvec3& x : queryPoints(level, 11)) {
    const ShRgb sh = query.interpolatedSh(x);
    outside += query.locate(x).outerCell >= 0;
    for (const glm::vec3& n : normals) {
      const glm::vec3 fromSh = shIrradiance(sh, n), direct = query.irradiance(x, n);
      ASSERT_TRUE(sameBits(fromSh, direct))
          << "x (" << x.x << ", " << x.y << ", " << x.z << ") n (" << n.x << ", " << n.y << ", " << n.z
          << "): SH " << fromSh.x << " " << fromSh.y << " " << fromSh.z << ", irradiance " << direct.x << " "
          << direct.y << " " << direct.z;
    }
  }
  EXPECT_GT(outside, 300u);  // the outer cells are exercised
}

// An L1 level's probes have coefficients 4..8 zero; so has their blend (no L2 ringing invented).
TEST(ObjectSh, AnL1LevelGivesL1Sh) {
  Level level = boxLevel(8);
  level.shOrder = 1;
  for (ShRgb& s : level.sh)
    for (int i = 4; i < kShCoeffCount; ++i) s.c[size_t(i)] = glm::vec3(0.0f);
  const ProbeQuery query(level);
  for (const glm::dvec3& x : queryPoints(level, 12)) {
    const ShRgb sh = query.interpolatedSh(x);
    for (int i = 4; i < kShCoeffCount; ++i)
      ASSERT_EQ(sh.c[size_t(i)], glm::vec3(0.0f)) << "coefficient " << i;
    ASSERT_NE(sh.c[0], glm::vec3(0.0f));
  }
}

// With occlusion the SH is decided for the point itself (zero normal). Where the per-normal lookup sees the
// same visibility as the zero normal and no fallback runs, the answers are the same bits; everywhere the SH
// is a convex blend of the tet's four probes, so for every normal each channel lies within the probes' own
// irradiance range (1e-5 relative to the largest |E|: the blend's float rounding).
TEST(ObjectSh, AgreesWithIrradianceWhereVisibilityIgnoresTheNormal) {
  Level level = boxLevel(9);
  level.occlusion = randomPlaneOcclusion(level, 5);
  const ProbeQuery query(level);
  ASSERT_TRUE(query.usesOcclusion());
  const std::vector<glm::vec3> normals = randomNormals(8, 4);
  size_t agreeing = 0, differing = 0, occludedAgreeing = 0;
  for (const glm::dvec3& x : queryPoints(level, 13)) {
    const ShRgb sh = query.interpolatedSh(x);
    ShadeRecord atCentre;
    query.explain(x, glm::vec3(0.0f), atCentre);
    for (const glm::vec3& n : normals) {
      ShadeRecord rec;
      const glm::vec3 direct = query.explain(x, n, rec);
      const glm::vec3 fromSh = shIrradiance(sh, n);
      if (rec.visibility == atCentre.visibility && rec.fallback == 0.0f && atCentre.fallback == 0.0f) {
        ASSERT_TRUE(sameBits(fromSh, direct)) << "x (" << x.x << ", " << x.y << ", " << x.z << "): SH "
                                              << fromSh.x << ", irradiance " << direct.x;
        ++agreeing;
        occludedAgreeing += atCentre.visibility != glm::vec4(1.0f);
      } else {
        ++differing;
      }
      for (int c = 0; c < 3; ++c) {
        float lo = rec.probeIrradiance[0][c], hi = lo, scale = 0.0f;
        for (const glm::vec3& e : rec.probeIrradiance) {
          lo = std::min(lo, e[c]);
          hi = std::max(hi, e[c]);
          scale = std::max(scale, std::abs(e[c]));
        }
        const float tol = 1e-5f * scale;
        ASSERT_GE(fromSh[c], lo - tol) << "x (" << x.x << ", " << x.y << ", " << x.z << ") channel " << c;
        ASSERT_LE(fromSh[c], hi + tol) << "x (" << x.x << ", " << x.y << ", " << x.z << ") channel " << c;
      }
    }
  }
  // Both cases occur, and the agreement covers points that do not see every probe.
  EXPECT_GT(agreeing, 5000u);
  EXPECT_GT(occludedAgreeing, 2000u);
  EXPECT_GT(differing, 1000u);
}

// The per-object cache: a path walked with the tet of the previous step as the hint, and points visited in
// random order (hints from far away), give the cold answer bit for bit, with and without occlusion.
TEST(ObjectSh, CachedHintGivesTheColdAnswer) {
  Level level = boxLevel(10);
  for (const bool occluded : {false, true}) {
    if (occluded) level.occlusion = randomPlaneOcclusion(level, 6);
    const ProbeQuery query(level);
    int32_t cache = -1;
    for (int f = 0; f <= 400; ++f) {  // a diagonal path from outside the hull, through it, out again
      const glm::dvec3 x = kOrigin + glm::dvec3(-2.0, -1.0, -1.5) + glm::dvec3(14.0, 8.0, 11.0) * (f / 400.0);
      ASSERT_TRUE(sameBits(query.interpolatedSh(x, &cache), query.interpolatedSh(x))) << "frame " << f;
      ASSERT_EQ(cache, query.locate(x).tet) << "frame " << f;
    }
    cache = -1;
    for (const glm::dvec3& x : queryPoints(level, 14))
      ASSERT_TRUE(sameBits(query.interpolatedSh(x, &cache), query.interpolatedSh(x)));
  }
}

// A moving object's walk from its cached tet is short: following the lookup's walk rule (step across the face
// opposite the most negative weight, exact weights) from the previous frame's tet, an object moving 5 cm a
// frame through tets about a metre across reaches its new tet in a step or two, far within the hint walk's
// budget (kLookupMaxHintSteps), after which the located tet is the one the walk reached.
TEST(ObjectSh, MovingObjectsHintWalkTakesFewSteps) {
  const Level level = boxLevel(15);
  const ProbeQuery query(level);
  int32_t cache = -1;
  int maxSteps = 0, totalSteps = 0, frames = 0;
  for (int f = 0; f <= 200; ++f) {  // 10 m inside the hull, 5 cm a frame
    const glm::dvec3 x = kOrigin + glm::dvec3(0.5, 0.7, 0.6) + glm::dvec3(9.0, 4.4, 6.6) * (f / 200.0);
    const glm::dvec3 local = x - kOrigin;
    if (cache >= 0) {
      int32_t cur = cache, steps = 0;
      for (; steps <= kLookupMaxHintSteps; ++steps) {
        double w[4];
        test::exactTetWeights(level, level.tets[size_t(cur)], local, w);
        const int m = int(std::min_element(w, w + 4) - w);
        if (w[m] >= -kLookupInsideEps) break;
        cur = level.tets[size_t(cur)].n[m];
        ASSERT_GE(cur, 0) << "left the hull at frame " << f;
      }
      maxSteps = std::max(maxSteps, steps);
      totalSteps += steps;
      ++frames;
    }
    query.interpolatedSh(x, &cache);
    ASSERT_GE(cache, 0);
  }
  EXPECT_LE(maxSteps, 3);
  EXPECT_LT(double(totalSteps) / frames, 0.5);
}

}  // namespace
}  // namespace tetraprobe
