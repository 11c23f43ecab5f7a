// Extreme radiance (SH from a 1e6 W/m^2 source, all-zero probes) and occlusion at its edges: a wall passing
// exactly through probes, and the seam the per-tet occlusion data can leave on a face two tets share.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numbers>
#include <random>
#include <string>
#include <vector>

#include "../occlusion/test_levels.h"
#include "stability_checks.h"
#include "tetraprobe/bake/bake.h"
#include "tetraprobe/occlusion/build_occlusion.h"
#include "tetraprobe/runtime/face_blend.h"
#include "tetraprobe/runtime/occlusion.h"
#include "tetraprobe/runtime/shade.h"

namespace tetraprobe {
namespace {

using stability::checkLevel;

std::vector<glm::dvec3> lattice(int n, double spacing) {
  std::vector<glm::dvec3> pts;
  for (int z = 0; z < n; ++z)
    for (int y = 0; y < n; ++y)
      for (int x = 0; x < n; ++x) pts.emplace_back(spacing * x, spacing * y, spacing * z);
  return pts;
}

// Incident radiance of a distant source of irradiance `e` (W/m^2) from unit direction d, projected on SH L2:
// L_lm = e Y_lm(d) (a delta in direction d), in every channel.
ShRgb deltaSource(double e, const glm::dvec3& d) {
  const auto y = shBasis<double>(d.x, d.y, d.z);
  ShRgb sh;
  for (int k = 0; k < kShCoeffCount; ++k) sh.c[size_t(k)] = glm::vec3(float(e * y[size_t(k)]));
  return sh;
}

// A spherical Fibonacci set of unit normals.
std::vector<glm::vec3> normals(int count) {
  std::vector<glm::vec3> n;
  const double golden = std::numbers::pi * (3.0 - std::sqrt(5.0));
  for (int i = 0; i < count; ++i) {
    const double z = 1.0 - (i + 0.5) * 2.0 / count, r = std::sqrt(1.0 - z * z);
    n.emplace_back(float(r * std::cos(golden * i)), float(r * std::sin(golden * i)), float(z));
  }
  return n;
}

// Each probe sees a 1e6 W/m^2 source from its own direction (a sun, a welding arc); projected on L2 its
// irradiance rings to -4 % of the mean on the far side. After deringing (the bake's default) every probe's
// and every interpolated irradiance is >= -1e-5 of the mean (kDeringTolerance) and within the probes' range,
// finite, and continuous across faces at 1e6 scale. Guard: deringProbes() (bake/src/dering.cpp); without it
// the probes' own irradiance at their far side is -4e4 W/m^2.
TEST(Stability, MegawattSourceStaysFiniteAndNonNegativeAfterDering) {
  const std::vector<glm::dvec3> pts = lattice(3, 1.0);
  Level level = test::makeLevel(pts, glm::dvec3(1.0), 16);
  std::mt19937_64 rng(17);
  std::normal_distribution<double> g;
  for (ShRgb& sh : level.sh) sh = deltaSource(1e6, glm::normalize(glm::dvec3(g(rng), g(rng), g(rng))));
  DeringOptions dering;
  dering.threads = 1;
  deringProbes(level.sh, dering);
  const double mean =
      std::numbers::pi * sh_const::kY00 * 1e6 * sh_const::kY00;  // pi Y00 L00: the mean irradiance
  const double floor = -kDeringTolerance * mean * 1.01;          // 1 % for the float evaluation
  double lowest = 1e300;
  for (const ShRgb& sh : level.sh)
    for (const glm::vec3& n : normals(512)) {
      const glm::vec3 e = shIrradiance(sh, n);
      lowest = std::min<double>(lowest, std::min({e.x, e.y, e.z}));
      ASSERT_GE(e.x, floor) << "probe irradiance " << e.x;
    }
  const ProbeQuery query(level);
  for (const Tet& t : level.tets)
    for (const glm::vec3& n : normals(64)) {
      glm::dvec3 c(0.0);
      for (int i = 0; i < 4; ++i) c += 0.25 * glm::dvec3(level.probes[size_t(t.v[i])]);
      const glm::vec3 e = query.irradiance(level.origin + c, n);
      ASSERT_TRUE(std::isfinite(e.x));
      ASSERT_GE(e.x, floor - stability::kRelRange * 1e6) << "interpolated irradiance";
    }
  for (const glm::vec3& n : {glm::vec3(0, 0, 1), glm::normalize(glm::vec3(1, -2, 0.5f))}) {
    checkLevel(level, "1e6 W/m^2 sources", stability::kRelRange, n);
    ASSERT_FALSE(HasFatalFailure());
  }
  RecordProperty("lowest_probe_irradiance", std::to_string(lowest));
  std::printf("[1e6 W/m^2] lowest probe irradiance after dering %.4g W/m^2 (mean %.4g)\n", lowest, mean);
}

// All-zero probes (an unlit level, or a level baked before its lights were placed): every answer is exactly
// 0 and finite, inside, on faces, outside at 1e6 m, with and without the deringer. No guard in the code is
// needed: nothing divides by a probe's energy (the deringer's tolerance scales with the mean, so a zero probe
// is left as it is); the case pins that none is introduced.
TEST(Stability, AllZeroProbesAnswerExactlyZero) {
  const ShRgb zero{};
  Level level = test::makeLevel(lattice(3, 1.0), glm::dvec3(1.0), 18, &zero);
  DeringOptions dering;
  dering.threads = 1;
  const DeringStats st = deringProbes(level.sh, dering);
  EXPECT_EQ(st.deringedProbes, 0u);
  for (const ShRgb& sh : level.sh)
    for (const glm::vec3& c : sh.c) ASSERT_EQ(c, glm::vec3(0.0f));
  const ProbeQuery query(level);
  std::mt19937_64 rng(19);
  std::uniform_real_distribution<double> u(-1.0, 3.0);
  for (int k = 0; k < 2000; ++k) {
    const glm::dvec3 x = level.origin + glm::dvec3(u(rng), u(rng), u(rng)) * (k % 10 == 0 ? 1e6 : 1.0);
    ASSERT_EQ(query.irradiance(x, glm::vec3(0, 0, 1)), glm::vec3(0.0f));
    ASSERT_EQ(query.irradiance(x, glm::vec3(0.0f)), glm::vec3(0.0f));
  }
  checkLevel(level, "all-zero probes");
}

OcclusionOptions quiet() {
  OcclusionOptions o;
  o.progress = false;
  o.threads = 1;
  return o;
}

// Probes below a wall lit (1 W/m^2 ambient), above it dark (0.01), on it in between.
ShRgb ambient(float e) {
  ShRgb sh;
  sh.c[0] = glm::vec3(e / float(std::numbers::pi * sh_const::kY00));  // E = pi Y00 L00 for any normal
  return sh;
}

// Every answer with occlusion: finite, the located weights after occlusion in [0, 1] summing to 1, and the
// irradiance within the tet's probes' range (occludedIrradiance blends convex combinations only).
void checkOccludedQuery(const ProbeQuery& query, const glm::dvec3& w, const glm::vec3& n) {
  const Level& level = query.level();
  const Location loc = query.locate(w);
  ASSERT_GE(loc.tet, 0);
  const glm::vec4 vis = occlusionVisibility(level, level.occlusion, loc.tet, glm::vec3(w - level.origin), n);
  const glm::vec4 ow = applyOcclusion(loc.weights, vis);
  double sum = 0.0;
  for (int i = 0; i < 4; ++i) {
    ASSERT_TRUE(std::isfinite(ow[i])) << stability::where(w);
    ASSERT_GE(ow[i], 0.0f);
    ASSERT_LE(ow[i], 1.0f);
    sum += ow[i];
  }
  ASSERT_NEAR(sum, 1.0, stability::kWeightSum) << stability::where(w);
  const glm::vec3 e = query.irradiance(w, n);
  const stability::ProbeRange r = stability::probeRange(level, level.tets[size_t(loc.tet)], n);
  for (int c = 0; c < 3; ++c) {
    ASSERT_TRUE(std::isfinite(e[c])) << stability::where(w);
    ASSERT_GE(e[c], r.lo[c] - stability::kRelRange * r.scale) << stability::where(w);
    ASSERT_LE(e[c], r.hi[c] + stability::kRelRange * r.scale) << stability::where(w);
  }
}

// A wall (z = 1) passing exactly through nine probes of a 3x3x3 lattice: tets touching it only at those
// probes store nothing, tets it cuts store planes in which the on-wall probes sit at plane value 0. At every
// tet's vertices, edge and face points and centroid, and at points on the wall with either normal, the
// answer is finite, its occluded weights sum to 1 and its irradiance is within the probes' range. Guard:
// applyOcclusion() (runtime/src/occlusion.cpp) renormalizes the visible weights (and falls back when none
// is visible); without the renormalization the weights on the wall sum to about 0.5.
TEST(Stability, WallThroughProbesGivesFiniteNormalizedAnswers) {
  Scene scene = test::emptyScene();
  test::addAxisQuad(scene, 2, 1.0f, {-1, -1}, {3, 3});
  const SceneTracer tracer(scene);
  Level level = test::makeLevel(lattice(3, 1.0), glm::dvec3(0.0), 20);
  for (size_t i = 0; i < level.probes.size(); ++i) {
    const float z = level.probes[i].z;
    level.sh[i] = ambient(z < 0.5f ? 1.0f : (z < 1.5f ? 0.5f : 0.01f));
  }
  OcclusionStats st;
  level.occlusion = buildOcclusion(tracer, level, quiet(), &st);
  ASSERT_FALSE(level.occlusion.empty());
  const ProbeQuery query(level);
  for (const Tet& t : level.tets) {
    glm::dvec3 p[4];
    for (int i = 0; i < 4; ++i) p[i] = glm::dvec3(level.probes[size_t(t.v[i])]);
    std::vector<glm::dvec3> xs = {0.25 * (p[0] + p[1] + p[2] + p[3])};
    for (int i = 0; i < 4; ++i) {
      xs.push_back(p[i]);
      for (int j = i + 1; j < 4; ++j) xs.push_back(0.5 * (p[i] + p[j]));
      xs.push_back((p[(i + 1) & 3] + p[(i + 2) & 3] + p[(i + 3) & 3]) / 3.0);
    }
    for (const glm::dvec3& x : xs)
      for (const glm::vec3& n : {glm::vec3(0.0f), glm::vec3(0, 0, 1), glm::vec3(0, 0, -1)}) {
        checkOccludedQuery(query, level.origin + x, n);
        ASSERT_FALSE(HasFatalFailure());
      }
  }
  for (double y = 0.05; y < 2.0; y += 0.3)
    for (double x = 0.05; x < 2.0; x += 0.3)
      for (const glm::vec3& n : {glm::vec3(0, 0, 1), glm::vec3(0, 0, -1)}) {
        checkOccludedQuery(query, glm::dvec3(x, y, 1.0), n);
        ASSERT_FALSE(HasFatalFailure());
      }
  std::printf("[wall through probes] %zu tets, %zu with geometry, %zu planes tets, agreement %.3f\n", st.tets,
              st.tetsWithGeometry, st.planeTets, st.agreement);
}

// Occlusion across a shared face: a tilted wall (through no probe) cuts a 4x4x4 lattice, lit below, dark
// above. At random points of every interior face where either tet stores occlusion, at least 0.1 m from the
// wall (the wall itself is a true edge of the lighting), the irradiance with occlusion is compared 1e-6 m
// either side of the face, for volume points (zero normal) and surface-like normals along the wall's.
// Each tet's data is fitted on its own (its own planes, cell masks, falloff band), so two tets sharing a
// face disagree on which of its probes a point sees: 0.82 of the lit irradiance at most, 219 of 4,014
// points above 1e-3, before the face blend.
// GUARD: faceBlendVisibility (runtime/face_blend.h), which gives both sides the same visibility of the
// face's probes. Away from the face's edges (every face barycentric at least kFaceBlendBand) only the two
// tets blend and the jump is float rounding (measured below 1e-5; bound 1e-4: weights from two float
// frames, through the planes' smoothstep of half-width 0.02, slope <= 75). Within the band of an edge the
// tets around the edge and corner blend too (the blend is a partition of unity over every tet holding the
// probe that reaches the point), so the jump there is float rounding as well: measured 1.7e-5 (it was 0.46
// when only the two face neighbours blended, 8 of 4,014 points above 1e-3). Removing the guard fails both.
constexpr double kSeamInteriorTolerance = 1e-4;
constexpr double kSeamEdgeTolerance = 1e-4;
constexpr size_t kSeamPointsAbove = 0;
TEST(Stability, OcclusionIsContinuousAcrossSharedFaces) {
  Scene scene = test::emptyScene();
  const glm::vec3 wn = glm::normalize(glm::vec3(0.3f, 0.2f, 1.0f)), c(1.5f, 1.5f, 1.45f);
  const glm::vec3 tu = glm::normalize(glm::cross(wn, glm::vec3(1, 0, 0))), tv = glm::cross(wn, tu);
  test::addQuad(scene, c - 4.0f * tu - 4.0f * tv, c + 4.0f * tu - 4.0f * tv, c + 4.0f * tu + 4.0f * tv,
                c - 4.0f * tu + 4.0f * tv);
  const SceneTracer tracer(scene);
  Level level = test::makeLevel(lattice(4, 1.0), glm::dvec3(0.0), 21);
  const auto side = [&](const glm::dvec3& p) { return glm::dot(glm::vec3(p) - c, wn); };
  for (size_t i = 0; i < level.probes.size(); ++i)
    level.sh[i] = ambient(side(glm::dvec3(level.probes[i])) < 0.0 ? 1.0f : 0.01f);
  OcclusionStats st;
  level.occlusion = buildOcclusion(tracer, level, quiet(), &st);
  ASSERT_FALSE(level.occlusion.empty());
  const ProbeQuery query(level);
  std::mt19937_64 rng(22);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  double interior = 0.0, edge = 0.0;
  size_t faces = 0, interiorPoints = 0, edgePoints = 0, above = 0;
  glm::dvec3 worstAt(0.0);
  for (size_t ti = 0; ti < level.tets.size(); ++ti) {
    const Tet& t = level.tets[ti];
    for (int f = 0; f < 4; ++f) {
      const int32_t nb = t.n[f];
      if (nb < int32_t(ti)) continue;
      if (level.occlusion.tets[ti].kind() == kOcclusionNone &&
          level.occlusion.tets[size_t(nb)].kind() == kOcclusionNone)
        continue;
      ++faces;
      const glm::dvec3 a(level.probes[size_t(t.v[(f + 1) & 3])]), b(level.probes[size_t(t.v[(f + 2) & 3])]),
          cc(level.probes[size_t(t.v[(f + 3) & 3])]);
      const glm::dvec3 n = stability::faceNormal(level, t, f);
      for (int k = 0; k < 16; ++k) {
        double b0 = u(rng), b1 = u(rng);
        if (b0 + b1 > 1.0) b0 = 1.0 - b0, b1 = 1.0 - b1;
        const glm::dvec3 x = a * b0 + b * b1 + cc * (1.0 - b0 - b1);
        if (std::abs(side(x)) < 0.1) continue;
        const bool nearEdge = std::min({b0, b1, 1.0 - b0 - b1}) < double(kFaceBlendBand);
        for (const glm::vec3& sn : {glm::vec3(0.0f), wn, -wn}) {
          const glm::vec3 e0 = query.irradiance(level.origin + x - 1e-6 * n, sn);
          const glm::vec3 e1 = query.irradiance(level.origin + x + 1e-6 * n, sn);
          ASSERT_TRUE(std::isfinite(e0.x) && std::isfinite(e1.x));
          const double jump = stability::maxAbs(e1 - e0);  // lit irradiance is 1 W/m^2
          above += jump > 1e-3;
          if (nearEdge) {
            ++edgePoints;
            edge = std::max(edge, jump);
          } else {
            ++interiorPoints;
            if (jump > interior) interior = jump, worstAt = x;
          }
        }
      }
    }
  }
  std::printf(
      "[occlusion seam] %zu tets (%zu with data), %zu faces: largest jump %.3g on %zu points away from "
      "edges (at %s), %.3g on %zu points within the band of an edge; %zu above 1e-3 (relative to the lit "
      "irradiance)\n",
      level.tets.size(), st.planeTets + st.shadowMapTets, faces, interior, interiorPoints,
      stability::where(worstAt).c_str(), edge, edgePoints, above);
  RecordProperty("largest_seam_away_from_edges", std::to_string(interior));
  RecordProperty("largest_seam_near_edges", std::to_string(edge));
  RecordProperty("seams_above_1e-3", std::to_string(above));
  EXPECT_GT(interiorPoints, 100u);
  EXPECT_GT(edgePoints, 100u);
  EXPECT_LE(interior, kSeamInteriorTolerance);
  EXPECT_LE(edge, kSeamEdgeTolerance);
  EXPECT_LE(above, kSeamPointsAbove);
}

// A corner whose tet sees none of its probes: in a jittered 5 x 5 x 5 lattice, one tet holding the centre
// probe stores a plane whose cells see none of its four probes (its own answer would be the fallback's
// guess), and a second tet of the centre's star hides the centre probe alone; every other tet stores
// nothing. Each probe holds a different constant irradiance (1 to 3 W/m^2). Around the centre, at points on
// every face shared by two tets of its star (drawn towards the face's edges and corners, where tets that are
// not face neighbours meet) and 1e-6 m either side of it, for volume points and random normals, the
// irradiance is the same on both sides within float rounding (1e-4 of the lit irradiance): no jump across
// the corner's faces and edges. Inside the blind tet, where its neighbours reach, the answer takes what they
// see (no fallback, and within the probes' range).
TEST(Stability, ACornerWhoseTetSeesNoneOfItsProbesIsContinuousAcrossItsFacesAndEdges) {
  std::vector<glm::dvec3> pts;
  std::mt19937_64 jitter(31);
  std::uniform_real_distribution<double> j(-0.15, 0.15);
  for (const glm::dvec3& p : lattice(5, 1.0)) pts.push_back(p + glm::dvec3(j(jitter), j(jitter), j(jitter)));
  Level level = test::makeLevel(pts);
  for (size_t i = 0; i < level.probes.size(); ++i) level.sh[i] = ambient(1.0f + 2.0f * float(i % 7) / 6.0f);
  const int32_t centre = 2 + 5 * (2 + 5 * 2);
  std::vector<int32_t> star;
  for (size_t t = 0; t < level.tets.size(); ++t)
    for (int32_t v : level.tets[t].v)
      if (v == centre) star.push_back(int32_t(t));
  ASSERT_GE(star.size(), 8u);
  LevelOcclusion& occ = level.occlusion;
  occ.tets.assign(level.tets.size(), TetOcclusion{});
  occ.planes.push_back(makeOcclusionPlane(1.0, -0.5, -0.5, -0.5));
  const int32_t blind = star[0], partial = star[star.size() / 2];
  occ.tets[size_t(blind)] = makeTetOcclusion(kOcclusionPlanes, 1, 0, 0x00u);  // sees none of its probes
  uint32_t seesAllButCentre = 0xFFu;
  for (int i = 0; i < 4; ++i)
    if (level.tets[size_t(partial)].v[i] == centre) seesAllButCentre &= ~(0x11u << i);
  occ.tets[size_t(partial)] = makeTetOcclusion(kOcclusionPlanes, 1, 0, seesAllButCentre);
  const ProbeQuery query(level);
  std::mt19937_64 rng(32);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::normal_distribution<float> g(0.0f, 1.0f);
  double worst = 0.0;
  size_t points = 0, nearEdge = 0;
  for (int32_t ti : star) {
    const Tet& t = level.tets[size_t(ti)];
    for (int f = 0; f < 4; ++f) {
      const int32_t nb = t.n[f];
      if (nb < ti || std::find(star.begin(), star.end(), nb) == star.end()) continue;
      const glm::dvec3 a(level.probes[size_t(t.v[(f + 1) & 3])]), b(level.probes[size_t(t.v[(f + 2) & 3])]),
          c(level.probes[size_t(t.v[(f + 3) & 3])]);
      const glm::dvec3 n = stability::faceNormal(level, t, f);
      for (int k = 0; k < 64; ++k) {
        double w[3] = {std::pow(u(rng), 3.0), std::pow(u(rng), 3.0), std::pow(u(rng), 3.0)};
        const double sum = w[0] + w[1] + w[2];
        const glm::dvec3 x = (a * w[0] + b * w[1] + c * w[2]) / sum;
        nearEdge += std::min({w[0], w[1], w[2]}) / sum < double(kFaceBlendBand);
        for (int s = 0; s < 3; ++s) {
          const glm::vec3 sn = s == 0 ? glm::vec3(0.0f) : glm::normalize(glm::vec3(g(rng), g(rng), g(rng)));
          const glm::vec3 e0 = query.irradiance(level.origin + x - 1e-6 * n, sn);
          const glm::vec3 e1 = query.irradiance(level.origin + x + 1e-6 * n, sn);
          ASSERT_TRUE(std::isfinite(e0.x) && std::isfinite(e1.x));
          worst = std::max(worst, stability::maxAbs(e1 - e0) / 3.0);  // the brightest probe: 3 W/m^2
          ++points;
        }
      }
    }
  }
  // Inside the blind tet, near each face (a tenth of the band in): the neighbours' sight, no fallback.
  size_t rescued = 0, inside = 0;
  const Tet& bt = level.tets[size_t(blind)];
  for (int f = 0; f < 4; ++f) {
    if (bt.n[f] < 0) continue;
    glm::dvec4 w(0.3);
    w[f] = 0.1 * double(kFaceBlendBand);
    w /= w.x + w.y + w.z + w.w;
    glm::dvec3 x(0.0);
    for (int i = 0; i < 4; ++i) x += w[i] * glm::dvec3(level.probes[size_t(bt.v[i])]);
    ShadeRecord r;
    const glm::vec3 e = query.explain(level.origin + x, glm::vec3(0.0f), r);
    ++inside;
    rescued += r.location.tet == blind && r.ownFallback >= 1.0f && r.fallback < 1.0f && e.x >= 1.0f - 1e-4f &&
               e.x <= 3.0f + 1e-4f;
  }
  std::printf(
      "[blind corner] star of %zu tets: %zu face points (%zu near an edge), largest jump %.3g of the "
      "lit irradiance; %zu of %zu points inside the blind tet see through its neighbours\n",
      star.size(), points, nearEdge, worst, rescued, inside);
  RecordProperty("largest_jump", std::to_string(worst));
  EXPECT_GT(nearEdge, 100u);
  EXPECT_LE(worst, 1e-4);
  EXPECT_GT(inside, 0u);
  EXPECT_EQ(rescued, inside);
}

}  // namespace
}  // namespace tetraprobe
