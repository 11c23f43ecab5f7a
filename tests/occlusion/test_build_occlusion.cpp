// buildOcclusion on hand-built walls with known answers: the chosen kind per tet, and visibility answers
// cross-checked against rays at points on both sides.
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <random>
#include <string>

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>

#include "missing_capability.h"
#include "test_levels.h"
#include "tetraprobe/bake/bake.h"
#include "tetraprobe/common/error.h"
#include "tetraprobe/occlusion/build_occlusion.h"
#include "tetraprobe/runtime/query.h"
#include "tetraprobe/scene/load.h"
#include "tetraprobe/tetra/placement.h"

namespace tetraprobe {
namespace {

OcclusionOptions quiet(OcclusionMode mode = OcclusionMode::kAuto) {
  OcclusionOptions o;
  o.mode = mode;
  o.progress = false;
  return o;
}

void printStats(const char* name, const OcclusionStats& s) {
  std::printf(
      "[%s] tets %zu, with geometry %zu: none %zu, planes %zu (1:%zu 2:%zu 3:%zu), shadow maps %zu; %zu "
      "bytes; "
      "agreement %.4f (surface %.4f; %llu answers, %llu leaking; %zu tets below minAgreement); %llu rays, "
      "%.3f s\n",
      name, s.tets, s.tetsWithGeometry, s.none, s.planeTets, s.planeTetsByCount[1], s.planeTetsByCount[2],
      s.planeTetsByCount[3], s.shadowMapTets, s.bytes, s.agreement, s.surfaceAgreement,
      (unsigned long long)s.answers, (unsigned long long)s.leaking, s.belowMinAgreement,
      (unsigned long long)s.rays, s.seconds);
}

// Visibility of the single tet's probes 0..3 (by probe index, not tet slot) from x with normal n.
glm::vec4 probeVisibility(const Level& level, const LevelOcclusion& occ, glm::vec3 x, glm::vec3 n) {
  const glm::vec4 v = occlusionVisibility(level, occ, 0, x, n);
  glm::vec4 out;
  for (int i = 0; i < 4; ++i) out[level.tets[0].v[i]] = v[i];
  return out;
}

// Held-out check in a single-tet level at the world origin: fraction of (point, probe) answers that agree
// with rays, over uniformly random points inside the tet (no normal), independent of the build's samples.
double volumeAgreement(const SceneTracer& tracer, const Level& level, const LevelOcclusion& occ, int points,
                       unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  int agree = 0, total = 0;
  for (int k = 0; k < points; ++k) {
    double w[4], sum = 0.0;
    for (double& x : w) sum += (x = -std::log(1.0 - u(rng)));
    glm::dvec3 x(0.0);
    for (int i = 0; i < 4; ++i) x += (w[i] / sum) * glm::dvec3(level.probes[size_t(i)]);
    const glm::vec4 v = probeVisibility(level, occ, glm::vec3(x), glm::vec3(0.0f));
    for (int i = 0; i < 4; ++i) {
      const bool ray = test::rayVisible(tracer, glm::vec3(x), glm::vec3(0.0f), level.probes[size_t(i)]);
      agree += (v[i] > 0.5f) == ray;
      ++total;
    }
  }
  return double(agree) / double(total);
}

// Held-out check at real shading points (bake's sampleSurfacePoints, normals into open space, inside the
// probe hull): fraction of (point, probe) answers agreeing with rays, and the mean interpolation weight that
// lands on probes the rays say are hidden, without and with occlusion.
struct SurfaceCheck {
  int points = 0;
  double agreement = 0.0, hiddenWeightBefore = 0.0, hiddenWeightAfter = 0.0;
};
SurfaceCheck surfaceCheck(const SceneTracer& tracer, const Level& level, const LevelOcclusion& occ,
                          int count) {
  const ProbeQuery query(level);
  SurfaceCheck c;
  long agree = 0, total = 0;
  for (const SurfacePoint& sp : sampleSurfacePoints(tracer, count, 0x0cc1u)) {
    const Location loc = query.locate(sp.position);
    if (!loc.inside) continue;
    const glm::vec3 x(sp.position);
    const glm::vec4 vis = occlusionVisibility(level, occ, loc.tet, x, sp.normal);
    const glm::vec4 w = applyOcclusion(loc.weights, vis);
    for (int i = 0; i < 4; ++i) {
      const bool ray =
          test::rayVisible(tracer, x, sp.normal, level.probes[size_t(level.tets[size_t(loc.tet)].v[i])]);
      agree += (vis[i] > 0.5f) == ray;
      ++total;
      if (!ray) {
        c.hiddenWeightBefore += loc.weights[i];
        c.hiddenWeightAfter += w[i];
      }
    }
    ++c.points;
  }
  if (c.points > 0) {
    c.agreement = double(agree) / double(total);
    c.hiddenWeightBefore /= c.points;
    c.hiddenWeightAfter /= c.points;
  }
  return c;
}

// No geometry in any tet: nothing stored at all, zero bytes, every probe visible.
TEST(Occlusion, NoGeometryStoresNothing) {
  Scene s = test::emptyScene();
  test::addAxisQuad(s, 1, -5.0f, {-1, -1}, {1, 1});  // far below the tet
  const SceneTracer tracer(s);
  const Level level = test::makeLevel(test::regularTet());
  OcclusionStats st;
  const LevelOcclusion occ = buildOcclusion(tracer, level, quiet(), &st);
  printStats("no geometry", st);
  EXPECT_TRUE(occ.empty());
  EXPECT_EQ(occ.bytes(), 0u);
  EXPECT_EQ(st.bytes, 0u);
  EXPECT_EQ(st.none, 1u);
  EXPECT_EQ(st.tetsWithGeometry, 0u);
  EXPECT_EQ(st.rays, 0u);
  EXPECT_EQ(probeVisibility(level, occ, glm::vec3(0.5f), glm::vec3(0.0f)), glm::vec4(1.0f));
}

// A wall z = 0.5 through the middle: one plane; from either side only the probes on that side are visible,
// and a point on the wall sees the probes its face looks at (the bias keeps it from shadowing itself).
TEST(Occlusion, SinglePlaneSplitsTheTet) {
  Scene s = test::emptyScene();
  test::addAxisQuad(s, 2, 0.5f, {-1, -1}, {2, 2});
  const SceneTracer tracer(s);
  const Level level = test::makeLevel(test::regularTet());
  OcclusionStats st;
  const LevelOcclusion occ = buildOcclusion(tracer, level, quiet(), &st);
  printStats("single plane", st);
  ASSERT_EQ(occ.tets.size(), 1u);
  EXPECT_EQ(occ.tets[0].kind(), kOcclusionPlanes);
  EXPECT_EQ(occ.tets[0].planeCount(), 1u);
  EXPECT_EQ(st.bytes, 8u + 8u);  // the tet's record and one snorm16 plane
  EXPECT_GE(st.agreement, 0.99);
  // Probes 0, 1 at z = 0; 2, 3 at z = 1.
  const glm::vec4 below(1, 1, 0, 0), above(0, 0, 1, 1);
  EXPECT_EQ(probeVisibility(level, occ, {0.5f, 0.5f, 0.3f}, glm::vec3(0.0f)), below);
  EXPECT_EQ(probeVisibility(level, occ, {0.5f, 0.5f, 0.7f}, glm::vec3(0.0f)), above);
  EXPECT_EQ(probeVisibility(level, occ, {0.5f, 0.5f, 0.5f}, {0, 0, -1}), below);
  EXPECT_EQ(probeVisibility(level, occ, {0.5f, 0.5f, 0.5f}, {0, 0, 1}), above);
  EXPECT_EQ(probeVisibility(level, occ, {0.4f, 0.55f, 0.5f}, {0, 0, 1}), above);
  EXPECT_GE(volumeAgreement(tracer, level, occ, 400, 1), 0.98);
}

// A dilated probe (visibilitySource) is seen wherever the probe whose SH it carries is: with probes 2 and 3
// (above the wall) carrying probe 0's and 1's SH, points below see all four; without sources, only 0 and 1.
TEST(Occlusion, DilatedProbesAreSeenWhereTheirSourceIs) {
  Scene s = test::emptyScene();
  test::addAxisQuad(s, 2, 0.5f, {-1, -1}, {2, 2});
  const SceneTracer tracer(s);
  const Level level = test::makeLevel(test::regularTet());
  OcclusionOptions o = quiet();
  o.visibilitySource = {0, 1, 0, 1};
  OcclusionStats st;
  const LevelOcclusion occ = buildOcclusion(tracer, level, o, &st);
  printStats("dilated sources", st);
  // Below the wall every probe's source is visible: nothing to store. Above it, probes 0 and 1 (and so
  // also 2 and 3) are hidden from the volume; the data must say so where it matters, below.
  const glm::vec4 below =
      occ.empty() ? glm::vec4(1.0f) : probeVisibility(level, occ, {0.5f, 0.5f, 0.3f}, glm::vec3(0.0f));
  EXPECT_EQ(below, glm::vec4(1.0f));
  const glm::vec4 onWall =
      occ.empty() ? glm::vec4(1.0f) : probeVisibility(level, occ, {0.5f, 0.5f, 0.5f}, {0, 0, -1});
  EXPECT_EQ(onWall, glm::vec4(1.0f));
  const LevelOcclusion plain = buildOcclusion(tracer, level, quiet(), nullptr);
  EXPECT_EQ(probeVisibility(level, plain, {0.5f, 0.5f, 0.3f}, glm::vec3(0.0f)), glm::vec4(1, 1, 0, 0));
  o.visibilitySource = {0, 1, 2};
  EXPECT_THROW(buildOcclusion(tracer, level, o, nullptr), InputError);
  o.visibilitySource = {0, 1, 2, 4};
  EXPECT_THROW(buildOcclusion(tracer, level, o, nullptr), InputError);
}

// The same wall far from the world origin: the build traces in world space, the data and the lookup live in
// the level's local frame (world = origin + local), and the answers are the same.
TEST(Occlusion, LocalFrameAwayFromTheOrigin) {
  const glm::dvec3 origin(4096.0, -128.0, 2048.0);
  Scene s = test::emptyScene();
  test::addAxisQuad(s, 2, float(origin.z) + 0.5f, {float(origin.x) - 1, float(origin.y) - 1},
                    {float(origin.x) + 2, float(origin.y) + 2});
  const SceneTracer tracer(s);
  std::vector<glm::dvec3> probes = test::regularTet();
  for (glm::dvec3& p : probes) p += origin;
  const Level level = test::makeLevel(probes, origin);
  OcclusionStats st;
  const LevelOcclusion occ = buildOcclusion(tracer, level, quiet(), &st);
  ASSERT_EQ(occ.tets.size(), 1u);
  EXPECT_EQ(occ.tets[0].kind(), kOcclusionPlanes);
  EXPECT_GE(st.agreement, 0.99);
  EXPECT_EQ(probeVisibility(level, occ, {0.5f, 0.5f, 0.3f}, glm::vec3(0.0f)), glm::vec4(1, 1, 0, 0));
  EXPECT_EQ(probeVisibility(level, occ, {0.5f, 0.5f, 0.7f}, glm::vec3(0.0f)), glm::vec4(0, 0, 1, 1));
  EXPECT_EQ(probeVisibility(level, occ, {0.5f, 0.5f, 0.5f}, {0, 0, 1}), glm::vec4(0, 0, 1, 1));
}

// Forcing shadow maps on the same wall: 64 bytes of texels, and the answers still follow the wall.
TEST(Occlusion, ForcedShadowMapsFollowTheWall) {
  Scene s = test::emptyScene();
  test::addAxisQuad(s, 2, 0.5f, {-1, -1}, {2, 2});
  const SceneTracer tracer(s);
  const Level level = test::makeLevel(test::regularTet());
  OcclusionStats st;
  const LevelOcclusion occ = buildOcclusion(tracer, level, quiet(OcclusionMode::kShadowMaps), &st);
  printStats("single plane, shadow maps", st);
  ASSERT_EQ(occ.tets.size(), 1u);
  EXPECT_EQ(occ.tets[0].kind(), kOcclusionShadowMaps);
  EXPECT_EQ(occ.shadowMaps.size(), 64u);
  EXPECT_EQ(st.bytes, 8u + 64u);
  EXPECT_GE(st.agreement, 0.95);
  EXPECT_EQ(probeVisibility(level, occ, {0.5f, 0.5f, 0.3f}, glm::vec3(0.0f)), glm::vec4(1, 1, 0, 0));
  EXPECT_EQ(probeVisibility(level, occ, {0.5f, 0.5f, 0.7f}, glm::vec3(0.0f)), glm::vec4(0, 0, 1, 1));
  EXPECT_EQ(probeVisibility(level, occ, {0.5f, 0.5f, 0.5f}, {0, 0, -1}), glm::vec4(1, 1, 0, 0));
  EXPECT_EQ(probeVisibility(level, occ, {0.5f, 0.5f, 0.5f}, {0, 0, 1}), glm::vec4(0, 0, 1, 1));
  EXPECT_GE(volumeAgreement(tracer, level, occ, 400, 2), 0.95);
}

// Mode none stores nothing even where a wall cuts the tet (the comparison baseline).
TEST(Occlusion, ModeNoneStoresNothing) {
  Scene s = test::emptyScene();
  test::addAxisQuad(s, 2, 0.5f, {-1, -1}, {2, 2});
  const SceneTracer tracer(s);
  const Level level = test::makeLevel(test::regularTet());
  OcclusionStats st;
  const LevelOcclusion occ = buildOcclusion(tracer, level, quiet(OcclusionMode::kNone), &st);
  EXPECT_TRUE(occ.empty());
  EXPECT_EQ(st.none, 1u);
}

// An L-shaped corner (x = 0.5 for y >= 0.5, y = 0.5 for x >= 0.5) encloses probe 1 = (1,1,0): one plane
// cannot say it, two planes with per-cell masks (or shadow maps) can.
TEST(Occlusion, LShapedCornerNeedsTwoPlanesOrShadowMaps) {
  Scene s = test::emptyScene();
  test::addAxisQuad(s, 0, 0.5f, {0.5f, -1}, {2, 2});  // plane x = 0.5: (y, z) in [0.5,2] x [-1,2]
  test::addAxisQuad(s, 1, 0.5f, {-1, 0.5f}, {2, 2});  // plane y = 0.5: (z, x) in [-1,2] x [0.5,2]
  const SceneTracer tracer(s);
  const Level level = test::makeLevel(test::regularTet());
  OcclusionStats st;
  const LevelOcclusion occ = buildOcclusion(tracer, level, quiet(), &st);
  printStats("L corner", st);
  ASSERT_EQ(occ.tets.size(), 1u);
  const TetOcclusion rec = occ.tets[0];
  EXPECT_TRUE((rec.kind() == kOcclusionPlanes && rec.planeCount() >= 2) || rec.kind() == kOcclusionShadowMaps)
      << "kind " << rec.kind() << " planes " << rec.planeCount();
  EXPECT_GE(st.agreement, 0.95);
  // Inside the corner only probe 1 is visible; outside it, probe 1 is not.
  const glm::vec4 in = probeVisibility(level, occ, {0.75f, 0.65f, 0.3f}, glm::vec3(0.0f));
  EXPECT_EQ(in, glm::vec4(0, 1, 0, 0));
  const glm::vec4 out = probeVisibility(level, occ, {0.3f, 0.3f, 0.4f}, glm::vec3(0.0f));
  EXPECT_EQ(out.y, 0.0f);
  EXPECT_EQ(out.x, 1.0f);
  EXPECT_GE(volumeAgreement(tracer, level, occ, 400, 3), 0.9);
}

// A closed slab 0.45 <= z <= 0.55 through the tet: a two-sided wall. Each side sees its own probes only,
// including points on either face of the slab.
TEST(Occlusion, ThinSlabIsTwoSided) {
  Scene s = test::emptyScene();
  test::addBox(s, {-1, -1, 0.45f}, {2, 2, 0.55f});
  const SceneTracer tracer(s);
  const Level level = test::makeLevel(test::regularTet());
  OcclusionStats st;
  const LevelOcclusion occ = buildOcclusion(tracer, level, quiet(), &st);
  printStats("thin slab", st);
  ASSERT_EQ(occ.tets.size(), 1u);
  EXPECT_EQ(occ.tets[0].kind(), kOcclusionPlanes);
  EXPECT_GE(st.agreement, 0.95);
  EXPECT_EQ(probeVisibility(level, occ, {0.5f, 0.5f, 0.3f}, glm::vec3(0.0f)), glm::vec4(1, 1, 0, 0));
  EXPECT_EQ(probeVisibility(level, occ, {0.5f, 0.5f, 0.7f}, glm::vec3(0.0f)), glm::vec4(0, 0, 1, 1));
  EXPECT_EQ(probeVisibility(level, occ, {0.5f, 0.5f, 0.45f}, {0, 0, -1}), glm::vec4(1, 1, 0, 0));
  EXPECT_EQ(probeVisibility(level, occ, {0.5f, 0.5f, 0.55f}, {0, 0, 1}), glm::vec4(0, 0, 1, 1));
}

// Geometry touching the tet only at a vertex cuts nothing inside it: nothing stored, everything visible.
TEST(Occlusion, GeometryTouchingAVertexOccludesNothing) {
  Scene s = test::emptyScene();
  test::addTriangle(s, {0, 0, 0}, {-1, -0.2f, -0.3f}, {-0.3f, -1, -0.5f});  // all of it in x, y, z <= 0
  const SceneTracer tracer(s);
  const Level level = test::makeLevel(test::regularTet());
  OcclusionStats st;
  const LevelOcclusion occ = buildOcclusion(tracer, level, quiet(), &st);
  printStats("vertex touch", st);
  EXPECT_TRUE(occ.empty());
  EXPECT_EQ(st.tetsWithGeometry, 0u);
  EXPECT_EQ(probeVisibility(level, occ, {0.5f, 0.5f, 0.5f}, glm::vec3(0.0f)), glm::vec4(1.0f));
}

// Two rooms split by a wall at x = 0 with a door (z in [1, 1.8], y < 2). Far from the door, points on the
// dark side (x < 0) get no weight from the probes on the lit side (x > 0), which they do without occlusion.
struct TwoRooms {
  Scene scene = test::emptyScene();
  Level level;
  std::vector<bool> lit;  // per probe: x > 0
  TwoRooms() {
    test::addBox(scene, {-2, 0, -2}, {2, 2.5f, 2}, /*inward=*/true);
    test::addAxisQuad(scene, 0, 0.0f, {0, -2}, {2.5f, 1});    // (y, z): z < 1
    test::addAxisQuad(scene, 0, 0.0f, {0, 1.8f}, {2.5f, 2});  // z > 1.8
    test::addAxisQuad(scene, 0, 0.0f, {2, 1}, {2.5f, 1.8f});  // lintel above the door
    std::vector<glm::dvec3> probes;
    for (double z : {-1.7, -1.0, -0.3, 0.4, 1.1, 1.7})
      for (double y : {0.3, 1.2, 2.2})
        for (double x : {-1.7, -1.0, -0.3, 0.3, 1.0, 1.7}) probes.push_back({x, y, z});
    level = test::makeLevel(probes);
    for (const glm::dvec3& p : probes) lit.push_back(p.x > 0.0);
  }
};

TEST(Occlusion, TwoRoomsDarkSideIgnoresLitProbes) {
  const TwoRooms rooms;
  const SceneTracer tracer(rooms.scene);
  OcclusionStats st;
  const LevelOcclusion occ = buildOcclusion(tracer, rooms.level, quiet(), &st);
  printStats("two rooms", st);
  ASSERT_FALSE(occ.empty());
  EXPECT_GE(st.agreement, 0.95);
  const ProbeQuery query(rooms.level);
  double maxLeakBefore = 0.0, maxLeakAfter = 0.0;
  int points = 0;
  auto check = [&](glm::vec3 x, glm::vec3 n) {
    const Location loc = query.locate(glm::dvec3(x));
    ASSERT_GE(loc.tet, 0);
    const glm::vec4 vis = occlusionVisibility(rooms.level, occ, loc.tet, x, n);
    const glm::vec4 w = applyOcclusion(loc.weights, vis);
    double before = 0.0, after = 0.0, sum = 0.0;
    for (int i = 0; i < 4; ++i) {
      ASSERT_TRUE(std::isfinite(w[i]));
      sum += w[i];
      if (rooms.lit[size_t(rooms.level.tets[size_t(loc.tet)].v[i])]) {
        before += loc.weights[i];
        after += w[i];
      }
    }
    EXPECT_NEAR(sum, 1.0, 1e-5);
    EXPECT_LE(after, 0.02) << "x=(" << x.x << "," << x.y << "," << x.z << ") n=(" << n.x << "," << n.y << ","
                           << n.z << ") before " << before;
    maxLeakBefore = std::max(maxLeakBefore, before);
    maxLeakAfter = std::max(maxLeakAfter, after);
    ++points;
  };
  // Dark side, at least 0.8 m from the door: volume points and points on the wall's dark face.
  for (float z = -1.6f; z <= 0.2f; z += 0.15f)
    for (float y = 0.35f; y <= 2.15f; y += 0.15f) {
      check({-0.0f, y, z}, {-1, 0, 0});
      for (float x = -1.6f; x < -0.05f; x += 0.2f) check({x, y, z}, glm::vec3(0.0f));
    }
  std::printf("[two rooms] %d dark-side points: largest lit-probe weight %.3f without occlusion, %.4f with\n",
              points, maxLeakBefore, maxLeakAfter);
  EXPECT_GE(maxLeakBefore, 0.3);  // the case is meaningful: without occlusion, light leaks
}

// Bytes of the occlusion arrays and the stats that describe them, for equality.
bool sameOcclusion(const LevelOcclusion& a, const LevelOcclusion& b) {
  if (a.tets.size() != b.tets.size() || a.planes.size() != b.planes.size() || a.shadowMaps != b.shadowMaps)
    return false;
  // Empty arrays have null data(), which memcmp may not be given (UBSan), whatever the size.
  return (a.tets.empty() ||
          std::memcmp(a.tets.data(), b.tets.data(), a.tets.size() * sizeof(TetOcclusion)) == 0) &&
         (a.planes.empty() ||
          std::memcmp(a.planes.data(), b.planes.data(), a.planes.size() * sizeof(OcclusionPlane)) == 0);
}
bool sameStats(const OcclusionStats& a, const OcclusionStats& b) {
  return a.tets == b.tets && a.tetsWithGeometry == b.tetsWithGeometry && a.none == b.none &&
         a.planeTets == b.planeTets && a.shadowMapTets == b.shadowMapTets && a.planes == b.planes &&
         a.bytes == b.bytes && a.belowMinAgreement == b.belowMinAgreement && a.answers == b.answers &&
         a.agreeing == b.agreeing && a.leaking == b.leaking && a.blackouts == b.blackouts &&
         a.rays == b.rays && a.surfaceAnswers == b.surfaceAnswers && a.surfaceAgreeing == b.surfaceAgreeing;
}

// A level grown by appended probes (what the bake's hole and refinement rounds do) gets the same occlusion
// data and stats, bit for bit, with the cache of the previous call as without it; the tets the new probes
// left alone are reused, the others worked out. A moved probe or other options invalidate the cache.
TEST(OcclusionCache, GrownLevelGetsTheSameDataAsAFreshBuild) {
  const TwoRooms rooms;
  const SceneTracer tracer(rooms.scene);
  std::vector<glm::dvec3> probes;
  for (const glm::vec3& p : rooms.level.probes) probes.push_back(glm::dvec3(p));
  for (int shapes = 0; shapes < 2; ++shapes) {
    OcclusionOptions options = quiet(shapes == 0 ? OcclusionMode::kAuto : OcclusionMode::kShadowMaps);
    OcclusionCache cache;
    OcclusionStats first;
    buildOcclusion(tracer, rooms.level, options, &first, &cache);
    EXPECT_EQ(cache.reused(), 0u);
    EXPECT_EQ(cache.computed(), rooms.level.tets.size());

    std::vector<glm::dvec3> grown = probes;
    for (const glm::dvec3& p : {glm::dvec3(-0.15, 1.0, 1.3), glm::dvec3(0.15, 1.9, -1.4),
                                glm::dvec3(-1.3, 0.6, 0.0), glm::dvec3(1.35, 2.0, 1.45)})
      grown.push_back(p);
    const Level bigger = test::makeLevel(grown);
    OcclusionStats cached, fresh;
    const LevelOcclusion a = buildOcclusion(tracer, bigger, options, &cached, &cache);
    const LevelOcclusion b = buildOcclusion(tracer, bigger, options, &fresh, nullptr);
    EXPECT_TRUE(sameOcclusion(a, b)) << "mode " << shapes;
    EXPECT_TRUE(sameStats(cached, fresh)) << "mode " << shapes;
    EXPECT_GT(cache.reused(), bigger.tets.size() / 2) << "most tets are untouched by four new probes";
    EXPECT_GT(cache.computed(), 0u);
    EXPECT_EQ(cache.reused() + cache.computed(), bigger.tets.size());

    // The same level again: everything reused.
    buildOcclusion(tracer, bigger, options, nullptr, &cache);
    EXPECT_EQ(cache.reused(), bigger.tets.size());

    // A probe moved (not appended): nothing reused, and the answer is the fresh one.
    std::vector<glm::dvec3> moved = grown;
    moved[7].y += 0.05;
    const Level shifted = test::makeLevel(moved);
    OcclusionStats movedStats, movedFresh;
    const LevelOcclusion c = buildOcclusion(tracer, shifted, options, &movedStats, &cache);
    EXPECT_EQ(cache.reused(), 0u);
    EXPECT_TRUE(sameOcclusion(c, buildOcclusion(tracer, shifted, options, &movedFresh, nullptr)));
    EXPECT_TRUE(sameStats(movedStats, movedFresh));

    // Other options: nothing reused.
    OcclusionOptions stricter = options;
    stricter.minAgreement = 0.999;
    buildOcclusion(tracer, shifted, stricter, nullptr, &cache);
    EXPECT_EQ(cache.reused(), 0u);
  }
}

// Near the door, light comes through: points in the doorway on the dark side still see lit probes.
TEST(Occlusion, TwoRoomsDoorLetsLightThrough) {
  const TwoRooms rooms;
  const SceneTracer tracer(rooms.scene);
  const LevelOcclusion occ = buildOcclusion(tracer, rooms.level, quiet(), nullptr);
  const ProbeQuery query(rooms.level);
  const glm::vec3 x(-0.1f, 1.0f, 1.4f);  // in the doorway, just on the dark side
  const Location loc = query.locate(glm::dvec3(x));
  const glm::vec4 w =
      applyOcclusion(loc.weights, occlusionVisibility(rooms.level, occ, loc.tet, x, glm::vec3(0.0f)));
  double lit = 0.0;
  for (int i = 0; i < 4; ++i)
    if (rooms.lit[size_t(rooms.level.tets[size_t(loc.tet)].v[i])]) lit += w[i];
  EXPECT_GT(lit, 0.1);
}

// The arrays are the same for any thread count.
TEST(Occlusion, DeterministicForAnyThreadCount) {
  const TwoRooms rooms;
  const SceneTracer tracer(rooms.scene);
  OcclusionOptions one = quiet(), many = quiet();
  one.threads = 1;
  many.threads = 3;
  const LevelOcclusion a = buildOcclusion(tracer, rooms.level, one),
                       b = buildOcclusion(tracer, rooms.level, many);
  ASSERT_EQ(a.tets.size(), b.tets.size());
  for (size_t t = 0; t < a.tets.size(); ++t) {
    EXPECT_EQ(a.tets[t].header, b.tets[t].header) << "tet " << t;
    EXPECT_EQ(a.tets[t].cells, b.tets[t].cells) << "tet " << t;
  }
  ASSERT_EQ(a.planes.size(), b.planes.size());
  for (size_t p = 0; p < a.planes.size(); ++p)
    for (int i = 0; i < 4; ++i) EXPECT_EQ(a.planes[p].c[i], b.planes[p].c[i]);
  EXPECT_EQ(a.shadowMaps, b.shadowMaps);
}

// Every mode on the two rooms, for the comparison figures (printed): forced planes and shadow maps must also
// stop the leak far from the door in aggregate (agreement), and auto must not be worse than either.
TEST(Occlusion, ModesCompareOnTwoRooms) {
  const TwoRooms rooms;
  const SceneTracer tracer(rooms.scene);
  double agreement[3];
  int k = 0;
  for (OcclusionMode mode : {OcclusionMode::kPlanes, OcclusionMode::kShadowMaps, OcclusionMode::kAuto}) {
    OcclusionStats st;
    buildOcclusion(tracer, rooms.level, quiet(mode), &st);
    printStats((std::string("two rooms, ") + occlusionModeName(mode)).c_str(), st);
    agreement[k++] = st.agreement;
  }
  EXPECT_GE(agreement[2] + 1e-9, std::min(agreement[0], agreement[1]));
}

TEST(Occlusion, RejectsBadOptions) {
  Scene s = test::emptyScene();
  test::addAxisQuad(s, 2, 0.5f, {-1, -1}, {2, 2});
  const SceneTracer tracer(s);
  const Level level = test::makeLevel(test::regularTet());
  OcclusionOptions o = quiet();
  o.minAgreement = 1.5;
  EXPECT_THROW(buildOcclusion(tracer, level, o), InputError);
  o = quiet();
  o.volumeSamples = -1;
  EXPECT_THROW(buildOcclusion(tracer, level, o), InputError);
  OcclusionMode m;
  EXPECT_TRUE(parseOcclusionMode("shadow-maps", m));
  EXPECT_EQ(m, OcclusionMode::kShadowMaps);
  EXPECT_FALSE(parseOcclusionMode("shadowmaps", m));
}

// Figures on a real level (printed; about 4 s): veach_ajar from the shared scenes, or the scene at
// TETRAPROBE_OCCLUSION_SCENE=<scene path> ("1" or unset: veach_ajar), probes on a 1 m grid over the scene
// bounds (TETRAPROBE_OCCLUSION_SPACING overrides) without those inside geometry.
TEST(OcclusionScene, VeachAjarFigures) {
  const char* env = std::getenv("TETRAPROBE_OCCLUSION_SCENE");
  const std::string path = env == nullptr || *env == 0 || std::string(env) == "1"
                               ? std::string(TETRAPROBE_SHARED_SCENES) + "/veach_ajar/veach_ajar.obj"
                               : std::string(env);
  if (!std::filesystem::exists(path)) TETRAPROBE_SKIP_MISSING(path << " not present");
  const Scene scene = loadScene(path);
  const SceneTracer tracer(scene);
  glm::vec3 lo, hi;
  sceneBounds(scene, lo, hi);
  const char* spacing = std::getenv("TETRAPROBE_OCCLUSION_SPACING");  // metres, default 1
  const std::vector<glm::dvec3> grid =
      placeGridProbes(glm::dvec3(lo), glm::dvec3(hi), spacing ? std::atof(spacing) : 1.0);
  const std::vector<uint8_t> inside = probesInsideGeometry(tracer, grid);
  std::vector<glm::dvec3> probes;
  for (size_t i = 0; i < grid.size(); ++i)
    if (!inside[i]) probes.push_back(grid[i]);
  const Level level = test::makeLevel(probes);
  std::printf("[veach_ajar] %zu triangles, %zu grid points, %zu probes, %zu tets\n", scene.triangles.size(),
              grid.size(), probes.size(), level.tets.size());
  for (OcclusionMode mode : {OcclusionMode::kPlanes, OcclusionMode::kShadowMaps, OcclusionMode::kAuto}) {
    OcclusionStats st;
    OcclusionOptions options = quiet(mode);
    if (const char* m = std::getenv("TETRAPROBE_OCCLUSION_MIN_AGREEMENT"))
      options.minAgreement = std::atof(m);
    const LevelOcclusion occ = buildOcclusion(tracer, level, options, &st);
    printStats((std::string("veach_ajar, ") + occlusionModeName(mode)).c_str(), st);
    EXPECT_GT(st.agreement, 0.5);
    const SurfaceCheck c = surfaceCheck(tracer, level, occ, 20000);
    std::printf(
        "[veach_ajar, %s] %d held-out surface points: agreement %.4f, mean weight on hidden probes %.4f "
        "without occlusion, %.4f with\n",
        occlusionModeName(mode), c.points, c.agreement, c.hiddenWeightBefore, c.hiddenWeightAfter);
  }
  OcclusionOptions one = quiet(), all = quiet();
  one.threads = 1;
  const LevelOcclusion a = buildOcclusion(tracer, level, one), b = buildOcclusion(tracer, level, all);
  ASSERT_EQ(a.tets.size(), b.tets.size());
  for (size_t t = 0; t < a.tets.size(); ++t) ASSERT_EQ(a.tets[t].header, b.tets[t].header) << "tet " << t;
  EXPECT_EQ(a.shadowMaps, b.shadowMaps);
}

// ProbeQuery applies the stored occlusion: with the wall z = 0.5 through the tet, a point below it ignores
// the lit probes above (2, 3), inside the hull and outside it (the outer cell's answer takes its hull tet's
// occlusion); with occlusion off the answers are the plain interpolation.
TEST(Occlusion, ProbeQueryIgnoresProbesBehindTheWall) {
  Scene s = test::emptyScene();
  test::addAxisQuad(s, 2, 0.5f, {-1, -1}, {2, 2});
  const SceneTracer tracer(s);
  Level level = test::makeLevel(test::regularTet());
  for (int p = 0; p < 4; ++p) level.sh[size_t(p)] = ShRgb{};
  level.sh[2].c[0] = level.sh[3].c[0] = glm::vec3(1.0f);  // only the probes above the wall are lit
  level.occlusion = buildOcclusion(tracer, level, quiet());
  ASSERT_FALSE(level.occlusion.empty());
  ProbeQuery query(level);
  ASSERT_TRUE(query.usesOcclusion());
  // `outside`: 0.3 m beyond the face (0, 1, 2) (outward normal (1,-1,-1)/sqrt 3) from its centroid, at
  // z = 0.16, below the wall; its outer cell interpolates lit probe 2 unless occlusion hides it.
  const glm::dvec3 below(0.5, 0.5, 0.3), above(0.5, 0.5, 0.7),
      outside(2.0 / 3.0 + 0.3 / std::sqrt(3.0), 1.0 / 3.0 - 0.3 / std::sqrt(3.0),
              1.0 / 3.0 - 0.3 / std::sqrt(3.0));
  const glm::vec3 up(0, 0, 1), down(0, 0, -1);
  EXPECT_EQ(query.irradiance(below, down), glm::vec3(0.0f));  // behind the wall: the far probes drop out
  EXPECT_EQ(query.irradiance(below, up), glm::vec3(0.0f));
  EXPECT_GT(query.irradiance(above, up).x, 0.0f);
  EXPECT_EQ(query.irradiance(outside, down), glm::vec3(0.0f));  // outside, still below the wall
  const glm::dvec3 worlds[3] = {below, above, outside};
  const glm::vec3 normals[3] = {down, up, down};
  glm::vec3 batch[3];
  query.irradianceBatch(worlds, normals, batch, 3, 2);
  for (int i = 0; i < 3; ++i) EXPECT_EQ(batch[i], query.irradiance(worlds[i], normals[i]));

  query.setUseOcclusion(false);
  EXPECT_FALSE(query.usesOcclusion());
  EXPECT_GT(query.irradiance(below, down).x, 0.0f);    // the leak occlusion removes
  EXPECT_GT(query.irradiance(outside, down).x, 0.0f);  // outside: the extrapolated leak
}

}  // namespace
}  // namespace tetraprobe
