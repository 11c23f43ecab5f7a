// The late sliver pass (tetra/final_slivers.h): probes appended after the filler (hole and refinement probes)
// make slivers; the pass brings the worst tet back to the bound the earlier mesh had.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <random>

#include <glm/geometric.hpp>

#include "tetraprobe/tetra/final_slivers.h"
#include "tetraprobe/tetra/quality.h"

namespace tetraprobe {
namespace {

// A body-centred cubic lattice (1 m cubes and their centres, the centres jittered by up to `jitter` m per axis:
// at 0.2 the worst tet has a 3.7-degree min dihedral, as the filler leaves real levels), then late probes a few centimetres off the middles of cube faces, as hole and
// refinement probes land a short offset in front of a surface next to the probes already there: their tets
// are slivers far below the lattice's worst.
struct LateCase {
  std::vector<glm::dvec3> points;
  std::vector<double> spacing;
  size_t firstLate = 0;
};

LateCase latticeWithLateProbes(double jitter) {
  LateCase l;
  std::mt19937_64 rng(29);
  std::uniform_real_distribution<double> j(-1.0, 1.0);
  for (int z = 0; z < 6; ++z)
    for (int y = 0; y < 6; ++y)
      for (int x = 0; x < 6; ++x) {
        l.points.emplace_back(x, y, z);
        if (x < 5 && y < 5 && z < 5)
          l.points.push_back(glm::dvec3(x + 0.5, y + 0.5, z + 0.5) +
                             jitter * glm::dvec3(j(rng), j(rng), j(rng)));
      }
  l.firstLate = l.points.size();
  std::uniform_int_distribution<int> cell(1, 3);
  std::uniform_real_distribution<double> off(-0.04, 0.04);
  for (int i = 0; i < 60; ++i) {
    const glm::dvec3 p(cell(rng) + 0.5, cell(rng) + (i % 3 == 0 ? 0.5 : 0.0),
                       cell(rng) + (i % 2 ? 0.5 : 0.0));
    l.points.push_back(p + glm::dvec3(off(rng), off(rng), off(rng)));
  }
  l.spacing.assign(l.points.size(), 1.0);
  return l;
}

double worstOf(const std::vector<glm::dvec3>& pts) {
  return meshQuality(pts, tetrahedralizeDelaunay(pts)).worstMinDihedralDeg;
}

// The worst min dihedral of the case's mesh before its late probes: the pass's bound.
double earlyWorst(const LateCase& l) {
  return worstOf(std::vector<glm::dvec3>(l.points.begin(), l.points.begin() + std::ptrdiff_t(l.firstLate)));
}

// The pass's options for the case: its late probes, bounded by the worst before them (removal only: no
// fillers, no moves).
FinalSliverOptions lateOptions(const LateCase& l) {
  FinalSliverOptions o;
  o.targetDeg = earlyWorst(l);
  o.firstLate = l.firstLate;
  return o;
}

// An inside test that vetoes every candidate.
std::vector<uint8_t> allInside(const std::vector<glm::dvec3>& pts) {
  return std::vector<uint8_t>(pts.size(), 1);
}

// The points a result keeps, where they now stand (moved ones moved), in their order, then its fillers: the
// points its mesh is the Delaunay mesh of.
std::vector<glm::dvec3> keptPoints(const LateCase& l, const FinalSliverResult& r) {
  std::vector<glm::dvec3> at = l.points;
  for (const auto& [i, p] : r.moved) at[i] = p;
  std::vector<glm::dvec3> kept;
  for (size_t i = 0; i < at.size(); ++i)
    if (!std::binary_search(r.removed.begin(), r.removed.end(), i)) kept.push_back(at[i]);
  kept.insert(kept.end(), r.added.begin(), r.added.end());
  return kept;
}

// The invariant the bake relies on: whatever the late probes did, the final mesh's worst min dihedral is at
// least the worst before them, and only late probes (never an earlier one) are dropped.
TEST(LateSlivers, FinalWorstDihedralIsNoWorseThanBeforeLateProbes) {
  const LateCase l = latticeWithLateProbes(0.2);
  const double bound = earlyWorst(l);
  ASSERT_GT(bound, 1.0) << "the early mesh has the worst slivers: the case tests nothing";
  for (size_t budget : {size_t(0), size_t(20)}) {
    FinalSliverOptions o;
    o.targetDeg = bound;
    o.firstLate = l.firstLate;
    o.maxFillers = budget;
    const FinalSliverResult r = fixFinalSlivers(l.points, l.spacing, o, nullptr);
    ASSERT_LT(r.before.worstMinDihedralDeg, bound)
        << "the late probes made no sliver: the case tests nothing";
    EXPECT_GE(r.after.worstMinDihedralDeg, bound) << "budget " << budget;
    EXPECT_LE(r.added.size(), budget);
    EXPECT_LT(r.removed.size(), l.points.size() - l.firstLate) << "every late probe dropped";
    for (size_t i : r.removed) EXPECT_GE(i, l.firstLate) << "an earlier probe was dropped";
    EXPECT_TRUE(std::is_sorted(r.removed.begin(), r.removed.end()));
    // The mesh is the Delaunay mesh of the kept points in their order, then the fillers.
    const std::vector<glm::dvec3> kept = keptPoints(l, r);
    EXPECT_EQ(tetrahedralizeDelaunay(kept).tets, r.mesh.tets);
    EXPECT_EQ(meshQuality(kept, r.mesh).worstMinDihedralDeg, r.after.worstMinDihedralDeg);
    // Deterministic.
    const FinalSliverResult again = fixFinalSlivers(l.points, l.spacing, o, nullptr);
    EXPECT_EQ(again.removed, r.removed);
    EXPECT_EQ(again.added, r.added);
    EXPECT_EQ(again.mesh.tets, r.mesh.tets);
  }
}

// Fillers fix slivers instead of dropping the probes: with a budget, fewer late probes are dropped than
// without, and the inside test still vetoes them (everything inside: the removal-only answer).
TEST(LateSlivers, FillersSpareLateProbesAndObeyTheInsideTest) {
  const LateCase l = latticeWithLateProbes(0.2);
  FinalSliverOptions o = lateOptions(l);
  const FinalSliverResult none = fixFinalSlivers(l.points, l.spacing, o, nullptr);
  o.maxFillers = 200;
  const FinalSliverResult some = fixFinalSlivers(l.points, l.spacing, o, nullptr);
  EXPECT_LE(some.removed.size(), none.removed.size());
  const FinalSliverResult vetoed = fixFinalSlivers(l.points, l.spacing, o, allInside);
  EXPECT_TRUE(vetoed.added.empty());
  EXPECT_EQ(vetoed.removed, none.removed);
}

// Moving a late probe off its slivers (step 1b) spares it: with move rounds the pass still reaches the bound,
// drops fewer late probes than without, moves only late probes (by at most maxNudge x spacing), and its mesh is
// the Delaunay mesh of the kept points where they now stand; where the inside test vetoes every move, it drops
// exactly what the removal alone drops.
TEST(LateSlivers, MovesSpareLateProbesAndStillReachTheBound) {
  const LateCase l = latticeWithLateProbes(0.2);
  FinalSliverOptions o = lateOptions(l);
  const FinalSliverResult none = fixFinalSlivers(l.points, l.spacing, o, nullptr);
  o.nudgeRounds = 4;
  const FinalSliverResult moved = fixFinalSlivers(l.points, l.spacing, o, nullptr);
  std::printf("[lattice] dropped %zu without moves; with them %zu moved, %zu dropped (%d rounds)\n",
              none.removed.size(), moved.moved.size(), moved.removed.size(), moved.nudgeRounds);
  EXPECT_GE(moved.after.worstMinDihedralDeg, o.targetDeg);
  EXPECT_GT(moved.nudgeRounds, 0);
  EXPECT_LT(moved.removed.size(), none.removed.size());
  for (const auto& [i, p] : moved.moved) {
    EXPECT_GE(i, l.firstLate) << "an earlier probe was moved";
    // At most maxNudge x spacing a round.
    EXPECT_LE(glm::distance(p, l.points[i]), o.nudgeRounds * o.maxNudge * l.spacing[i] * (1.0 + 1e-9));
    EXPECT_FALSE(std::binary_search(moved.removed.begin(), moved.removed.end(), i));
  }
  EXPECT_EQ(tetrahedralizeDelaunay(keptPoints(l, moved)).tets, moved.mesh.tets);
  const FinalSliverResult vetoed = fixFinalSlivers(l.points, l.spacing, o, allInside);
  EXPECT_TRUE(vetoed.moved.empty());
  EXPECT_EQ(vetoed.removed, none.removed);
}

// Nothing to do: a mesh already at the bound comes back unchanged (no probe dropped, none added).
TEST(LateSlivers, MeshAtTheBoundIsLeftAlone) {
  const LateCase l = latticeWithLateProbes(0.2);
  FinalSliverOptions o;
  o.targetDeg = 0.0;
  o.firstLate = l.firstLate;
  o.maxFillers = 50;
  const FinalSliverResult r = fixFinalSlivers(l.points, l.spacing, o, nullptr);
  EXPECT_TRUE(r.removed.empty());
  EXPECT_TRUE(r.added.empty());
  EXPECT_EQ(r.after.worstMinDihedralDeg, r.before.worstMinDihedralDeg);
}

}  // namespace
}  // namespace tetraprobe
