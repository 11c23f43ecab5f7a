// Tet quality measures on literal tets, and sliver filler probes.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "tetraprobe/tetra/filler.h"
#include "tetraprobe/tetra/quality.h"

namespace tetraprobe {
namespace {

// A regular tet has the textbook values: dihedral acos(1/3) = 70.53 deg, radius-edge sqrt(6)/4.
TEST(Quality, RegularTetHasTextbookValues) {
  const double s = 1.0 / std::sqrt(2.0);
  const TetQuality q = tetQuality({1, 0, -s}, {-1, 0, -s}, {0, 1, s}, {0, -1, s});
  EXPECT_NEAR(q.minDihedralDeg, std::acos(1.0 / 3.0) * 180.0 / M_PI, 1e-9);
  EXPECT_NEAR(q.radiusEdge, std::sqrt(6.0) / 4.0, 1e-9);
  EXPECT_GE(q.condition, 1.0);
  EXPECT_LT(q.condition, 1.5);
}

// Orientation does not matter; a sliver (four nearly coplanar points spread in a square) has a tiny
// dihedral angle but a harmless radius-edge ratio, which is why the filler uses the dihedral.
TEST(Quality, SliverHasSmallDihedralAndLargeCondition) {
  const TetQuality a = tetQuality({0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1});
  const TetQuality b = tetQuality({0, 0, 0}, {0, 1, 0}, {1, 0, 0}, {0, 0, 1});
  EXPECT_DOUBLE_EQ(a.minDihedralDeg, b.minDihedralDeg);
  const TetQuality sliver = tetQuality({0, 0, 0}, {1, 1, 0}, {1, 0, 0.01}, {0, 1, 0.01});
  EXPECT_LT(sliver.minDihedralDeg, 2.0);
  EXPECT_LT(sliver.radiusEdge, 1.0);
  EXPECT_GT(sliver.condition, 50.0);
  const TetQuality flat = tetQuality({0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {1, 1, 0});
  EXPECT_EQ(flat.minDihedralDeg, 0.0);
  EXPECT_TRUE(std::isinf(flat.radiusEdge));
}

TEST(Quality, HistogramCountsEveryTet) {
  std::vector<glm::dvec3> pts;
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  for (int i = 0; i < 300; ++i) pts.emplace_back(u(rng), u(rng), u(rng));
  const TetMesh mesh = tetrahedralizeDelaunay(pts);
  const MeshQuality q = meshQuality(pts, mesh);
  uint64_t total = 0;
  for (uint64_t c : q.minDihedralHistogram) total += c;
  EXPECT_EQ(total, mesh.tets.size());
  EXPECT_GT(q.worstMinDihedralDeg, 0.0);
  EXPECT_LE(q.worstMinDihedralDeg, q.meanMinDihedralDeg);
}

// Two parallel 8 x 8 planes of probes 1 m apart, the interior ones jittered in their plane: the tets
// spanning the gap that take one edge from each plane are slivers (the edge rows keep the hull faces exactly
// planar, so the slivers are interior ones that probes can fix). Filler probes between the planes must
// raise the worst minimum dihedral angle.
PlacedProbes twoPlanes() {
  PlacedProbes p;
  std::mt19937_64 rng(9);
  std::uniform_real_distribution<double> j(-0.1, 0.1);
  for (int plane = 0; plane < 2; ++plane)
    for (int y = 0; y < 8; ++y)
      for (int x = 0; x < 8; ++x) {
        glm::dvec3 q(x, y, plane);
        if (x > 0 && x < 7 && y > 0 && y < 7) q += glm::dvec3(j(rng), j(rng), 0.0);
        p.add(q, plane ? ProbeKind::kSurface : ProbeKind::kUser, 1.0);
      }
  return p;
}

TEST(Filler, ImprovesWorstDihedralOnTwoPlanesCgal) {
  PlacedProbes p = twoPlanes();
  const size_t n = p.size();
  const PlacedProbes original = p;
  FillerOptions opt;
  opt.snapToLattice = false;  // jittered planes are no voxel lattice
  const FillerResult r = addSliverFillers(p, opt, nullptr);
  EXPECT_GT(r.added, 0u);
  EXPECT_EQ(p.size(), n + r.added);
  EXPECT_GT(r.after.worstMinDihedralDeg, r.before.worstMinDihedralDeg)
      << "before " << r.before.worstMinDihedralDeg << " after " << r.after.worstMinDihedralDeg;
  EXPECT_LT(r.after.tetsBelow10Deg, r.before.tetsBelow10Deg)
      << "before " << r.before.tetsBelow10Deg << " after " << r.after.tetsBelow10Deg;
  for (size_t i = 0; i < n; ++i) EXPECT_EQ(p.positions[i], original.positions[i]);  // probes never move
  for (size_t i = n; i < p.size(); ++i) EXPECT_EQ(p.kinds[i], ProbeKind::kFiller);
  // Deterministic.
  PlacedProbes q = original;
  const FillerResult again = addSliverFillers(q, opt, nullptr);
  EXPECT_EQ(q.positions, p.positions);
  EXPECT_EQ(again.mesh.tets, r.mesh.tets);
}

TEST(Filler, ImprovesWorstDihedralOnTwoPlanesTetGen) {
  PlacedProbes p = twoPlanes();
  FillerOptions opt;
  opt.backend = TetraBackend::kTetGen;
  const FillerResult r = addSliverFillers(p, opt, nullptr);
  EXPECT_GT(r.after.worstMinDihedralDeg, r.before.worstMinDihedralDeg)
      << "before " << r.before.worstMinDihedralDeg << " after " << r.after.worstMinDihedralDeg;
  EXPECT_GT(r.after.worstMinDihedralDeg, 5.0);
}

// The inside callback vetoes candidates (e.g. inside geometry): nothing is added when it rejects all.
TEST(Filler, InsideCallbackRejectsCandidates) {
  PlacedProbes p = twoPlanes();
  const size_t n = p.size();
  FillerOptions opt;
  opt.snapToLattice = false;
  const FillerResult r = addSliverFillers(
      p, opt, [](const std::vector<glm::dvec3>& pts) { return std::vector<uint8_t>(pts.size(), 1); });
  EXPECT_EQ(r.added, 0u);
  EXPECT_GT(r.rejected, 0u);
  EXPECT_EQ(p.size(), n);
}

}  // namespace
}  // namespace tetraprobe
