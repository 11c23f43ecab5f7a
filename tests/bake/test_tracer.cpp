// SceneTracer, inside test and surface points: geometric invariants on tiny hand-built scenes.
#include <cmath>
#include <limits>

#include <gtest/gtest.h>
#include <glm/geometric.hpp>

#include "test_scenes.h"
#include "tetraprobe/bake/bake.h"
#include "tetraprobe/bake/tracer.h"
#include "tetraprobe/common/error.h"

namespace tetraprobe {
namespace {

constexpr float kInf = std::numeric_limits<float>::infinity();

// The contract every sampler leans on: frontFace and geometricNormal follow the counter-clockwise winding,
// and t is the exact distance along a unit ray.
TEST(Tracer, FrontFaceFollowsCounterClockwiseWinding) {
  Scene s;
  const uint32_t m = test::addMaterial(s, glm::vec3(0.5f));
  test::addGround(s, 0.0f, 10.0f, m);  // faces +Y
  SceneTracer tracer(s);
  const Hit down = tracer.intersect({0.3f, 2.0f, 0.1f}, {0, -1, 0}, 0.0f, kInf);
  ASSERT_TRUE(down.hit);
  EXPECT_TRUE(down.frontFace);
  EXPECT_NEAR(down.t, 2.0f, 1e-6f);
  EXPECT_NEAR(glm::dot(down.geometricNormal, glm::vec3(0, 1, 0)), 1.0f, 1e-6f);
  const Hit up = tracer.intersect({0.3f, -2.0f, 0.1f}, {0, 1, 0}, 0.0f, kInf);
  ASSERT_TRUE(up.hit);
  EXPECT_FALSE(up.frontFace);
  EXPECT_NEAR(glm::dot(up.geometricNormal, glm::vec3(0, 1, 0)), 1.0f, 1e-6f);
  // Barycentrics reproduce the hit point.
  const glm::uvec3 t = s.triangles[down.triangle];
  const glm::vec3 p =
      s.positions[t.x] * (1 - down.u - down.v) + s.positions[t.y] * down.u + s.positions[t.z] * down.v;
  EXPECT_NEAR(glm::length(p - glm::vec3(0.3f, 0.0f, 0.1f)), 0.0f, 1e-5f);
}

// The hit normal is the unit (P1 - P0) x (P2 - P0) of the triangle met, for any orientation (Embree's own
// normal is used on the hot path; this pins its sign and scale to the winding contract).
TEST(Tracer, GeometricNormalIsUnitCounterClockwiseCross) {
  Scene s;
  const uint32_t m = test::addMaterial(s, glm::vec3(0.5f));
  const glm::vec3 a(0.1f, -0.3f, 0.2f), b(1.3f, 0.4f, -0.6f), c(-0.2f, 1.1f, 0.9f);
  test::addTriangle(s, a, b, c, m);
  SceneTracer tracer(s);
  const glm::vec3 n = glm::normalize(glm::cross(b - a, c - a));
  const glm::vec3 centroid = (a + b + c) / 3.0f;
  for (float side : {1.0f, -1.0f}) {
    const Hit h = tracer.intersect(centroid + side * 2.0f * n, -side * n, 0.0f, kInf);
    ASSERT_TRUE(h.hit);
    EXPECT_EQ(h.frontFace, side > 0.0f);
    EXPECT_NEAR(glm::length(h.geometricNormal - n), 0.0f, 1e-6f);
  }
}

// Tracing threads run with flush-to-zero / denormals-are-zero, and the scope restores the caller's mode.
TEST(Tracer, FlushDenormalsScopeSetsAndRestoresTheMode) {
  volatile float tiny = 1e-39f;  // a denormal
  ASSERT_NE(tiny * 1.0f, 0.0f);
  {
    FlushDenormalsScope scope;
    EXPECT_EQ(tiny * 1.0f, 0.0f);
  }
  EXPECT_NE(tiny * 1.0f, 0.0f);
}

// Occluded must agree with intersect on the segment it tests, including the tfar bound.
TEST(Tracer, OccludedAgreesWithIntersect) {
  Scene s;
  const uint32_t m = test::addMaterial(s, glm::vec3(0.5f));
  test::addBox(s, {-1, -1, -1}, {1, 1, 1}, false, m, 2);
  SceneTracer tracer(s);
  EXPECT_TRUE(tracer.occluded({0, 0, -5}, {0, 0, 1}, 0.0f, kInf));
  EXPECT_FALSE(tracer.occluded({0, 0, -5}, {0, 0, 1}, 0.0f, 3.9f));  // stops 0.1 m short of the box
  EXPECT_FALSE(tracer.occluded({0, 5, -5}, {0, 0, 1}, 0.0f, kInf));
  EXPECT_FALSE(tracer.intersect({0, 5, -5}, {0, 0, 1}, 0.0f, kInf).hit);
}

// Bad scenes from outside are InputErrors, never crashes inside Embree.
TEST(Tracer, RejectsEmptyNonFiniteAndInconsistentScenes) {
  Scene empty;
  EXPECT_THROW(SceneTracer{empty}, InputError);
  Scene nan;
  const uint32_t m = test::addMaterial(nan, glm::vec3(0.5f));
  test::addTriangle(nan, {0, 0, 0}, {1, 0, 0}, {0, std::nanf(""), 0}, m);
  EXPECT_THROW(SceneTracer{nan}, InputError);
  Scene badIndex;
  test::addMaterial(badIndex, glm::vec3(0.5f));
  test::addTriangle(badIndex, {0, 0, 0}, {1, 0, 0}, {0, 1, 0}, 0);
  badIndex.triangles[0].z = 7;
  EXPECT_THROW(SceneTracer{badIndex}, InputError);
  Scene badMaterial;
  test::addTriangle(badMaterial, {0, 0, 0}, {1, 0, 0}, {0, 1, 0}, 3);
  EXPECT_THROW(SceneTracer{badMaterial}, InputError);
}

// The Unity APV rule: inside a solid (outward-facing) crate every ray meets a back face; outside none does.
TEST(InsideGeometry, PointInClosedCrateIsInsideAndOutsideIsNot) {
  Scene s;
  const uint32_t m = test::addMaterial(s, glm::vec3(0.5f));
  test::addBox(s, {-1, -1, -1}, {1, 1, 1}, false, m, 3);
  test::addGround(s, -1.0f, 20.0f, m);
  SceneTracer tracer(s);
  const std::vector<glm::dvec3> points = {
      {0.1, 0.2, -0.3}, {0.9, 0.9, 0.9}, {3, 0, 0}, {0, 2, 0}, {-4, 5, 2}};
  for (int threads : {1, 2}) {
    const std::vector<uint8_t> inside = probesInsideGeometry(tracer, points, 64, 0.25, threads);
    ASSERT_EQ(inside.size(), points.size());
    EXPECT_EQ(inside[0], 1);
    EXPECT_EQ(inside[1], 1);
    EXPECT_EQ(inside[2], 0);
    EXPECT_EQ(inside[3], 0);
    EXPECT_EQ(inside[4], 0);
  }
}

float distanceToTriangle(const Scene& s, const SurfacePoint& p) {
  const glm::uvec3 t = s.triangles[p.triangle];
  const glm::vec3 a = s.positions[t.x], b = s.positions[t.y], c = s.positions[t.z];
  const glm::vec3 n = glm::normalize(glm::cross(b - a, c - a));
  const glm::vec3 x = glm::vec3(p.position);
  // Inside the triangle's prism (all edge tests agree) and on its plane.
  const float e0 = glm::dot(glm::cross(b - a, x - a), n), e1 = glm::dot(glm::cross(c - b, x - b), n),
              e2 = glm::dot(glm::cross(a - c, x - c), n);
  if (e0 < -1e-6f || e1 < -1e-6f || e2 < -1e-6f) return kInf;
  return std::fabs(glm::dot(x - a, n));
}

// In a room (inward-facing closed box) every surface point lies on its triangle and faces into the room,
// i.e. along the triangle's front normal; albedo comes from the material.
TEST(SurfacePoints, LieOnTheirTrianglesAndFaceIntoTheRoom) {
  Scene s;
  const uint32_t m = test::addMaterial(s, glm::vec3(0.25f, 0.5f, 0.75f));
  test::addBox(s, {-2, 0, -3}, {2, 3, 3}, true, m, 2);
  SceneTracer tracer(s);
  const std::vector<SurfacePoint> pts = sampleSurfacePoints(tracer, 200, 42);
  ASSERT_EQ(pts.size(), 200u);
  for (const SurfacePoint& p : pts) {
    EXPECT_LT(distanceToTriangle(s, p), 1e-5f) << "triangle " << p.triangle;
    const glm::vec3 toCentre = glm::vec3(0, 1.5f, 0) - glm::vec3(p.position);
    EXPECT_GT(glm::dot(p.normal, toCentre), 0.0f) << "normal must point into the room";
    EXPECT_NEAR(glm::length(p.normal), 1.0f, 1e-5f);
    EXPECT_EQ(p.albedo, glm::vec3(0.25f, 0.5f, 0.75f));
  }
  // Same seed, same points.
  const std::vector<SurfacePoint> again = sampleSurfacePoints(tracer, 200, 42);
  for (size_t i = 0; i < pts.size(); ++i) EXPECT_EQ(pts[i].position, again[i].position);
}

// Side choice: a crate whose lid is flipped (front face into the solid crate) is seen from the room through
// the lid's back side, so lid points take the back normal (+Y); a panel buried inside the crate is enclosed
// on both sides and never returned.
TEST(SurfacePoints, PickTheOpenSideAndSkipEnclosedSurfaces) {
  Scene s;
  const uint32_t room = test::addMaterial(s, glm::vec3(0.5f));
  const uint32_t crate = test::addMaterial(s, glm::vec3(0.3f));
  const uint32_t lid = test::addMaterial(s, glm::vec3(0.7f));
  const uint32_t buried = test::addMaterial(s, glm::vec3(0.1f));
  test::addBox(s, {-4, 0, -4}, {4, 4, 4}, true, room);
  // Crate [-1,1] x [0,2] x [-1,1] without its top, then a lid facing down (into the crate).
  const size_t before = s.triangles.size();
  test::addBox(s, {-1, 0, -1}, {1, 2, 1}, false, crate);
  // Drop the crate's top face (the 4th face: triangles 6 and 7 of the 12 just added).
  s.triangles.erase(s.triangles.begin() + long(before) + 6, s.triangles.begin() + long(before) + 8);
  s.triangleMaterial.erase(s.triangleMaterial.begin() + long(before) + 6,
                           s.triangleMaterial.begin() + long(before) + 8);
  test::addQuad(s, {-1, 2, -1}, {1, 2, -1}, {1, 2, 1}, {-1, 2, 1}, lid);  // faces -Y
  test::addQuad(s, {-0.5f, 1, -0.5f}, {0.5f, 1, -0.5f}, {0.5f, 1, 0.5f}, {-0.5f, 1, 0.5f}, buried);
  SceneTracer tracer(s);
  const std::vector<SurfacePoint> pts = sampleSurfacePoints(tracer, 2000, 7);
  ASSERT_EQ(pts.size(), 2000u);
  int lidPoints = 0;
  for (const SurfacePoint& p : pts) {
    const uint32_t mat = s.triangleMaterial[p.triangle];
    EXPECT_NE(mat, buried) << "enclosed panel returned at " << p.position.x << " " << p.position.y;
    if (mat == lid) {
      ++lidPoints;
      EXPECT_GT(p.normal.y, 0.99f) << "the lid is seen from above, through its back side";
    }
  }
  EXPECT_GT(lidPoints, 0);
}

// Under a sky, the void below a level is its outside: the underside of a ground plane (single-sided, facing
// +Y) sees the sky below the horizon and would be "open" by back faces alone, yet no viewer on the ground
// sees it, so no point is drawn there; its top is. Two roofs 3 m up: one facing down, whose downward rays
// meet the ground's front face (open: a viewer under the eaves sees it), one facing up, whose top is open
// under a sky and sees the void under a black one (then its underside is taken). The ground reaches 30 m
// past the roofs, so few of their grazing rays pass its edge.
TEST(SurfacePoints, UndersideOfAGroundPlaneUnderASkyIsNeverDrawn) {
  for (const bool sky : {true, false}) {
    Scene s;
    const uint32_t ground = test::addMaterial(s, glm::vec3(0.5f));
    const uint32_t down = test::addMaterial(s, glm::vec3(0.3f));
    const uint32_t up = test::addMaterial(s, glm::vec3(0.4f));
    test::addGround(s, 0.0f, 40.0f, ground);
    test::addQuad(s, {-10, 3, -3}, {-4, 3, -3}, {-4, 3, 3}, {-10, 3, 3}, down);  // faces -Y
    test::addQuad(s, {4, 3, 3}, {10, 3, 3}, {10, 3, -3}, {4, 3, -3}, up);        // faces +Y
    if (sky) s.skyRadiance = glm::vec3(1.0f);
    SceneTracer tracer(s);
    const std::vector<SurfacePoint> pts = sampleSurfacePoints(tracer, 4000, 5);
    int groundPoints = 0, downPoints = 0, upPoints = 0;
    for (const SurfacePoint& p : pts) {
      const uint32_t m = s.triangleMaterial[p.triangle];
      if (m == ground) {
        ++groundPoints;
        EXPECT_GT(p.normal.y, 0.99f) << "a ground point is on its top, never its underside; sky " << sky
                                     << " at " << p.position.x << " " << p.position.z;
      } else if (m == down) {
        ++downPoints;
        EXPECT_LT(p.normal.y, -0.99f) << "the down-facing roof is seen from the ground; sky " << sky;
      } else {
        ++upPoints;
        EXPECT_NEAR(p.normal.y, sky ? 1.0f : -1.0f, 1e-5f)
            << "the up-facing roof's top is open under a sky only; sky " << sky;
      }
    }
    EXPECT_GT(downPoints, 0);
    EXPECT_GT(upPoints, 0);
    if (sky) {
      EXPECT_EQ(pts.size(), 4000u);
      EXPECT_GT(groundPoints, 3500) << "the ground's top is most of the open area";
    } else {
      // Under a black sky the ground sees the void from both sides: the roofs' undersides are all there is.
      EXPECT_EQ(groundPoints, 0);
    }
  }
}
}  // namespace
}  // namespace tetraprobe
