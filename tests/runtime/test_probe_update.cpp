// setProbeSh (probe_update.h): the contract of run-time SH updates on the CPU. What it accepts, what it
// rejects without touching the level, and that a query built before the update answers with the new SH
// exactly as a query on a level built with them from the start.
#include <gtest/gtest.h>

#include <limits>
#include <random>
#include <vector>

#include "test_levels.h"
#include "tetraprobe/runtime/probe_update.h"
#include "tetraprobe/runtime/query.h"

namespace tetraprobe {
namespace {

ShRgb constantSh(float v) {
  ShRgb s;
  for (auto& c : s.c) c = glm::vec3(v, 0.5f * v, -0.25f * v);
  return s;
}

Level smallLevel() {
  return test::makeLevel(test::randomBoxPoints(40, 3, glm::dvec3(-2.0), glm::dvec3(2.0)), glm::dvec3(0.0), 5);
}

// Why: an engine relights a range (one room's probes); the probes outside it must keep their SH bit for bit.
TEST(ProbeUpdate, ReplacesExactlyTheRange) {
  Level level = smallLevel();
  const std::vector<ShRgb> before = level.sh;
  const std::vector<ShRgb> fresh(7, constantSh(3.0f));
  ASSERT_TRUE(setProbeSh(level, 10, fresh));
  for (size_t p = 0; p < level.sh.size(); ++p) {
    const ShRgb& expected = p >= 10 && p < 17 ? fresh[0] : before[p];
    for (int c = 0; c < kShCoeffCount; ++c) EXPECT_EQ(level.sh[p].c[size_t(c)], expected.c[size_t(c)]) << p;
  }
}

// Why: a bad range must be an error, never a write past the end (the GPU copy is laid out the same way).
TEST(ProbeUpdate, RejectsRangesOutsideTheLevelAndLeavesItUnchanged) {
  Level level = smallLevel();
  const size_t n = level.probes.size();
  const std::vector<ShRgb> before = level.sh;
  const std::vector<ShRgb> one(1, constantSh(1.0f)), two(2, constantSh(1.0f));
  EXPECT_EQ(setProbeSh(level, n, one).status, ShUpdateStatus::kOutOfRange);
  EXPECT_EQ(setProbeSh(level, n - 1, two).status, ShUpdateStatus::kOutOfRange);
  EXPECT_EQ(setProbeSh(level, std::numeric_limits<size_t>::max(), two).status, ShUpdateStatus::kOutOfRange);
  EXPECT_EQ(setProbeSh(level, n + 1, {}).status, ShUpdateStatus::kOutOfRange);
  const ShUpdateResult r = setProbeSh(level, n - 1, two);
  EXPECT_NE(r.message.find("outside the level"), std::string::npos) << r.message;
  EXPECT_TRUE(setProbeSh(level, n, {})) << "an empty update at the end is a no-op";
  EXPECT_TRUE(setProbeSh(level, n - 1, one)) << "the last probe alone is in range";
  level.sh.back() = before.back();
  for (size_t p = 0; p < n; ++p) EXPECT_EQ(level.sh[p].c[0], before[p].c[0]) << p;
}

// Why: one NaN in the middle of a batch must not leave half the batch written (all or nothing), and the level
// must stay one that validateLevel accepts and saveLevel writes.
TEST(ProbeUpdate, RejectsNonFiniteWithoutWritingAnything) {
  Level level = smallLevel();
  const std::vector<ShRgb> before = level.sh;
  std::vector<ShRgb> batch(5, constantSh(2.0f));
  batch[3].c[6].y = std::numeric_limits<float>::quiet_NaN();
  const ShUpdateResult r = setProbeSh(level, 4, batch);
  EXPECT_EQ(r.status, ShUpdateStatus::kNonFinite);
  EXPECT_NE(r.message.find("probe 7 coefficient 6"), std::string::npos) << r.message;
  batch[3].c[6].y = std::numeric_limits<float>::infinity();
  EXPECT_EQ(setProbeSh(level, 4, batch).status, ShUpdateStatus::kNonFinite);
  // Finite but beyond what the file and the GPU hold (half precision, sh_half.h): refused the same way.
  batch[3].c[6].y = 3e9f;
  const ShUpdateResult big = setProbeSh(level, 4, batch);
  EXPECT_EQ(big.status, ShUpdateStatus::kTooLarge);
  EXPECT_NE(big.message.find("probe 7 coefficient 6"), std::string::npos) << big.message;
  for (size_t p = 0; p < level.sh.size(); ++p)
    for (int c = 0; c < kShCoeffCount; ++c) EXPECT_EQ(level.sh[p].c[size_t(c)], before[p].c[size_t(c)]);
  EXPECT_TRUE(validateLevel(level));
}

// Why: an L1 level with L2 terms would be refused by saveLevel and evaluated differently by the GPU's L1
// variant; negative radiance (ringing) stays allowed.
TEST(ProbeUpdate, L1LevelRejectsL2CoefficientsAcceptsNegative) {
  Level level = smallLevel();
  for (ShRgb& s : level.sh)
    for (int c = 4; c < kShCoeffCount; ++c) s.c[size_t(c)] = glm::vec3(0.0f);
  level.shOrder = 1;
  ShRgb l2 = constantSh(1.0f);
  EXPECT_EQ(setProbeSh(level, 0, {&l2, 1}).status, ShUpdateStatus::kNotL1);
  for (int c = 4; c < kShCoeffCount; ++c) l2.c[size_t(c)] = glm::vec3(0.0f);
  l2.c[1] = glm::vec3(-5.0f);
  EXPECT_TRUE(setProbeSh(level, 0, {&l2, 1}));
  EXPECT_TRUE(validateLevel(level));
}

// Why: nothing a ProbeQuery builds depends on the SH, so no rebuild is needed: a query built before the update
// answers bit for bit as a query on a level built from the same probes with the new SH (in and outside the
// hull, with and without a tet cache).
TEST(ProbeUpdate, QueryBuiltBeforeAnswersAsAFreshLevel) {
  const auto points = test::randomBoxPoints(60, 9, glm::dvec3(-3.0), glm::dvec3(3.0));
  Level level = test::makeLevel(points, glm::dvec3(0.5), 1);
  const Level relit = test::makeLevel(points, glm::dvec3(0.5), 2);  // other random SH, same probes
  ASSERT_EQ(level.tets.size(), relit.tets.size());
  const ProbeQuery query(level);
  const ProbeQuery fresh(relit);
  ASSERT_TRUE(setProbeSh(level, 0, relit.sh));
  std::mt19937_64 rng(4);
  std::uniform_real_distribution<double> u(-4.0, 4.0);
  int32_t cache = -1;
  int differentBefore = 0;
  const Level original = test::makeLevel(points, glm::dvec3(0.5), 1);
  const ProbeQuery old(original);
  for (int i = 0; i < 2000; ++i) {
    const glm::dvec3 x(u(rng), u(rng), u(rng));
    const glm::vec3 n = glm::normalize(glm::vec3(u(rng), u(rng), u(rng)) + glm::vec3(1e-3f));
    const glm::vec3 expected = fresh.irradiance(x, n);
    EXPECT_EQ(query.irradiance(x, n), expected) << "point " << i;
    EXPECT_EQ(query.irradiance(x, n, &cache), expected) << "point " << i << " (cached walk)";
    differentBefore += old.irradiance(x, n) != expected;
  }
  EXPECT_GT(differentBefore, 1900)
      << "the two SH sets must light the points differently for the test to bite";
}

}  // namespace
}  // namespace tetraprobe
