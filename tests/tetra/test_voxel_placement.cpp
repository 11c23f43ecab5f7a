// Adaptive voxel placement, push-out and merging, checked against brute force on tiny scenes.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <set>

#include "test_support.h"
#include "tetraprobe/common/error.h"
#include "tetraprobe/tetra/placement.h"
#include "tetraprobe/tetra/tetrahedralize.h"

namespace tetraprobe {
namespace {

using test::addBox;
using test::addQuad;

// A floor, a tilted triangle and a small solid box: flat, oblique and closed geometry.
Scene smallScene() {
  Scene s;
  addQuad(s, {0, 0, 0}, {0, 0, 4}, {4, 0, 4}, {4, 0, 0});
  const uint32_t base = uint32_t(s.positions.size());
  s.positions.insert(s.positions.end(), {{0.3f, 0.7f, 0.2f}, {3.1f, 2.9f, 1.3f}, {1.2f, 1.9f, 3.6f}});
  s.triangles.push_back({base, base + 1, base + 2});
  s.triangleMaterial.push_back(0);
  addBox(s, {2.6f, 0.0f, 2.6f}, {3.4f, 0.8f, 3.4f}, true);
  return s;
}

bool voxelHoldsGeometry(const Scene& s, const glm::dvec3& lo, const glm::dvec3& hi) {
  for (const auto& t : s.triangles)
    if (triangleBoxOverlap(glm::dvec3(s.positions[t.x]), glm::dvec3(s.positions[t.y]),
                           glm::dvec3(s.positions[t.z]), lo, hi))
      return true;
  return false;
}

// The separating axis test decides "voxel holds geometry": pin the cases a bounding-box test gets wrong.
TEST(TriangleBox, SeparatingAxisCases) {
  const glm::dvec3 lo(0.0), hi(1.0);
  EXPECT_TRUE(triangleBoxOverlap({0.5, 0.5, 0.5}, {5, 5, 0.5}, {0.5, 5, 5}, lo, hi));  // vertex inside
  EXPECT_TRUE(triangleBoxOverlap({-5, 0.5, -5}, {5, 0.5, -5}, {0, 0.5, 10}, lo, hi));  // cuts through
  EXPECT_TRUE(triangleBoxOverlap({1, 0, 0}, {3, 0, 0}, {1, 3, 0}, lo, hi));            // touches an edge
  EXPECT_FALSE(triangleBoxOverlap({1.01, 0, 0}, {3, 0, 0}, {1.01, 3, 0}, lo, hi));     // just beside
  // Bounding boxes overlap, but the triangle's plane passes by the corner (triangle-normal axis).
  EXPECT_FALSE(triangleBoxOverlap({3.1, 0, 0}, {0, 3.1, 0}, {0, 0, 3.1}, lo, hi));
  EXPECT_TRUE(triangleBoxOverlap({2.9, 0, 0}, {0, 2.9, 0}, {0, 0, 2.9}, lo, hi));
  // A thin triangle in the plane x + y = 2.2, whose bounding box holds the whole box.
  EXPECT_FALSE(triangleBoxOverlap({-1, 3.2, 0.5}, {3.2, -1, 0.5}, {3.2, -1, 0.6}, lo, hi));
  // A triangle leaning over the box edge x = y = 1 with an overlapping bounding box.
  EXPECT_FALSE(triangleBoxOverlap({2.2, 0.5, -1}, {0.5, 2.2, 2}, {1.5, 1.5, 3}, lo, hi));
}

// Valient's rule: a surface probe sits at the centre of every empty voxel (inside the level's bounds) that
// touches a voxel with geometry, and nowhere else. Cross-checked against brute-force triangle-box tests over
// the whole grid.
TEST(VoxelPlacement, SurfaceProbesLieInEmptyVoxelsNextToGeometry) {
  const Scene scene = smallScene();
  VoxelPlacementOptions opt;
  opt.spacing = 0.5;
  opt.maxSpacing = 2.0;
  opt.fillerSpacing = 0.0;
  const PlacedProbes placed = placeVoxelProbes(scene, opt);
  std::set<std::array<int64_t, 3>> surface;
  // Voxel centres on the lattice spacing * Z^3; the first voxel starts 1.5 spacings below floor(min).
  const glm::dvec3 origin = glm::dvec3(-1.5 * opt.spacing);
  for (size_t i = 0; i < placed.size(); ++i) {
    if (placed.kinds[i] != ProbeKind::kSurface) continue;
    const glm::dvec3 c = (placed.positions[i] - origin) / opt.spacing - 0.5;
    const std::array<int64_t, 3> cell{std::llround(c.x), std::llround(c.y), std::llround(c.z)};
    ASSERT_NEAR(c.x, double(cell[0]), 1e-9) << "surface probe off a voxel centre";
    EXPECT_TRUE(surface.insert(cell).second) << "two surface probes in one voxel";
    EXPECT_EQ(placed.spacing[i], opt.spacing);
  }
  glm::vec3 flo, fhi;
  sceneBounds(scene, flo, fhi);
  const glm::dvec3 blo(flo), bhi(fhi);
  // Brute force over the scene bounds grown by two voxels.
  size_t expected = 0;
  for (int64_t z = -1; z < 12; ++z)
    for (int64_t y = -1; y < 9; ++y)
      for (int64_t x = -1; x < 12; ++x) {
        auto box = [&](int64_t a, int64_t b, int64_t c, glm::dvec3& lo, glm::dvec3& hi) {
          lo = origin + glm::dvec3(a, b, c) * opt.spacing;
          hi = lo + glm::dvec3(opt.spacing);
        };
        glm::dvec3 lo, hi;
        box(x, y, z, lo, hi);
        const glm::dvec3 centre = 0.5 * (lo + hi);  // probes stay inside the scene bounds
        const bool inDomain = centre.x >= blo.x && centre.y >= blo.y && centre.z >= blo.z &&
                              centre.x <= bhi.x && centre.y <= bhi.y && centre.z <= bhi.z;
        const bool holds = voxelHoldsGeometry(scene, lo, hi);
        bool touches = false;
        for (int dz = -1; dz <= 1 && !touches; ++dz)
          for (int dy = -1; dy <= 1 && !touches; ++dy)
            for (int dx = -1; dx <= 1 && !touches; ++dx) {
              if (!dx && !dy && !dz) continue;
              glm::dvec3 nlo, nhi;
              box(x + dx, y + dy, z + dz, nlo, nhi);
              touches = voxelHoldsGeometry(scene, nlo, nhi);
            }
        const bool want = inDomain && !holds && touches;
        expected += want;
        EXPECT_EQ(want, surface.count({x, y, z}) == 1)
            << "voxel " << x << "," << y << "," << z << " holds=" << holds << " touches=" << touches;
      }
  EXPECT_EQ(surface.size(), expected);
  EXPECT_GT(expected, 100u);
}

// Open space coarsens with distance from geometry, never beyond maxSpacing; fine volumes stay fine.
TEST(VoxelPlacement, CoarsensAwayFromGeometryAndKeepsFineVolumes) {
  Scene scene;
  addQuad(scene, {0, 0, 0}, {0, 0, 40}, {40, 0, 40}, {40, 0, 0});
  scene.materials.push_back({});
  Volume v;
  v.name = "arena";
  v.min = {30, 20, 30};
  v.max = {33, 22, 33};
  scene.fineVolumes.push_back(v);
  VoxelPlacementOptions opt;
  opt.spacing = 1.0;
  opt.maxSpacing = 10.0;
  opt.fillerSpacing = 0.0;
  const PlacedProbes p = placeVoxelProbes(scene, opt);
  std::set<double> spacings;
  size_t volume = 0;
  for (size_t i = 0; i < p.size(); ++i) {
    spacings.insert(p.spacing[i]);
    EXPECT_LE(p.spacing[i], opt.maxSpacing);
    if (p.kinds[i] == ProbeKind::kVolume) {
      ++volume;
      EXPECT_TRUE(test::insideBox(p.positions[i], v.min - glm::vec3(1), v.max + glm::vec3(1)));
    }
    const glm::dvec3& q = p.positions[i];
    if (p.kinds[i] == ProbeKind::kOpen && q.x > 1 && q.x < 39 && q.z > 1 && q.z < 39) {
      EXPECT_GT(std::abs(q.y), 1.0);  // above (or below) the floor, open cells are not next to it
    }
  }
  EXPECT_EQ(spacings, (std::set<double>{1.0, 2.0, 4.0, 8.0}));
  EXPECT_GE(volume, size_t(3 * 2 * 3));
}

// The same scene gives the same probes in the same order, whatever the thread count.
TEST(VoxelPlacement, DeterministicAcrossThreads) {
  const Scene scene = smallScene();
  VoxelPlacementOptions opt;
  opt.spacing = 0.25;
  opt.maxSpacing = 2.0;
  opt.fillerSpacing = 1.0;
  opt.threads = 1;
  const PlacedProbes a = placeVoxelProbes(scene, opt);
  opt.threads = 3;
  const PlacedProbes b = placeVoxelProbes(scene, opt);
  EXPECT_EQ(a.positions, b.positions);
  EXPECT_EQ(a.kinds, b.kinds);
  EXPECT_GT(a.count(ProbeKind::kSurface), 0u);
}

TEST(VoxelPlacement, RejectsBadOptionsAndEmptyScenes) {
  const Scene scene = smallScene();
  VoxelPlacementOptions opt;
  opt.spacing = 0.0;
  EXPECT_THROW(placeVoxelProbes(scene, opt), InputError);
  opt.spacing = std::numeric_limits<double>::quiet_NaN();
  EXPECT_THROW(placeVoxelProbes(scene, opt), InputError);
  opt.spacing = 2.0;
  opt.maxSpacing = 1.0;
  EXPECT_THROW(placeVoxelProbes(scene, opt), InputError);
  opt.maxSpacing = 10.0;
  opt.fillerSpacing = -1.0;
  EXPECT_THROW(placeVoxelProbes(scene, opt), InputError);
  opt.fillerSpacing = 4.0;
  EXPECT_THROW(placeVoxelProbes(Scene{}, opt), InputError);
  opt.spacing = 1e-6;  // 4 m at 1 um: more than 2^20 voxels per axis
  EXPECT_THROW(placeVoxelProbes(scene, opt), InputError);
  opt.spacing = 0.01;
  opt.maxProbes = 1000;
  EXPECT_THROW(placeVoxelProbes(scene, opt), InputError);
}

// Probes must not sit inside solid geometry: after push-out, none is inside the closed box's walls, and
// none is closer than 0.05 x spacing to a surface along the test rays.
TEST(PushOut, NoProbeInsideClosedBoxWalls) {
  Scene scene;
  addBox(scene, {0, 0, 0}, {6, 4, 6}, false);                   // the room (inward faces)
  addBox(scene, {2.2f, 0.0f, 2.2f}, {3.9f, 1.7f, 3.9f}, true);  // a solid block (outward faces)
  VoxelPlacementOptions opt;
  opt.spacing = 0.5;
  opt.maxSpacing = 2.0;
  opt.fillerSpacing = 2.0;
  PlacedProbes p = placeVoxelProbes(scene, opt);
  size_t insideBefore = 0;
  for (const auto& q : p.positions) insideBefore += test::insideBox(q, {2.2f, 0, 2.2f}, {3.9f, 1.7f, 3.9f});
  const PushOutStats stats = pushOutProbes(p, test::bruteForceClearance(scene));
  EXPECT_GT(insideBefore, 0u) << "the test needs probes inside the block to begin with";
  EXPECT_GT(stats.rejected + stats.pushed, 0u);
  for (const auto& q : p.positions) {
    EXPECT_FALSE(test::insideBox(q, {2.2f, 0, 2.2f}, {3.9f, 1.7f, 3.9f})) << q.x << " " << q.y << " " << q.z;
    EXPECT_TRUE(test::insideBox(q, {0, 0, 0}, {6, 4, 6}))
        << "outside the room: " << q.x << " " << q.y << " " << q.z;
  }
}

// The inside rule, literally: APV's 25 % of back-face hits, or back faces the majority of the hits once at
// least 1/16 of the rays hit them (outside a closed level), and nothing for a few stray back hits.
TEST(PushOut, InsideRuleCases) {
  EXPECT_TRUE(insideByRays(64, 64, 17));   // > 25 % back
  EXPECT_FALSE(insideByRays(64, 64, 16));  // exactly 25 %, back faces a minority of the hits
  EXPECT_TRUE(insideByRays(64, 10, 10));   // outside a closed room's corner: few hits, all back
  EXPECT_FALSE(insideByRays(64, 3, 3));    // three stray back hits
  EXPECT_FALSE(insideByRays(64, 40, 0));   // an ordinary room probe
  EXPECT_FALSE(insideByRays(0, 0, 0));
}

// User probes are never moved, even inside geometry; the others are.
TEST(PushOut, UserProbesAreNeverMoved) {
  Scene scene;
  addBox(scene, {0, 0, 0}, {1, 1, 1}, true);
  PlacedProbes p;
  p.add({0.5, 0.5, 0.5}, ProbeKind::kUser, 1.0);        // inside the solid box
  p.add({0.5, 0.5, 0.5001}, ProbeKind::kSurface, 1.0);  // same place, automatic
  p.add({1.01, 0.5, 0.5}, ProbeKind::kSurface, 1.0);    // 0.01 m off a face: pushed to 0.05 m
  const PushOutStats stats = pushOutProbes(p, test::bruteForceClearance(scene));
  ASSERT_GE(p.size(), 2u);
  EXPECT_EQ(p.positions[0], glm::dvec3(0.5, 0.5, 0.5));
  EXPECT_EQ(p.kinds[0], ProbeKind::kUser);
  EXPECT_EQ(stats.pushed + stats.rejected, 2u);
  const glm::dvec3 last = p.positions.back();
  EXPECT_NEAR(last.x, 1.05, 1e-3);  // the closest of 64 rays is not quite perpendicular
}

// No two probes closer than tolerance x the larger local spacing survive, user probes all do, and the
// result matches a quadratic brute force on which pairs conflict.
TEST(Merge, ToleranceRespectedAndUserProbesKept) {
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> u(0.0, 3.0);
  const double spacings[3] = {0.25, 1.0, 4.0};
  PlacedProbes p;
  for (int i = 0; i < 3000; ++i) {
    const ProbeKind kind = i % 50 == 0 ? ProbeKind::kUser : ProbeKind(1 + i % 4);
    p.add({u(rng), u(rng), u(rng)}, kind, spacings[i % 3]);
  }
  const PlacedProbes before = p;
  const size_t dropped = mergeProbes(p, 0.1);
  EXPECT_GT(dropped, 0u);
  EXPECT_EQ(p.size() + dropped, before.size());
  EXPECT_EQ(p.count(ProbeKind::kUser), before.count(ProbeKind::kUser));
  for (size_t i = 0; i < p.size(); ++i)
    for (size_t j = i + 1; j < p.size(); ++j) {
      if (p.kinds[i] == ProbeKind::kUser && p.kinds[j] == ProbeKind::kUser) continue;
      const double tol = 0.1 * std::max(p.spacing[i], p.spacing[j]);
      ASSERT_GE(glm::distance(p.positions[i], p.positions[j]), tol) << i << " " << j;
    }
  // Deterministic.
  PlacedProbes again = before;
  mergeProbes(again, 0.1);
  EXPECT_EQ(again.positions, p.positions);
}

// The whole build-side chain with user probes: every user probe ends up a mesh vertex at exactly its input
// position.
TEST(VoxelPlacement, UserProbesAreVerticesAndUnmoved) {
  const Scene scene = smallScene();
  VoxelPlacementOptions opt;
  opt.spacing = 0.5;
  opt.maxSpacing = 2.0;
  PlacedProbes p;
  const std::vector<glm::dvec3> user = {
      {1.0, 1.0, 1.0}, {1.01, 1.0, 1.0}, {2.75, 0.25, 2.75}, {0.3, 0.7, 0.2}};
  for (const auto& u : user) p.add(u, ProbeKind::kUser, opt.spacing);
  const PlacedProbes autoProbes = placeVoxelProbes(scene, opt);
  for (size_t i = 0; i < autoProbes.size(); ++i)
    p.add(autoProbes.positions[i], autoProbes.kinds[i], autoProbes.spacing[i]);
  pushOutProbes(p, test::bruteForceClearance(scene));
  mergeProbes(p, 0.1);
  const TetMesh mesh = tetrahedralizeDelaunay(p.positions);
  std::vector<bool> vertex(p.size(), false);
  for (const auto& t : mesh.tets)
    for (int32_t v : t) vertex[size_t(v)] = true;
  for (size_t k = 0; k < user.size(); ++k) {
    ASSERT_EQ(p.positions[k], user[k]);
    EXPECT_EQ(p.kinds[k], ProbeKind::kUser);
    EXPECT_TRUE(vertex[k]) << "user probe " << k;
  }
}

}  // namespace
}  // namespace tetraprobe
