// The lookup's one shading function (runtime/shade.h) serves the runtime, `query --explain` and the bake's
// occlusion-hole finder: the explain record answers as irradiance() does, bit for bit, at surface and volume
// points inside and outside the hull, through the face blend and the all-occluded fallback; the record agrees
// with the occlusion primitives it is made of; the hole finder's counts are the records' fallbacks.
#include <cstdio>
#include <cstring>
#include <random>
#include <vector>

#include <gtest/gtest.h>

#include "test_levels.h"
#include "tetraprobe/bake/bake.h"
#include "tetraprobe/occlusion/build_occlusion.h"
#include "tetraprobe/occlusion/occlusion_holes.h"
#include "tetraprobe/runtime/face_blend.h"
#include "tetraprobe/runtime/occlusion.h"
#include "tetraprobe/runtime/query.h"
#include "tetraprobe/runtime/shade.h"

namespace tetraprobe {
namespace {

bool sameBits(const glm::vec3& a, const glm::vec3& b) {
  return std::memcmp(&a, &b, sizeof a) == 0;
}

// A room (inward box, -2..2) on a 0.7 m probe lattice with a closet in its middle: a thin-walled box between
// the lattice's probes with none inside, so the points on its inner walls see none of their tet's probes (the
// fallback), and the points near its outer walls are where tets' data disagree (the face blend). Random SH,
// occlusion built from the scene, the level's frame away from the world origin.
struct ClosetRoom {
  Scene scene = test::emptyScene();
  Level level;
  ClosetRoom() {
    test::addBox(scene, {-2, 0, -2}, {2, 2.5f, 2}, /*inward=*/true);
    test::addBox(scene, {-0.25f, 0.4f, -0.25f}, {0.25f, 1.1f, 0.25f});  // the closet's outside
    test::addBox(scene, {-0.24f, 0.41f, -0.24f}, {0.24f, 1.09f, 0.24f}, /*inward=*/true);  // and inside
    std::vector<glm::dvec3> probes;
    for (double z : {-1.7, -1.0, -0.3, 0.3, 1.0, 1.7})
      for (double y : {0.3, 1.2, 2.2})
        for (double x : {-1.7, -1.0, -0.3, 0.3, 1.0, 1.7}) probes.push_back({x, y, z});
    level = test::makeLevel(probes, glm::dvec3(3.0, -1.0, 2.0));
    std::mt19937_64 rng(7);
    std::uniform_real_distribution<float> u(-0.3f, 0.3f);
    for (ShRgb& s : level.sh) {
      for (glm::vec3& c : s.c) c = glm::vec3(u(rng), u(rng), u(rng));
      s.c[0] += glm::vec3(1.0f, 0.8f, 0.6f);
    }
    const SceneTracer tracer(scene);
    OcclusionOptions o;
    o.progress = false;
    level.occlusion = buildOcclusion(tracer, level, o);
  }
};

// Surface points of the scene (their normals) and volume points (zero normal) over a box larger than the
// probes' hull, so some lie outside it.
void queryPoints(const SceneTracer& tracer, std::vector<glm::dvec3>& world, std::vector<glm::vec3>& normal) {
  for (const SurfacePoint& p : sampleSurfacePoints(tracer, 3000, 11)) {
    world.push_back(p.position);
    normal.push_back(p.normal);
  }
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> u(-2.4, 2.4);
  for (int i = 0; i < 1000; ++i) {
    world.emplace_back(u(rng), 1.25 + 0.5 * u(rng), u(rng));
    normal.emplace_back(0.0f);
  }
}

TEST(Shade, ExplainAnswersAsIrradianceBitForBit) {
  const ClosetRoom room;
  ASSERT_FALSE(room.level.occlusion.empty());
  const SceneTracer tracer(room.scene);
  std::vector<glm::dvec3> world;
  std::vector<glm::vec3> normal;
  queryPoints(tracer, world, normal);
  ProbeQuery query(room.level);
  for (const bool occlusion : {true, false}) {
    query.setUseOcclusion(occlusion);
    std::vector<glm::vec3> batch(world.size());
    query.irradianceBatch(world.data(), normal.data(), batch.data(), world.size(), 2);
    size_t fallback = 0, ownFallback = 0, partial = 0, blended = 0, outside = 0;
    for (size_t i = 0; i < world.size(); ++i) {
      ShadeRecord r;
      const glm::vec3 e = query.irradiance(world[i], normal[i]);
      const glm::vec3 a = query.explain(world[i], normal[i], r);
      const glm::dvec3& p = world[i];
      ASSERT_TRUE(sameBits(a, e) && sameBits(r.answer, e) && sameBits(batch[i], e))
          << "point " << i << " (" << p.x << ", " << p.y << ", " << p.z << "): explain " << a.x << " record "
          << r.answer.x << " batch " << batch[i].x << " irradiance " << e.x;
      ASSERT_EQ(r.occlusion, occlusion);
      fallback += r.fallback >= 1.0f;
      ownFallback += r.ownFallback >= 1.0f;
      partial += r.fallback > 0.0f && r.fallback < 1.0f;
      blended += r.visibility != r.ownVisibility;
      outside += r.location.outerCell >= 0;
      if (!occlusion) {
        EXPECT_EQ(r.weights, r.location.weights);
        EXPECT_EQ(r.fallback, 0.0f);
      }
    }
    std::printf(
        "[closet room, occlusion %s] %zu points: %zu all-occluded (%zu by the tet's own data), %zu partly, "
        "%zu face-blended, %zu outside the hull\n",
        occlusion ? "on" : "off", world.size(), fallback, ownFallback, partial, blended, outside);
    EXPECT_GT(outside, 0u);  // the cases are covered (points whose own data sees nothing: the blend
    if (occlusion) {         // takes what their neighbours see, so few or none fall back after it)
      EXPECT_GT(ownFallback, 0u);
      EXPECT_GT(blended, 0u);
    }
  }
}

// The probe flags (faceBlendMask, packed into the GPU's occlusion record) never skip a probe whose blend
// would change the answer: at random points in every tet (weights drawn towards the faces, edges and corners,
// where the blend acts; many more in tets with data nearby) with random and zero normals, the blend of the
// flagged probes equals the blend of every probe bit for bit, on the closet room built with each occlusion
// mode (auto, planes only, shadow maps only). A probe no tet of the level can hide is never flagged.
TEST(FaceBlend, FlagNeverSkipsAProbeWhoseBlendWouldChangeTheAnswer) {
  for (const OcclusionMode mode :
       {OcclusionMode::kAuto, OcclusionMode::kPlanes, OcclusionMode::kShadowMaps}) {
    ClosetRoom room;
    {
      const SceneTracer tracer(room.scene);
      OcclusionOptions o;
      o.progress = false;
      o.mode = mode;
      room.level.occlusion = buildOcclusion(tracer, room.level, o);
    }
    const Level& level = room.level;
    const LevelOcclusion& occ = level.occlusion;
    ASSERT_FALSE(occ.empty());
    // Which probes some tet's data may hide, by the long way: every tet, every slot.
    std::vector<char> hidable(level.probes.size(), 0);
    for (size_t t = 0; t < level.tets.size(); ++t) {
      if (occ.tets[t].kind() == kOcclusionNone) continue;
      for (int i = 0; i < 4; ++i) hidable[size_t(level.tets[t].v[i])] = 1;
    }
    std::mt19937_64 rng(17);
    std::uniform_real_distribution<float> u(0.0f, 1.0f);
    std::normal_distribution<float> g(0.0f, 1.0f);
    size_t points = 0, changed = 0, flags = 0, slots = 0;
    for (size_t t = 0; t < level.tets.size(); ++t) {
      const Tet& tet = level.tets[t];
      const BaryFrame frame = baryFrame(tet, level.probes);
      const uint32_t mask = faceBlendMask(level, occ, int32_t(t));
      for (int i = 0; i < 4; ++i) {
        slots += 1;
        flags += (mask >> i) & 1u;
        // A probe no tet with data holds is never flagged.
        if (!hidable[size_t(tet.v[i])]) {
          EXPECT_EQ((mask >> i) & 1u, 0u) << "tet " << t << " slot " << i;
        }
      }
      bool nearData = occ.tets[t].kind() != kOcclusionNone;
      for (int k = 0; k < 4; ++k)
        nearData = nearData || (tet.n[k] >= 0 && occ.tets[size_t(tet.n[k])].kind() != kOcclusionNone);
      for (int s = 0; s < (nearData ? 400 : 20); ++s) {
        glm::vec4 w;
        for (int i = 0; i < 4; ++i) w[i] = std::pow(u(rng), 3.0f);  // many near a face, edge or corner
        w /= w.x + w.y + w.z + w.w;
        glm::vec3 x(0.0f);
        for (int i = 0; i < 4; ++i) x += w[i] * level.probes[size_t(tet.v[i])];
        glm::vec3 n = s % 4 == 0 ? glm::vec3(0.0f) : glm::normalize(glm::vec3(g(rng), g(rng), g(rng)));
        const glm::vec4 own = occlusionVisibility(level, occ, int32_t(t), frame, x, n);
        const glm::vec4 flagged =
            faceBlendVisibility(level, occ, int32_t(t), w, own, x, n, kFaceBlendFlaggedProbes);
        const glm::vec4 every =
            faceBlendVisibility(level, occ, int32_t(t), w, own, x, n, kFaceBlendEveryProbe);
        ASSERT_EQ(std::memcmp(&flagged, &every, sizeof flagged), 0)
            << "tet " << t << " point " << s << ": flagged " << flagged.x << " " << flagged.y << " "
            << flagged.z << " " << flagged.w << ", every probe " << every.x << " " << every.y << " "
            << every.z << " " << every.w;
        changed += flagged != own;
        ++points;
      }
    }
    std::printf("[closet room, mode %d] %zu points, %zu blended; %zu of %zu probe slots flagged\n", int(mode),
                points, changed, flags, slots);
    EXPECT_GT(changed, 1000u);  // the blend acts on these points
    EXPECT_LT(flags, slots);    // and the flags skip some
  }
}

// The record is what the documented rule makes of the occlusion primitives (occlusion.h, face_blend.h),
// computed here the long way: own visibility, the face blend, the occluded weights and both fallback shares,
// the answer (the plain blend of the occluded weights, or occludedIrradianceAt where the fallback runs), and
// the fallback's probe (the largest fallbackLean).
TEST(Shade, RecordIsTheOcclusionRuleTakenStepByStep) {
  const ClosetRoom room;
  const Level& level = room.level;
  const SceneTracer tracer(room.scene);
  std::vector<glm::dvec3> world;
  std::vector<glm::vec3> normal;
  queryPoints(tracer, world, normal);
  const ProbeQuery query(level);
  for (size_t i = 0; i < world.size(); ++i) {
    ShadeRecord r;
    query.explain(world[i], normal[i], r);
    const Location loc = query.locate(world[i]);
    ASSERT_EQ(r.location.tet, loc.tet);
    ASSERT_EQ(r.location.weights, loc.weights);
    const Tet& t = level.tets[size_t(loc.tet)];
    const glm::vec3 local(world[i] - level.origin), n = normal[i];
    const glm::vec4 own = occlusionVisibility(level, level.occlusion, loc.tet, local, n);
    const glm::vec4 vis = lookupVisibility(level, level.occlusion, loc, own, local, n);
    float fallback = 0.0f, ownFallback = 0.0f;
    const glm::vec4 w = applyOcclusion(loc.weights, vis, &fallback);
    applyOcclusion(loc.weights, own, &ownFallback);
    EXPECT_EQ(r.ownVisibility, own) << "point " << i;
    EXPECT_EQ(r.visibility, vis) << "point " << i;
    EXPECT_EQ(r.weights, w) << "point " << i;
    EXPECT_EQ(r.fallback, fallback) << "point " << i;
    EXPECT_EQ(r.ownFallback, ownFallback) << "point " << i;
    const ShRgb* sh[4];
    glm::vec3 toProbe[4];
    for (int k = 0; k < 4; ++k) {
      sh[k] = &level.sh[size_t(t.v[k])];
      toProbe[k] = level.probes[size_t(t.v[k])] - local;
      EXPECT_EQ(r.probeIrradiance[k], shIrradiance(*sh[k], n));
    }
    const float wf[4] = {w.x, w.y, w.z, w.w};
    const glm::vec3 answer = fallback > 0.0f
                                 ? occludedIrradianceAt(level, loc.tet, loc.weights, vis, local, n)
                                 : shIrradiance(shBlend(sh, wf, 4), n);
    EXPECT_TRUE(sameBits(r.answer, answer)) << "point " << i << ": " << r.answer.x << " vs " << answer.x;
    const glm::vec4 u = applyOcclusion(loc.weights, glm::vec4(1.0f));
    EXPECT_EQ(r.unoccluded, u);
    EXPECT_EQ(r.front, probeFront(toProbe, n));
    const glm::vec4 lean = fallbackLean(u, r.front);
    ASSERT_GE(r.fallbackProbe, 0);
    for (int k = 0; k < 4; ++k) EXPECT_LE(lean[k], lean[r.fallbackProbe]) << "point " << i;
    const float uf[4] = {u.x, u.y, u.z, u.w};
    EXPECT_EQ(r.unoccludedIrradiance, shIrradiance(shBlend(sh, uf, 4), n));
  }
}

// The hole finder counts with the lookup's shading: its hole points are the surface points whose record has
// an own-data fallback (with lookupOnly, an answer that falls back), its lookup-fallback points those whose
// answer falls back (after the blend over the stars), and occlusionFallbackShare is the record's own-data share.
TEST(OcclusionHoles, CountsAreTheShadeRecordsFallbacks) {
  const ClosetRoom room;
  const SceneTracer tracer(room.scene);
  OcclusionHoleOptions options;
  options.spacing = 0.7;
  options.minPoints = options.maxPoints = 2000;
  options.propose = false;
  const OcclusionHoles holes = findOcclusionHoles(tracer, room.level, options);
  ASSERT_EQ(holes.pointsChecked, 2000u);
  const ProbeQuery query(room.level);
  size_t own = 0, lookup = 0;
  for (const SurfacePoint& p : sampleSurfacePoints(tracer, 2000, options.seed)) {
    ShadeRecord r;
    query.explain(p.position, p.normal, r);
    own += r.ownFallback > 0.0f;
    lookup += r.fallback > 0.0f;
    EXPECT_EQ(occlusionFallbackShare(room.level, query, p.position, p.normal), r.ownFallback);
  }
  std::printf("[closet room] holes: %zu of %zu points by the tets' data, %zu by the lookup\n",
              holes.holePoints, holes.pointsChecked, holes.lookupFallbackPoints);
  EXPECT_GT(own, 0u);
  EXPECT_EQ(holes.holePoints, own);
  EXPECT_EQ(holes.lookupFallbackPoints, lookup);
  // The round aimed at the lookup (the bake's --lookup-holes) judges a hole by the answer, not the data.
  options.lookupOnly = true;
  const OcclusionHoles byLookup = findOcclusionHoles(tracer, room.level, options);
  EXPECT_EQ(byLookup.holePoints, lookup);
  EXPECT_EQ(byLookup.lookupFallbackPoints, lookup);
  EXPECT_LT(lookup, own);
}

// The hole finder checks a number of points proportional to the level's surface, with no upper bound by
// default: twice the density gives twice the points, past the 50,000 the finder once stopped at (a town of
// sixteen houses was checked as sparsely as 3,000 square metres).
TEST(OcclusionHoles, PointCountGrowsWithTheSurfaceWithoutACap) {
  const ClosetRoom room;
  const SceneTracer tracer(room.scene);
  OcclusionHoleOptions options;
  options.spacing = 0.7;
  options.propose = false;
  options.minPoints = 1;  // the surface alone decides
  options.pointsPerSquareMetre = 1.0;
  const size_t small = findOcclusionHoles(tracer, room.level, options).pointsChecked;
  ASSERT_GT(small, 0u);
  // The density that asks for about 60,000 points, then twice that.
  options.pointsPerSquareMetre = 60000.0 / double(small);
  const size_t large = findOcclusionHoles(tracer, room.level, options).pointsChecked;
  options.pointsPerSquareMetre *= 2.0;
  const size_t twice = findOcclusionHoles(tracer, room.level, options).pointsChecked;
  EXPECT_GT(large, 50000u);
  EXPECT_NEAR(double(twice) / double(large), 2.0, 0.01);
  // An explicit cap still holds.
  options.maxPoints = 30000;
  EXPECT_EQ(findOcclusionHoles(tracer, room.level, options).pointsChecked, 30000u);
}

// No tet (an empty level): the answer is 0 and the record keeps its defaults.
TEST(Shade, NoTetAnswersZero) {
  const Level level;
  ShadeRecord r;
  r.fallback = 0.5f;
  const Location none;
  EXPECT_EQ(shadeLocated(level, &level.occlusion, none, glm::dvec3(1.0), glm::vec3(0, 1, 0), &r),
            glm::vec3(0.0f));
  EXPECT_EQ(r.location.tet, -1);
  EXPECT_EQ(r.fallback, 0.0f);
  EXPECT_EQ(r.fallbackProbe, -1);
  EXPECT_EQ(r.answer, glm::vec3(0.0f));
}

}  // namespace
}  // namespace tetraprobe
