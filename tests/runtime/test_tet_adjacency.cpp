// linkTetNeighbours: the neighbours a level file no longer stores, derived from the tets' probes, must be the
// tetrahedralization's own (checked against CGAL's adjacency and a brute-force face search) whatever the tet
// and vertex order; a face of three tets is named, never linked.
#include <gtest/gtest.h>

#include <algorithm>
#include <random>

#include "test_levels.h"
#include "tetraprobe/runtime/tet_adjacency.h"

namespace tetraprobe {
namespace {

// For each face, the other tet holding all three of its probes, by scanning every tet: O(T^2).
std::vector<Tet> bruteForceNeighbours(std::vector<Tet> tets) {
  for (size_t t = 0; t < tets.size(); ++t)
    for (int f = 0; f < 4; ++f) {
      tets[t].n[f] = -1;
      for (size_t u = 0; u < tets.size(); ++u) {
        if (u == t) continue;
        int shared = 0;
        for (int i = 0; i < 4; ++i)
          if (i != f) shared += std::count(tets[u].v, tets[u].v + 4, tets[t].v[i]) > 0;
        if (shared == 3) tets[t].n[f] = int32_t(u);
      }
    }
  return tets;
}

bool sameNeighbours(const std::vector<Tet>& a, const std::vector<Tet>& b) {
  for (size_t t = 0; t < a.size(); ++t)
    if (!std::equal(a[t].n, a[t].n + 4, b[t].n)) return false;
  return a.size() == b.size();
}

TEST(TetAdjacency, EqualsTheTetrahedralizationsOwnNeighbours) {
  // Random points, a regular lattice (every cell cospherical: Delaunay's degenerate case) and a flat slab.
  std::vector<std::vector<glm::dvec3>> sets = {test::randomBoxPoints(300, 5, {-4, -2, -3}, {4, 2, 3}),
                                               test::randomBoxPoints(60, 9, {0, 0, 0}, {10, 0.01, 10})};
  std::vector<glm::dvec3> lattice;
  for (int x = 0; x < 6; ++x)
    for (int y = 0; y < 5; ++y)
      for (int z = 0; z < 4; ++z) lattice.emplace_back(x, y, z);
  sets.push_back(lattice);
  for (const auto& pts : sets) {
    const Level level = test::makeLevel(pts, glm::dvec3(0.0));
    ASSERT_GT(level.tets.size(), 10u);
    std::vector<Tet> linked = level.tets;
    for (Tet& t : linked) t.n[0] = t.n[1] = t.n[2] = t.n[3] = 12345;  // stale values must not survive
    ASSERT_EQ(linkTetNeighbours(linked, level.probes.size()), "");
    EXPECT_TRUE(sameNeighbours(linked, level.tets)) << pts.size() << " points";
  }
}

TEST(TetAdjacency, DoesNotDependOnTetOrVertexOrder) {
  const Level level = test::makeLevel(test::randomBoxPoints(120, 11, {0, 0, 0}, {3, 3, 3}), glm::dvec3(0.0));
  std::vector<Tet> tets = level.tets;
  std::mt19937_64 rng(3);
  std::shuffle(tets.begin(), tets.end(), rng);
  for (Tet& t : tets) std::shuffle(t.v, t.v + 4, rng);
  ASSERT_EQ(linkTetNeighbours(tets, level.probes.size()), "");
  EXPECT_TRUE(sameNeighbours(tets, bruteForceNeighbours(tets)));
  size_t hull = 0, hullWas = 0;
  for (const Tet& t : tets) hull += size_t(std::count(t.n, t.n + 4, -1));
  for (const Tet& t : level.tets) hullWas += size_t(std::count(t.n, t.n + 4, -1));
  EXPECT_EQ(hull, hullWas);
}

TEST(TetAdjacency, FaceOfThreeTetsIsAnErrorNamingIt) {
  // Two tets on face (0, 1, 2) are neighbours; a third on it is not a tetrahedralization.
  std::vector<Tet> tets(3);
  const int32_t apex[3] = {3, 4, 5};
  for (int k = 0; k < 3; ++k) {
    tets[size_t(k)].v[0] = 0, tets[size_t(k)].v[1] = 1, tets[size_t(k)].v[2] = 2,
    tets[size_t(k)].v[3] = apex[k];
  }
  std::vector<Tet> two(tets.begin(), tets.begin() + 2);
  ASSERT_EQ(linkTetNeighbours(two, 6), "");
  EXPECT_EQ(two[0].n[3], 1);
  EXPECT_EQ(two[1].n[3], 0);
  EXPECT_EQ(two[0].n[0], -1);
  const std::string e = linkTetNeighbours(tets, 6);
  EXPECT_NE(e.find("the face on probes (0, 1, 2) is shared by 3 tets (0, 1, 2)"), std::string::npos) << e;
  std::vector<Tet> none;
  EXPECT_EQ(linkTetNeighbours(none, 0), "");
}

}  // namespace
}  // namespace tetraprobe
