// Error-driven refinement's proposals (eval/refine.h): where a new probe goes relative to the surface point
// whose error asked for it, and which points ask at all.
#include <gtest/gtest.h>

#include <vector>

#include "test_levels.h"
#include "tetraprobe/eval/refine.h"

namespace tetraprobe {
namespace {

RefinePoint pointWithError(glm::dvec3 position, glm::vec3 normal, double error) {
  RefinePoint p;
  p.surface.position = position;
  p.surface.normal = normal;
  p.error = error;
  return p;
}

// Under an open sky the free distance is unbounded, so a proposal sits exactly spacing x
// kRefineOffsetFraction along the normal (or at the explicit maxOffset), worst point first; points at or
// below minError propose nothing.
TEST(ProposeRefinement, ProbeSitsTheRefineOffsetInFrontOfTheWorstPoints) {
  const Scene s = test::floorUnderSky(glm::vec3(0.5f), glm::vec3(1.0f));
  const SceneTracer tracer(s);
  const Level level = test::bakedLevel(tracer, test::probeGrid(), 64);
  const std::vector<RefinePoint> points = {pointWithError({0.3, 0.0, 0.7}, {0, 1, 0}, 0.5),
                                           pointWithError({-1.1, 0.0, -0.9}, {0, 1, 0}, 2.0),
                                           pointWithError({1.4, 0.0, 1.2}, {0, 1, 0}, 0.05)};
  const double spacing = 1.0;
  const std::vector<glm::dvec3> auto_ = proposeRefinement(tracer, level, points, 10, spacing);
  ASSERT_EQ(auto_.size(), 2u) << "the point at error 0.05 <= minError 0.1 must not propose";
  const double d = spacing * kRefineOffsetFraction;
  EXPECT_NEAR(auto_[0].x, -1.1, 1e-9) << "the worst point proposes first";
  EXPECT_NEAR(auto_[0].y, d, 1e-5);
  EXPECT_NEAR(auto_[1].x, 0.3, 1e-9);
  EXPECT_NEAR(auto_[1].y, d, 1e-5);

  const std::vector<glm::dvec3> explicit_ = proposeRefinement(tracer, level, points, 10, spacing, 0.1, 0.3);
  ASSERT_EQ(explicit_.size(), 2u);
  EXPECT_NEAR(explicit_[0].y, 0.3, 1e-5);
  const std::vector<glm::dvec3> one = proposeRefinement(tracer, level, points, 1, spacing);
  ASSERT_EQ(one.size(), 1u) << "the budget caps the proposals";
}

// Under a slab 0.1 m above the floor the probe stays on the point's side: half the free distance (0.05 m),
// not the offset; with 0.015 m free the room (0.0075 m) is below spacing / 50 and nothing is proposed.
TEST(ProposeRefinement, ProbeStaysWithinHalfTheFreeDistance) {
  Scene s = test::floorUnderSky(glm::vec3(0.5f), glm::vec3(1.0f));
  const uint32_t m = test::addMaterial(s, glm::vec3(0.5f));
  test::addQuad(s, {-5.0f, 0.1f, -5.0f}, {5.0f, 0.1f, -5.0f}, {5.0f, 0.1f, 5.0f}, {-5.0f, 0.1f, 5.0f}, m);
  test::addQuad(s, {10.0f, 0.015f, -5.0f}, {20.0f, 0.015f, -5.0f}, {20.0f, 0.015f, 5.0f},
                {10.0f, 0.015f, 5.0f}, m);
  const SceneTracer tracer(s);
  const Level level = test::bakedLevel(tracer, test::probeGrid(), 64);
  const std::vector<RefinePoint> under = {pointWithError({0.2, 0.0, 0.4}, {0, 1, 0}, 1.0)};
  const std::vector<glm::dvec3> p = proposeRefinement(tracer, level, under, 10, 1.0);
  ASSERT_EQ(p.size(), 1u);
  // The free-distance ray starts rayEpsilon above the point, so half of (0.1 - epsilon).
  EXPECT_NEAR(p[0].y, 0.5 * (0.1 - double(tracer.rayEpsilon())), 1e-5);
  const std::vector<RefinePoint> tight = {pointWithError({15.0, 0.0, 0.0}, {0, 1, 0}, 1.0)};
  EXPECT_TRUE(proposeRefinement(tracer, level, tight, 10, 1.0).empty());
}

}  // namespace
}  // namespace tetraprobe
