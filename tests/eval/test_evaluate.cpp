// The evaluation's scoring (eval/evaluate.h): scoreMethod's measures have known answers on hand-built
// reports, the reference equals closed forms within its standard error, and `tet`'s bytes count every
// section the lookup reads.
#include <gtest/gtest.h>

#include <cmath>
#include <memory>
#include <numbers>
#include <random>
#include <vector>

#include "test_levels.h"
#include "tetraprobe/eval/evaluate.h"
#include "tetraprobe/occlusion/build_occlusion.h"
#include "tetraprobe/occlusion/occlusion_holes.h"
#include "tetraprobe/runtime/luminance.h"
#include "tetraprobe/runtime/query.h"
#include "tetraprobe/runtime/shade.h"
#include "tetraprobe/runtime/start_bricks.h"

namespace tetraprobe {
namespace {

constexpr double kPi = std::numbers::pi;

// Four points with references well above the 0.01 W/m^2 floor, one of them lit only indirectly.
EvalReport handBuiltReport() {
  EvalReport report;
  const glm::vec3 refs[4] = {
      {1.0f, 2.0f, 3.0f}, {0.5f, 0.5f, 0.5f}, {4.0f, 1.0f, 0.25f}, {10.0f, 8.0f, 6.0f}};
  for (int i = 0; i < 4; ++i) {
    EvalPoint p;
    p.surface.position = glm::dvec3(i, 0.0, 0.0);
    p.surface.normal = glm::vec3(0, 1, 0);
    p.reference.irradiance = refs[i];
    p.indirectOnly = i == 1;
    report.points.push_back(p);
  }
  return report;
}

// A method answering f(reference) at every point (looked up by the point's x coordinate).
LookupMethod methodOf(const EvalReport& report, glm::vec3 (*f)(glm::vec3)) {
  std::vector<glm::vec3> refs;
  for (const EvalPoint& p : report.points) refs.push_back(p.reference.irradiance);
  return {"m", 0, {}, 0, [refs, f](const glm::dvec3& p, const glm::vec3&) { return f(refs[size_t(p.x)]); }};
}

const MethodResult& scored(EvalReport& report, glm::vec3 (*f)(glm::vec3)) {
  scoreMethod(report, methodOf(report, f));
  return report.methods.back();
}

// The reference itself scores zero on every measure: nothing in the definitions is biased.
TEST(ScoreMethod, ExactAnswerScoresZeroEverywhere) {
  EvalReport report = handBuiltReport();
  const MethodResult& m = scored(report, [](glm::vec3 r) { return r; });
  EXPECT_EQ(m.relmse, 0.0);
  EXPECT_EQ(m.meanRelError, 0.0);
  EXPECT_EQ(m.p95RelError, 0.0);
  EXPECT_EQ(m.leak, 0.0);
  EXPECT_EQ(m.leakIndirect, 0.0);
  EXPECT_EQ(m.grossError, 0.0);
  EXPECT_EQ(m.darkHoles, 0.0);
  ASSERT_EQ(m.values.size(), report.points.size());
}

// gross_error is "off by more than 2x": just above twice the reference counts at every point, just below
// does not; the leak of 2x + eps is 1 + eps.
TEST(ScoreMethod, TwiceTheReferencePlusEpsilonIsGrossEverywhere) {
  EvalReport report = handBuiltReport();
  const MethodResult& above = scored(report, [](glm::vec3 r) { return r * 2.001f; });
  EXPECT_EQ(above.grossError, 1.0);
  EXPECT_EQ(above.darkHoles, 0.0);
  EXPECT_NEAR(above.leak, 1.001, 1e-5);
  EXPECT_NEAR(above.leakIndirect, 1.001, 1e-5);
  const MethodResult& below = scored(report, [](glm::vec3 r) { return r * 1.999f; });
  EXPECT_EQ(below.grossError, 0.0);
  const MethodResult& half = scored(report, [](glm::vec3 r) { return r * 0.499f; });
  EXPECT_EQ(half.grossError, 1.0);
  EXPECT_EQ(half.darkHoles, 0.0);
  EXPECT_EQ(half.leak, 0.0) << "too dark is not a leak";
}

// dark_holes is "below a quarter of the reference": 0.24x is a hole, 0.26x is not (but is gross).
TEST(ScoreMethod, DarkHoleThresholdIsAQuarter) {
  EvalReport report = handBuiltReport();
  EXPECT_EQ(scored(report, [](glm::vec3 r) { return r * 0.24f; }).darkHoles, 1.0);
  const MethodResult& m = scored(report, [](glm::vec3 r) { return r * 0.26f; });
  EXPECT_EQ(m.darkHoles, 0.0);
  EXPECT_EQ(m.grossError, 1.0);
}

// Points black in both (below the 0.01 W/m^2 floor) agree: neither gross nor dark, whatever the ratio.
TEST(ScoreMethod, NearBlackPointsAgreeBelowTheFloor) {
  EvalReport report = handBuiltReport();
  for (EvalPoint& p : report.points) p.reference.irradiance = glm::vec3(0.001f);
  const MethodResult& m = scored(report, [](glm::vec3) { return glm::vec3(0.008f); });
  EXPECT_EQ(m.grossError, 0.0);
  const MethodResult& d = scored(report, [](glm::vec3) { return glm::vec3(0.0f); });
  EXPECT_EQ(d.darkHoles, 0.0);
}

// A constant offset d gives relmse = mean over p, c of d^2 / max(r, f)^2 and mean_rel_error = mean over p of
// mean over c of d / max(r, f), f = 0.05 x the mean reference luminance; the former definition divides by
// sqrt(r^2 + 0.01): the closed forms of docs/evaluation.md. Channel 2 of point 2 (set to 0.05 W/m^2) lies
// below f, so the floor is exercised.
TEST(ScoreMethod, RelmseAndMeanRelMatchClosedForm) {
  EvalReport report = handBuiltReport();
  report.points[2].reference.irradiance.z = 0.05f;  // below f: the floor counts
  const MethodResult& m = scored(report, [](glm::vec3 r) { return r + glm::vec3(0.5f); });
  double brightness = 0.0;
  for (const EvalPoint& p : report.points) brightness += luminance(glm::dvec3(p.reference.irradiance));
  const double f = 0.05 * brightness / 4.0;
  ASSERT_GT(f, 0.05);
  EXPECT_NEAR(report.relFloor, f, 1e-9);
  EXPECT_EQ(report.closedPoints, 0u);
  double relmse = 0.0, meanRel = 0.0, relmseAbs = 0.0, meanRelAbs = 0.0;
  std::vector<double> perPoint, perPointAbs;
  for (const EvalPoint& p : report.points) {
    double e = 0.0, eAbs = 0.0;
    for (int c = 0; c < 3; ++c) {
      const double r = p.reference.irradiance[c];
      relmse += 0.25 / (std::max(r, f) * std::max(r, f));
      e += 0.5 / std::max(r, f);
      relmseAbs += 0.25 / (r * r + 0.01);
      eAbs += 0.5 / std::sqrt(r * r + 0.01);
    }
    perPoint.push_back(e / 3.0);
    perPointAbs.push_back(eAbs / 3.0);
    meanRel += e / 3.0;
    meanRelAbs += eAbs / 3.0;
  }
  EXPECT_NEAR(m.relmse, relmse / 12.0, 1e-6);
  EXPECT_NEAR(m.meanRelError, meanRel / 4.0, 1e-6);
  EXPECT_NEAR(m.relmseAbsFloor, relmseAbs / 12.0, 1e-6);
  EXPECT_NEAR(m.meanRelAbsFloor, meanRelAbs / 4.0, 1e-6);
  // p95 of 4 values is the largest (ceil(0.95 * 4) = 4th).
  EXPECT_NEAR(m.p95RelError, *std::max_element(perPoint.begin(), perPoint.end()), 1e-6);
  EXPECT_NEAR(m.p95RelAbsFloor, *std::max_element(perPointAbs.begin(), perPointAbs.end()), 1e-6);
}

// One point in a closed cavity (reference exactly 0) where a method answers 27.9 W/m^2 does not decide the
// table: it is counted apart (closedPoints, closedMean) and every per-point measure equals the one without
// it, while the former definition still carries it (27.9 / sqrt(0.01) = 279 per channel).
TEST(ScoreMethod, PointNoPathLeavesIsReportedApart) {
  EvalReport open = handBuiltReport();
  auto answer = [](glm::vec3 r) { return r == glm::vec3(0.0f) ? glm::vec3(27.9f) : r * 1.5f; };
  const MethodResult without = scored(open, answer);
  EvalReport report = handBuiltReport();
  EvalPoint closed;
  closed.surface.position = glm::dvec3(4.0, 0.0, 0.0);
  closed.surface.normal = glm::vec3(0, 1, 0);
  closed.indirectOnly = true;  // so that leak_indirect would see it, were it not apart
  report.points.push_back(closed);
  ASSERT_TRUE(noPathLeaves(report.points.back()));
  ASSERT_FALSE(noPathLeaves(report.points[0]));
  const MethodResult& m = scored(report, answer);
  EXPECT_EQ(report.closedPoints, 1u);
  EXPECT_EQ(report.relFloor, open.relFloor);
  EXPECT_EQ(m.closedMean, glm::vec3(27.9f));
  EXPECT_EQ(without.closedMean, glm::vec3(0.0f));
  EXPECT_EQ(m.meanRelError, without.meanRelError);
  EXPECT_EQ(m.p95RelError, without.p95RelError);
  EXPECT_EQ(m.relmse, without.relmse);
  EXPECT_EQ(m.leak, without.leak);
  EXPECT_EQ(m.leakIndirect, without.leakIndirect);
  EXPECT_EQ(m.grossError, without.grossError);
  EXPECT_EQ(m.darkHoles, without.darkHoles);
  // The former definition: the closed point adds 279 to the sum over 5 points.
  EXPECT_NEAR(m.meanRelAbsFloor, (4.0 * without.meanRelAbsFloor + 27.9 / 0.1) / 5.0, 1e-4);
  EXPECT_GT(m.meanRelAbsFloor, 50.0 * m.meanRelError);
}

// The fallback share counts the open points, like every other per-point measure: of four open points one
// falls back (1/4), and the two closed points that fall back are counted apart (no viewer sees them), so a
// level's sealed cavities do not decide its figure.
TEST(ScoreMethod, FallbackShareIsOverTheOpenPointsWithClosedOnesApart) {
  EvalReport report = handBuiltReport();
  for (double x : {4.0, 5.0, 6.0}) {
    EvalPoint closed;  // reference exactly 0: no path leaves
    closed.surface.position = glm::dvec3(x, 0.0, 0.0);
    closed.surface.normal = glm::vec3(0, 1, 0);
    report.points.push_back(closed);
  }
  LookupMethod m = methodOf(report, [](glm::vec3 r) { return r; });
  m.fallback = [](const glm::dvec3& p, const glm::vec3&) { return p.x == 2.0 || p.x >= 5.0 ? 0.5f : 0.0f; };
  scoreMethod(report, m);
  EXPECT_EQ(report.closedPoints, 3u);
  EXPECT_EQ(report.methods.back().fallback, 0.25);
  EXPECT_EQ(report.methods.back().closedFallbackPoints, 2u);
}

// leak_indirect averages over the points lit only indirectly, and only those.
TEST(ScoreMethod, LeakIndirectCountsOnlyIndirectPoints) {
  EvalReport report = handBuiltReport();
  scoreMethod(report, {"m", 0, {}, 0, [&](const glm::dvec3& p, const glm::vec3&) {
                         const glm::vec3 r = report.points[size_t(p.x)].reference.irradiance;
                         return p.x == 1.0 ? r * 3.0f : r;  // point 1 is the indirect one
                       }});
  EXPECT_NEAR(report.methods.back().leakIndirect, 2.0, 1e-6);
  EXPECT_NEAR(report.methods.back().leak, 0.5, 1e-6);
}

// Under a constant sky of radiance L an upward floor receives E = pi L and nothing else (it cannot light
// itself): every reference point equals it, within 4 of its standard errors (here 0: each cosine-sampled
// path sees the sky, so E is exact up to rounding).
TEST(ComputeReference, FloorUnderConstantSkyIsPiL) {
  const glm::vec3 L(1.0f, 0.5f, 0.25f);
  const Scene s = test::floorUnderSky(glm::vec3(0.5f), L);
  const SceneTracer tracer(s);
  EvalOptions o;
  o.points = 16;
  o.samplesPerPoint = 64;
  o.progress = false;
  const EvalReport r = computeReference(tracer, kContentDefault, o);
  ASSERT_EQ(r.points.size(), 16u);
  for (const EvalPoint& p : r.points) {
    EXPECT_EQ(p.surface.normal, glm::vec3(0, 1, 0));
    EXPECT_FALSE(p.indirectOnly) << "the sky lights the floor directly";
    for (int c = 0; c < 3; ++c)
      EXPECT_NEAR(p.reference.irradiance[c], kPi * L[c], 4.0 * p.reference.stderror[c] + 1e-5 * kPi * L[c]);
  }
}

// White furnace: inside a closed sphere of emission Le and albedo a, E = pi Le / (1 - a) everywhere (the
// unbiased, Russian-roulette-only reference must not lose the tail of the bounces).
TEST(ComputeReference, FurnaceMatchesClosedFormWithinStandardError) {
  Scene s;
  const float a = 0.5f;
  const glm::vec3 Le(0.2f, 0.4f, 0.1f);
  const uint32_t m = test::addMaterial(s, glm::vec3(a), Le);
  test::addSphere(s, glm::vec3(0.0f), 2.0f, true, m, 12, 24);
  const SceneTracer tracer(s);
  EvalOptions o;
  o.points = 8;
  o.samplesPerPoint = 512;
  o.progress = false;
  const EvalReport r = computeReference(tracer, kContentDefault, o);
  ASSERT_EQ(r.points.size(), 8u);
  for (const EvalPoint& p : r.points)
    for (int c = 0; c < 3; ++c) {
      const double exact = kPi * Le[c] / (1.0 - a);
      EXPECT_NEAR(p.reference.irradiance[c], exact, 5.0 * p.reference.stderror[c] + 1e-3 * exact)
          << "channel " << c << " stderr " << p.reference.stderror[c];
    }
}

// `tet`'s bytes are the sum of its sections, and the sections are the structures the lookup reads: the cell
// grid and outer cells included (they were left out before).
TEST(StandardMethods, TetBytesCountEverySectionTheLookupReads) {
  const Scene s = test::floorUnderSky(glm::vec3(0.5f), glm::vec3(1.0f));
  const SceneTracer tracer(s);
  Level level = test::bakedLevel(tracer, test::probeGrid(), 16);
  const ProbeQuery query(level);
  const std::vector<LookupMethod> methods = standardMethods(level);
  ASSERT_FALSE(methods.empty());
  const LookupMethod& tet = methods[0];
  ASSERT_EQ(tet.name, "tet");
  EXPECT_EQ(tet.bytes, totalBytes(tet.sections));
  EXPECT_EQ(tet.probes, level.probes.size());
  auto section = [&](const std::string& name) {
    for (const ByteSection& b : tet.sections)
      if (b.name == name) return b.bytes;
    ADD_FAILURE() << "no section " << name;
    return uint64_t(0);
  };
  EXPECT_EQ(section("positions"), level.probes.size() * 12);
  EXPECT_EQ(section("sh"), level.probes.size() * 56);  // ShHalf, as stored and uploaded
  // The GPU's packed tets (gpu_tets.h): a 16-byte header, then ceil(4 (bits of a probe index + bits of a
  // neighbour code) / 32) words a tet, then one zero word.
  const auto bits = [](uint64_t v) {
    uint64_t b = 1;
    while (b < 32 && (v >> b) != 0) ++b;
    return b;
  };
  const uint64_t stride = (4 * (bits(level.probes.size() - 1) + bits(level.tets.size())) + 31) / 32;
  EXPECT_LT(stride, 8u);
  EXPECT_EQ(section("tets"), 16 + (level.tets.size() * stride + 1) * 4);
  // The GPU's start (start bricks), as the upload packs them: slots, then one start tet a sub-cell at the
  // tets' neighbour width, then a zero word.
  const StartBricks bricks = buildStartBricks(level, query.startGrid(), query.cellGrid());
  EXPECT_EQ(
      section("start_bricks"),
      bricks.slots.size() * 16 + ((bricks.startTet.size() * bits(level.tets.size()) + 31) / 32 + 1) * 4);
  EXPECT_GT(section("start_bricks"), 0u);
  EXPECT_EQ(section("outer_cells"), query.outerCells().size() * 48);  // GpuOuterCell: octahedral normals
  EXPECT_GT(section("outer_cells"), 0u);
  EXPECT_EQ(section("start_grid"), query.startGrid().startTet.size() * 4);
}

// A 4 x 2.5 x 4 m room with a closed closet (a box with walls 1 cm thick) between the probes: points on the
// closet's inner walls see none of their tet's probes (the fallback).
Scene closetRoom() {
  Scene s;
  const uint32_t grey = test::addMaterial(s, glm::vec3(0.5f));
  test::addBox(s, {-2, 0, -2}, {2, 2.5f, 2}, /*inward=*/true, grey);
  test::addBox(s, {-0.25f, 0.4f, -0.25f}, {0.25f, 1.1f, 0.25f}, /*inward=*/false, grey);
  test::addBox(s, {-0.24f, 0.41f, -0.24f}, {0.24f, 1.09f, 0.24f}, /*inward=*/true, grey);
  return s;
}

// A 6 x 3 x 6 lattice of probes filling closetRoom() around the closet.
std::vector<glm::dvec3> closetRoomProbes() {
  std::vector<glm::dvec3> probes;
  for (double z : {-1.7, -1.0, -0.3, 0.3, 1.0, 1.7})
    for (double y : {0.3, 1.2, 2.2})
      for (double x : {-1.7, -1.0, -0.3, 0.3, 1.0, 1.7}) probes.push_back({x, y, z});
  return probes;
}

// `tet+occlusion` (occlusionMethod, for a level without stored occlusion) answers what the `tet` lookup
// answers once the level stores that occlusion, bit for bit: one shading (runtime/shade.h). Checked over a room
// with a closet between the probes (points on its inner walls see none of their probes: the fallback) at
// surface points and at volume points inside and outside the probes' hull.
TEST(OcclusionMethod, IsTheTetLookupWithTheLevelStoringTheData) {
  const Scene s = closetRoom();
  const SceneTracer tracer(s);
  const std::vector<glm::dvec3> probes = closetRoomProbes();
  Level plain = test::bakedLevel(tracer, probes, 1);
  std::mt19937_64 rng(7);  // the room is unlit: random light, so that every probe's weight shows
  std::uniform_real_distribution<float> u(-0.3f, 0.3f);
  for (ShRgb& sh : plain.sh) {
    for (glm::vec3& c : sh.c) c = glm::vec3(u(rng), u(rng), u(rng));
    sh.c[0] += glm::vec3(1.0f, 0.8f, 0.6f);
  }
  OcclusionOptions o;
  o.progress = false;
  auto occlusion = std::make_shared<const LevelOcclusion>(buildOcclusion(tracer, plain, o));
  ASSERT_FALSE(occlusion->empty());
  Level stored = plain;
  stored.occlusion = *occlusion;
  const LookupMethod method = occlusionMethod(plain, occlusion);
  const ProbeQuery query(stored);
  std::vector<SurfacePoint> points = sampleSurfacePoints(tracer, 2000, 3);
  for (int i = 0; i < 300; ++i) {
    SurfacePoint p;
    p.position = glm::dvec3(-2.4 + 0.016 * i, 0.1 + 0.007 * i, 2.4 - 0.016 * i);  // corner to corner
    points.push_back(p);
  }
  size_t fallback = 0;
  for (const SurfacePoint& p : points) {
    const glm::vec3 a = method.lookup(p.position, p.normal), b = query.irradiance(p.position, p.normal);
    ASSERT_TRUE(a == b) << "(" << p.position.x << ", " << p.position.y << ", " << p.position.z << "): " << a.x
                        << " vs " << b.x;
    fallback += occlusionFallbackShare(stored, query, p.position, p.normal) > 0.0f;
  }
  EXPECT_GT(fallback, 0u);  // the fallback is among the cases
}

// The fallback column counts the points whose final answer falls back: in a room with a closed closet between
// the probes, the tet's own data hides every probe from each point of the closet's inner floor (the bake's
// hole count), the face blend gives some of them back a probe, and the points on the room's floor far from
// the closet see some. `tet`'s share is the count over the points of ShadeRecord::fallback > 0 (after the
// face blend, not the own-data count), `tet (no occlusion)` never falls back and `nearest` has no fallback.
TEST(StandardMethods, FallbackShareIsTheCountOverPoints) {
  const Scene s = closetRoom();
  const SceneTracer tracer(s);
  const std::vector<glm::dvec3> probes = closetRoomProbes();
  Level level = test::bakedLevel(tracer, probes, 1);
  for (ShRgb& sh : level.sh) sh.c[0] = glm::vec3(1.0f);
  OcclusionOptions o;
  o.progress = false;
  level.occlusion = buildOcclusion(tracer, level, o);
  ASSERT_FALSE(level.occlusion.empty());

  EvalReport report;
  auto add = [&](double x, double y, double z) {
    EvalPoint p;
    p.surface.position = glm::dvec3(x, y, z);
    p.surface.normal = glm::vec3(0, 1, 0);
    p.reference.irradiance = glm::vec3(1.0f);
    report.points.push_back(p);
  };
  const size_t inside = 25;
  for (double x : {-0.2, -0.1, 0.0, 0.1, 0.2})
    for (double z : {-0.2, -0.1, 0.0, 0.1, 0.2}) add(x, 0.4101, z);  // the closet's inner floor
  for (double x : {-1.5, -0.8, 0.8, 1.5})
    for (double z : {-1.5, 1.5}) add(x, 0.0001, z);  // the room's floor, in the open
  const ProbeQuery query(level);
  size_t explained = 0, own = 0;
  for (const EvalPoint& p : report.points) {
    ShadeRecord record;
    query.explain(p.surface.position, p.surface.normal, record);
    const bool inCloset = std::abs(p.surface.position.x) < 0.24;
    explained += record.fallback > 0.0f ? 1 : 0;
    own += record.ownFallback > 0.0f ? 1 : 0;
    if (!inCloset) {
      EXPECT_EQ(record.fallback, 0.0f) << "open floor at x " << p.surface.position.x;
    }
  }
  EXPECT_EQ(own, inside) << "the closet's own data hides every probe from each inner point";
  ASSERT_GT(explained, 0u);
  ASSERT_LT(explained, inside) << "the face blend gives some inner points a probe back";

  std::vector<LookupMethod> methods = standardMethods(level);
  ASSERT_EQ(methods.size(), 3u);
  for (const LookupMethod& m : methods) scoreMethod(report, m);
  EXPECT_EQ(report.methods[0].name, "tet");
  EXPECT_EQ(report.methods[0].fallback, double(explained) / double(report.points.size()));
  EXPECT_EQ(report.methods[1].name, "tet (no occlusion)");
  EXPECT_EQ(report.methods[1].fallback, 0.0);
  EXPECT_EQ(report.methods[2].name, "nearest");
  EXPECT_LT(report.methods[2].fallback, 0.0) << "n/a";
}

// The shuffled timing order is a permutation of the coherent one (the same work, another order).
TEST(TimingPoints, ShuffleIsAPermutation) {
  TimingPoints t;
  for (int i = 0; i < 100; ++i) {
    t.position.push_back(glm::dvec3(i, 2 * i, 0));
    t.normal.push_back(glm::vec3(0, 0, 1));
  }
  const TimingPoints s = shuffledTimingPoints(t, 7);
  ASSERT_EQ(s.position.size(), 100u);
  std::vector<int> seen(100, 0);
  size_t moved = 0;
  for (size_t i = 0; i < 100; ++i) {
    ++seen[size_t(s.position[i].x)];
    EXPECT_EQ(s.position[i].y, 2 * s.position[i].x);
    moved += s.position[i].x != double(i);
  }
  for (int c : seen) EXPECT_EQ(c, 1);
  EXPECT_GT(moved, 50u);
}

}  // namespace
}  // namespace tetraprobe
