// The probe SH fit (eval/sh_fit.h): what it returns at the limits of its pull, that it recovers a field the
// tet interpolation can represent, that it lowers the error at independent points on a closed-form scene
// without making irradiance negative, that its hold-out score is the saved level's, and that threads do not
// change it.
#include <gtest/gtest.h>

#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <limits>
#include <numbers>
#include <vector>

#include <glm/geometric.hpp>

#include "test_levels.h"
#include "tetraprobe/eval/sh_fit.h"
#include "tetraprobe/runtime/query.h"
#include "tetraprobe/runtime/sh_half.h"

namespace tetraprobe {
namespace {

// A deterministic value in [-1, 1) from an index (no state, so tests read the same at any order).
double hashUnit(uint64_t i) {
  uint64_t z = i * 0x9e3779b97f4a7c15ull + 0x632be59bd9b4e019ull;
  z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
  z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
  z ^= z >> 31;
  return double(z >> 11) / double(1ull << 52) - 1.0;
}

glm::vec3 unitNormal(uint64_t i) {
  glm::dvec3 d(hashUnit(3 * i), hashUnit(3 * i + 1), hashUnit(3 * i + 2));
  if (glm::length(d) < 1e-3) d = {0.0, 1.0, 0.0};
  return glm::vec3(glm::normalize(d));
}

// A probe level over test::probeGrid() (no occlusion) whose SH are `sh(position)`.
Level gridLevel(ShRgb (*sh)(const glm::dvec3&)) {
  const std::vector<glm::dvec3> world = test::probeGrid();
  Level level;
  level.origin = glm::dvec3(0.0);
  for (const glm::dvec3& p : world) {
    level.probes.push_back(glm::vec3(p));
    level.sh.push_back(sh(p));
  }
  level.tets = buildTetRecords(world, tetrahedralizeDelaunay(world), level.origin);
  return level;
}

// A field linear in position (every coefficient, every channel): the tet interpolation holds it exactly.
ShRgb linearField(const glm::dvec3& p) {
  ShRgb s;
  for (int k = 0; k < kShCoeffCount; ++k)
    for (int c = 0; c < 3; ++c) {
      const double base = k == 0 ? 1.0 + 0.2 * c : 0.15 * std::cos(1.7 * k + c);
      const double slope = k == 0 ? 0.1 : 0.03;
      s.c[size_t(k)][c] = float(base + slope * (std::sin(k + 0.5 * c) * p.x + std::cos(2.0 * k + c) * p.y +
                                                std::sin(3.0 * k - c) * p.z));
    }
  return s;
}

// Points strictly inside the probe grid's hull, random normals, their exact irradiance from `field`.
std::vector<ShFitPoint> linearFieldPoints(size_t count, uint64_t salt) {
  std::vector<ShFitPoint> pts(count);
  for (size_t i = 0; i < count; ++i) {
    const uint64_t k = salt * 1000003ull + i;
    ShFitPoint& p = pts[i];
    p.position = {1.8 * hashUnit(4 * k), 1.25 + 0.6 * hashUnit(4 * k + 1), 1.8 * hashUnit(4 * k + 2)};
    p.normal = unitNormal(k + 77);
    p.target = shIrradiance(linearField(p.position), p.normal);
  }
  return pts;
}

double maxCoefficientError(const std::vector<ShRgb>& a, const Level& truth) {
  double e = 0.0;
  for (size_t j = 0; j < a.size(); ++j) {
    const ShRgb t = linearField(glm::dvec3(truth.probes[j]));
    for (int k = 0; k < kShCoeffCount; ++k)
      for (int c = 0; c < 3; ++c) e = std::max(e, double(std::abs(a[j].c[size_t(k)][c] - t.c[size_t(k)][c])));
  }
  return e;
}

// The same level with every probe's coefficients off by up to 15 % of its L00 (per coefficient, channel).
Level noisyLinearLevel() {
  Level level = gridLevel(linearField);
  for (size_t j = 0; j < level.sh.size(); ++j)
    for (int k = 0; k < kShCoeffCount; ++k)
      for (int c = 0; c < 3; ++c)
        level.sh[j].c[size_t(k)][c] +=
            float(0.15 * level.sh[j].c[0][c] * hashUnit(j * 31 + size_t(k) * 3 + size_t(c)));
  return level;
}

// lambda -> infinity pins every probe to its traced SH: infinity returns them bit for bit, a huge lambda
// within float rounding of them; lambda 0 lets the data move them.
TEST(ShFit, InfiniteLambdaReturnsTheTracedSh) {
  const Level level = noisyLinearLevel();
  const std::vector<ShFitPoint> pts = linearFieldPoints(1500, 1);
  ShFitOptions o;
  o.lambda = std::numeric_limits<double>::infinity();
  const std::vector<ShRgb> pinned = fitProbeSh(level, pts, {}, o);
  ASSERT_EQ(pinned.size(), level.sh.size());
  for (size_t j = 0; j < pinned.size(); ++j)
    for (int k = 0; k < kShCoeffCount; ++k) EXPECT_EQ(pinned[j].c[size_t(k)], level.sh[j].c[size_t(k)]);
  o.lambda = 1e12;
  const std::vector<ShRgb> stiff = fitProbeSh(level, pts, {}, o);
  for (size_t j = 0; j < stiff.size(); ++j)
    for (int k = 0; k < kShCoeffCount; ++k)
      for (int c = 0; c < 3; ++c)
        EXPECT_NEAR(stiff[j].c[size_t(k)][c], level.sh[j].c[size_t(k)][c], 1e-5 * level.sh[j].c[0][c])
            << "probe " << j << " coefficient " << k << " channel " << c;
  o.lambda = 0.0;
  EXPECT_LT(maxCoefficientError(fitProbeSh(level, pts, {}, o), level),
            0.5 * maxCoefficientError(level.sh, level));
}

// A field linear in position is what the tet interpolation represents exactly, so exact irradiance at
// enough points inside the hull (random normals) determines every probe's 9 coefficients: the fit recovers
// the field from probes that were 15 % off, down to the small bias the pull toward them leaves.
TEST(ShFit, RecoversALinearFieldFromNoisyProbes) {
  const Level level = noisyLinearLevel();
  const std::vector<ShFitPoint> pts = linearFieldPoints(4000, 2);
  ShFitOptions o;
  o.lambda = 1e-3;
  ShFitStats stats;
  const std::vector<float> rel(level.probes.size(), 0.15f);
  const std::vector<ShRgb> fitted = fitProbeSh(level, pts, rel, o, &stats);
  EXPECT_EQ(stats.fitted, pts.size());
  EXPECT_EQ(stats.fallbackPoints, 0u);
  EXPECT_EQ(stats.probesTouched, level.probes.size());
  const double before = maxCoefficientError(level.sh, level), after = maxCoefficientError(fitted, level);
  EXPECT_GT(before, 0.05);
  EXPECT_LT(after, 0.02 * before) << "before " << before << " after " << after;
  EXPECT_LT(stats.objectiveAfter, 1e-3 * stats.objectiveBefore);
  // And independent points agree: the hold-out error falls to near zero.
  Level fittedLevel = level;
  fittedLevel.sh = fitted;
  const std::vector<ShFitPoint> holdout = linearFieldPoints(1000, 3);
  EXPECT_LT(shFitScore(fittedLevel, holdout).meanRelError, 0.05 * shFitScore(level, holdout).meanRelError);
}

// Cross-validation (ShFitOptions::crossValidate) holds the probes whose fit does not carry to points it was not
// fitted to. Probes already exact, fitted to points whose targets carry +-50 % noise the points do not declare
// (stderror 0): a loose fit chases the noise and makes exact independent points worse; cross-validated, the
// probes that would move are held (at least 80 % of them) and the independent error stays below half of the
// loose fit's. And where the data are consistent (exact targets, probes 15 % off), it holds almost none (at most
// 2 of 18) and the fit still recovers the field.
TEST(ShFit, CrossValidationHoldsProbesWhoseFitDoesNotCarryToUnseenPoints) {
  const Level exact = gridLevel(linearField);
  std::vector<ShFitPoint> noisy = linearFieldPoints(400, 11);
  for (size_t i = 0; i < noisy.size(); ++i) noisy[i].target *= float(1.0 + 0.5 * hashUnit(7919 * i + 3));
  const std::vector<ShFitPoint> holdout = linearFieldPoints(1000, 12);
  ShFitOptions o;
  o.lambda = 1e-3;
  o.maxMove = 1.0;
  o.crossValidate = false;
  Level loose = exact;
  loose.sh = fitProbeSh(exact, noisy, {}, o);
  o.crossValidate = true;
  ShFitStats stats;
  Level validated = exact;
  validated.sh = fitProbeSh(exact, noisy, {}, o, &stats);
  EXPECT_GE(double(stats.heldProbes), 0.8 * double(stats.probesTouched)) << stats.heldProbes << " held";
  const double looseError = shFitScore(loose, holdout).meanRelError;
  const double validatedError = shFitScore(validated, holdout).meanRelError;
  EXPECT_GT(looseError, 0.01) << "the loose fit must chase the noise for this test to mean anything";
  EXPECT_LT(validatedError, 0.5 * looseError) << "loose " << looseError << " validated " << validatedError;

  const Level off = noisyLinearLevel();
  ShFitStats consistent;
  const std::vector<ShRgb> recovered = fitProbeSh(off, linearFieldPoints(4000, 13), {}, o, &consistent);
  EXPECT_LE(consistent.heldProbes, 2u);
  EXPECT_LT(maxCoefficientError(recovered, off), 0.1 * maxCoefficientError(off.sh, off));
}

// The per-point lookups run on threads; the solve is serial: any thread count gives the same bits.
TEST(ShFit, SameBitsForAnyThreadCount) {
  const Level level = noisyLinearLevel();
  const std::vector<ShFitPoint> pts = linearFieldPoints(2000, 4);
  const std::vector<ShRgb> one = fitProbeSh(level, pts, {}, ShFitOptions{}, nullptr, 1);
  const std::vector<ShRgb> four = fitProbeSh(level, pts, {}, ShFitOptions{}, nullptr, 4);
  ASSERT_EQ(one.size(), four.size());
  for (size_t j = 0; j < one.size(); ++j)
    for (int k = 0; k < kShCoeffCount; ++k) EXPECT_EQ(one[j].c[size_t(k)], four[j].c[size_t(k)]);
}

// An L1 level (Level::shOrder 1: coefficients 4..8 zero, as the file format requires) stays one: the fit
// moves only coefficients 0..3, and still recovers the L1 part of a field linear in position from noisy
// probes (targets from the L1-truncated field, so that L1 probes can represent them exactly).
TEST(ShFit, L1LevelKeepsItsL2CoefficientsZero) {
  Level level = noisyLinearLevel();
  level.shOrder = 1;
  truncateShOrder(level.sh, 1);
  std::vector<ShFitPoint> pts = linearFieldPoints(3000, 6);
  for (ShFitPoint& p : pts) {
    std::vector<ShRgb> one{linearField(p.position)};
    truncateShOrder(one, 1);
    p.target = shIrradiance(one[0], p.normal);
  }
  ShFitOptions o;
  o.lambda = 1e-3;
  const std::vector<ShRgb> fitted = fitProbeSh(level, pts, {}, o);
  ASSERT_EQ(fitted.size(), level.sh.size());
  bool moved = false;
  for (size_t j = 0; j < fitted.size(); ++j) {
    for (int k = 4; k < kShCoeffCount; ++k)
      EXPECT_EQ(fitted[j].c[size_t(k)], glm::vec3(0.0f)) << "probe " << j;
    for (int k = 0; k < 4; ++k) moved = moved || fitted[j].c[size_t(k)] != level.sh[j].c[size_t(k)];
  }
  EXPECT_TRUE(moved);
  Level fittedLevel = level;
  fittedLevel.sh = fitted;
  std::vector<ShFitPoint> holdout = linearFieldPoints(1000, 7);
  for (ShFitPoint& p : holdout) {
    std::vector<ShRgb> one{linearField(p.position)};
    truncateShOrder(one, 1);
    p.target = shIrradiance(one[0], p.normal);
  }
  EXPECT_LT(shFitScore(fittedLevel, holdout).meanRelError, 0.2 * shFitScore(level, holdout).meanRelError);
}

// A point light of intensity I 1 m above a black floor (no sky, no bounce): the floor's irradiance is the
// closed form I h / r^3, a peak far narrower than the 2 m probe grid above and below the light resolves. With
// that as the target at points on the floor, the fit lowers the error at independent floor points, and after
// deringing no probe's irradiance is negative for any normal, so no lookup answer is.
TEST(ShFit, LowersTheErrorAtIndependentPointsOnAClosedFormScene) {
  Scene s;
  test::addGround(s, 0.0f, 100.0f, test::addMaterial(s, glm::vec3(0.0f)));
  Light light;
  light.type = LightType::kPoint;
  light.position = {0.3f, 1.0f, -0.2f};
  light.intensity = glm::vec3(10.0f);
  s.lights.push_back(light);
  const SceneTracer tracer(s);
  const std::vector<glm::dvec3> world = test::probeGrid();
  Level level;
  level.origin = glm::dvec3(0.0);
  for (const glm::dvec3& p : world) level.probes.push_back(glm::vec3(p));
  BakeOptions bake;
  bake.samplesPerProbe = 64;
  bake.content = kContentAll;
  bake.progress = false;
  level.sh = bakeProbes(tracer, world, bake);
  level.content = bake.content;
  level.tets = buildTetRecords(world, tetrahedralizeDelaunay(world), level.origin);
  auto floorPoints = [&](size_t count, uint64_t salt) {
    std::vector<ShFitPoint> pts(count);
    for (size_t i = 0; i < count; ++i) {
      const uint64_t k = salt * 1000003ull + i;
      ShFitPoint& p = pts[i];
      p.position = {1.9 * hashUnit(2 * k), 0.0, 1.9 * hashUnit(2 * k + 1)};
      p.normal = {0.0f, 1.0f, 0.0f};
      const glm::dvec3 d = glm::dvec3(light.position) - p.position;
      const double r = glm::length(d);
      p.target = glm::vec3(float(10.0 * d.y / (r * r * r)));
    }
    return pts;
  };
  const std::vector<ShFitPoint> fit = floorPoints(3000, 5), holdout = floorPoints(1000, 6);
  ShFitOptions o;
  o.maxMove = 1.0;  // the peak needs the probes near it to move far
  std::vector<ShRgb> fitted = fitProbeSh(level, fit, {}, o);
  deringProbes(fitted, DeringOptions{});
  const double before = shFitScore(level, holdout).meanRelError;
  for (const ShRgb& sh : fitted)
    EXPECT_GE(minShIrradiance(sh), -1e-5f * sh.c[0].x) << "a probe rings negative";
  level.sh = fitted;
  const double after = shFitScore(level, holdout).meanRelError;
  EXPECT_GT(before, 0.1) << "the traced probes must leave an error for the fit to lower";
  EXPECT_LT(after, 0.7 * before) << "before " << before << " after " << after;
  const ProbeQuery query(level);
  for (size_t i = 0; i < holdout.size(); ++i) {
    const glm::vec3 e = query.irradiance(holdout[i].position, unitNormal(i));
    EXPECT_GE(std::min({e.x, e.y, e.z}), 0.0f);
  }
}

// How far a probe may move: per channel, the RMS over normals of its irradiance change is at most maxMove x
// its mean irradiance (every probe here is far brighter than the floor f), whatever the data ask for.
TEST(ShFit, NoProbeMovesFurtherThanTheCap) {
  const Level level = noisyLinearLevel();
  ShFitOptions o;
  o.lambda = 0.0;
  o.maxMove = 0.02;
  ShFitStats stats;
  const std::vector<ShRgb> fitted = fitProbeSh(level, linearFieldPoints(2000, 9), {}, o, &stats);
  EXPECT_GT(stats.cappedProbes, 0u);
  for (size_t j = 0; j < fitted.size(); ++j)
    for (int c = 0; c < 3; ++c) {
      double ms = 0.0;
      for (int k = 0; k < kShCoeffCount; ++k) {
        const double d =
            shCosineLobe(k) * (double(fitted[j].c[size_t(k)][c]) - double(level.sh[j].c[size_t(k)][c]));
        ms += d * d / (4.0 * std::numbers::pi);
      }
      const double mean = std::numbers::pi * sh_const::kY00 * double(level.sh[j].c[0][c]);
      EXPECT_LE(std::sqrt(ms), o.maxMove * mean * (1.0 + 1e-4)) << "probe " << j << " channel " << c;
    }
}

// The bake reports the hold-out error of the SH it saves (deringed, half precision). Saved and loaded back,
// the level's error recomputed here term by term (eval's mean_rel_error written out) equals the score.
TEST(ShFit, HoldoutScoreIsTheSavedLevelsError) {
  Level level = noisyLinearLevel();
  std::vector<ShRgb> fitted = fitProbeSh(level, linearFieldPoints(1500, 7), {}, ShFitOptions{});
  deringProbes(fitted, DeringOptions{});
  for (ShRgb& sh : fitted) sh = quantizeSh(sh);
  level.sh = fitted;
  const std::vector<ShFitPoint> holdout = linearFieldPoints(500, 8);
  const ShFitScore score = shFitScore(level, holdout);
  const double reported = score.meanRelError;

  const std::filesystem::path file =
      std::filesystem::temp_directory_path() / ("tetraprobe_shfit_" + std::to_string(::getpid()) + ".tpb");
  ASSERT_TRUE(saveLevel(file.string(), level));
  Level loaded;
  const LevelResult r = loadLevel(file.string(), loaded);
  std::filesystem::remove(file);
  ASSERT_TRUE(r) << r.message;
  const ProbeQuery query(loaded);
  double brightness = 0.0;
  for (const ShFitPoint& p : holdout)
    brightness += 0.2126 * p.target.x + 0.7152 * p.target.y + 0.0722 * p.target.z;
  const double f = 0.05 * brightness / double(holdout.size());
  double sum = 0.0;
  size_t gross = 0;
  auto lum = [](const glm::vec3& v) { return 0.2126 * v.x + 0.7152 * v.y + 0.0722 * v.z; };
  for (const ShFitPoint& p : holdout) {
    const glm::vec3 x = query.irradiance(p.position, p.normal);
    const double lx = std::max(lum(x), 0.01), lr = std::max(lum(p.target), 0.01);
    gross += lx > 2.0 * lr || lx < 0.5 * lr ? 1 : 0;
    for (int c = 0; c < 3; ++c)
      sum += std::abs(double(x[c]) - double(p.target[c])) / std::max(double(p.target[c]), f) / 3.0;
  }
  EXPECT_NEAR(reported, sum / double(holdout.size()), 1e-9 * (1.0 + reported));
  EXPECT_GT(reported, 0.0);
  EXPECT_EQ(score.points, holdout.size());
  EXPECT_DOUBLE_EQ(score.gross, double(gross) / double(holdout.size()));
}

// The auto gate: the fit is kept only with a lower mean rel and no higher gross share (Sponza's guided fit,
// 0.0550 -> 0.0590 on 1,747 points, is dropped), and never on an empty score.
TEST(ShFit, GateKeepsAFitOnlyWhenMeanRelDropsAndGrossDoesNotRise) {
  const ShFitScore before{1747, 0.2021, 0.0550};
  EXPECT_TRUE(shFitKept(before, {1747, 0.1827, 0.0550}));
  EXPECT_TRUE(shFitKept(before, {1747, 0.1827, 0.0500}));
  EXPECT_FALSE(shFitKept(before, {1747, 0.1827, 0.0590}));
  EXPECT_FALSE(shFitKept(before, {1747, 0.2021, 0.0500}));  // mean rel not lower
  EXPECT_FALSE(shFitKept(ShFitScore{}, {1747, 0.1827, 0.0550}));
}

}  // namespace
}  // namespace tetraprobe
