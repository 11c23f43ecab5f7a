// Filler probes where tets are slivers. Valient (GDC 2014) adds filler probes in empty space because the
// Delaunay tets of surface probes come out long and flat; here the slivers are found by their minimum
// dihedral angle and fixed the way Delaunay refinement does (Shewchuk 1998; Si 2015): a point at the
// circumcentre (or centroid when the circumcentre is far away), then re-tetrahedralize, a bounded number of
// rounds. The TetGen backend lets TetGen's own quality refinement choose the points.
#include "tetraprobe/tetra/filler.h"

#include <algorithm>
#include <cmath>

#include <glm/common.hpp>
#include <glm/geometric.hpp>

namespace tetraprobe {
namespace {

TetMesh delaunay(const std::vector<glm::dvec3>& points, TetraBackend backend) {
  if (backend == TetraBackend::kTetGen) return tetrahedralizeTetGen(points).mesh;
  return tetrahedralizeDelaunay(points);
}

// Appends the candidates that survive the merge tolerance (against existing probes and each other) and the
// inside test. Returns how many were appended; `rejected` counts the rest.
size_t appendCandidates(PlacedProbes& probes, const PlacedProbes& candidates, double tolerance,
                        const std::function<std::vector<uint8_t>(const std::vector<glm::dvec3>&)>& inside,
                        size_t& rejected) {
  // Existing probes take part as kUser so that the merge never drops them, only candidates.
  PlacedProbes all;
  const size_t n = probes.size();
  for (size_t i = 0; i < n; ++i) all.add(probes.positions[i], ProbeKind::kUser, probes.spacing[i]);
  for (size_t i = 0; i < candidates.size(); ++i)
    all.add(candidates.positions[i], ProbeKind::kFiller, candidates.spacing[i]);
  mergeProbes(all, tolerance);
  std::vector<glm::dvec3> pts(all.positions.begin() + std::ptrdiff_t(n), all.positions.end());
  std::vector<uint8_t> in(pts.size(), 0);
  if (inside && !pts.empty()) in = inside(pts);
  size_t added = 0;
  for (size_t i = 0; i < pts.size(); ++i) {
    if (in[i]) continue;
    probes.add(pts[i], ProbeKind::kFiller, all.spacing[n + i]);
    ++added;
  }
  rejected += candidates.size() - added;
  return added;
}

}  // namespace

FillerResult addSliverFillers(
    PlacedProbes& probes, const FillerOptions& options,
    const std::function<std::vector<uint8_t>(const std::vector<glm::dvec3>&)>& inside) {
  FillerResult r;
  r.mesh = delaunay(probes.positions, options.backend);
  r.before = meshQuality(probes.positions, r.mesh);
  if (options.backend == TetraBackend::kTetGen) {
    TetGenOptions tg;
    tg.refine = true;
    tg.minDihedralDeg = options.minDihedralDeg;
    tg.radiusEdge = options.tetgenRadiusEdge;
    tg.maxSteiner = int(std::min<size_t>(probes.size(), 1'000'000));
    const TetGenResult refined = tetrahedralizeTetGen(probes.positions, tg);
    PlacedProbes candidates;
    for (const glm::dvec3& p : refined.steiner) {
      // Spacing of a Steiner point: the spacing of the nearest corner's tet is not known here; use the
      // median spacing of the probes (a tolerance only).
      candidates.add(p, ProbeKind::kFiller, 0.0);
    }
    std::vector<double> sorted = probes.spacing;
    std::nth_element(sorted.begin(), sorted.begin() + std::ptrdiff_t(sorted.size() / 2), sorted.end());
    const double median = sorted.empty() ? 1.0 : sorted[sorted.size() / 2];
    for (double& s : candidates.spacing) s = median;
    r.rounds = 1;
    r.added = appendCandidates(probes, candidates, options.minDistance, inside, r.rejected);
    // Final mesh: TetGen's refinement of all kept probes with no further Steiner points (S0), so its flips
    // still remove slivers the kept points did not; a plain Delaunay mesh if TetGen adds points anyway.
    tg.maxSteiner = 0;
    TetGenResult final = tetrahedralizeTetGen(probes.positions, tg);
    TetMesh mesh =
        final.steiner.empty() ? std::move(final.mesh) : delaunay(probes.positions, options.backend);
    const MeshQuality q = meshQuality(probes.positions, mesh);
    if (q.worstMinDihedralDeg < r.before.worstMinDihedralDeg) {  // never worse: undo
      const size_t n = probes.size() - r.added;
      probes.positions.resize(n);
      probes.kinds.resize(n);
      probes.spacing.resize(n);
      r.rejected += r.added;
      r.added = 0;
      r.after = r.before;
      return r;
    }
    r.mesh = std::move(mesh);
    r.after = meshQuality(probes.positions, r.mesh);
    return r;
  }

  r.after = r.before;
  for (int round = 0; round < options.rounds; ++round) {
    PlacedProbes candidates;
    for (size_t ti = 0; ti < r.mesh.tets.size(); ++ti) {
      const auto& t = r.mesh.tets[ti];
      // A sliver with a hull face covers a concavity of the probe cloud: a point inside it only splits it
      // into more flat tets, so only interior slivers get candidates.
      const auto& nb = r.mesh.neighbours[ti];
      if (std::find(nb.begin(), nb.end(), -1) != nb.end()) continue;
      const glm::dvec3 p0 = probes.positions[size_t(t[0])], p1 = probes.positions[size_t(t[1])],
                       p2 = probes.positions[size_t(t[2])], p3 = probes.positions[size_t(t[3])];
      const TetQuality q = tetQuality(p0, p1, p2, p3);
      if (q.minDihedralDeg >= options.minDihedralDeg) continue;
      const glm::dvec3 a = p1 - p0, b = p2 - p0, c = p3 - p0;
      const double det = glm::dot(a, glm::cross(b, c));
      const glm::dvec3 centroid = 0.25 * (p0 + p1 + p2 + p3);
      double longest = 0.0;
      const glm::dvec3 pts[4] = {p0, p1, p2, p3};
      for (int i = 0; i < 4; ++i)
        for (int j = i + 1; j < 4; ++j) longest = std::max(longest, glm::distance(pts[i], pts[j]));
      glm::dvec3 candidate = centroid;
      if (det != 0.0) {
        const glm::dvec3 cc = p0 + (glm::dot(a, a) * glm::cross(b, c) + glm::dot(b, b) * glm::cross(c, a) +
                                    glm::dot(c, c) * glm::cross(a, b)) /
                                       (2.0 * det);
        if (std::isfinite(cc.x) && std::isfinite(cc.y) && std::isfinite(cc.z) &&
            glm::distance(cc, centroid) <= longest)
          candidate = cc;
      }
      double spacing = 0.0;
      for (int i = 0; i < 4; ++i) spacing += 0.25 * probes.spacing[size_t(t[size_t(i)])];
      if (options.snapToLattice && spacing > 0.0) {
        // Voxel placement puts probes on the lattice spacing * Z^3; a sliver there marks a hole in the
        // lattice, which the nearest lattice point fills with lattice-shaped tets.
        const glm::dvec3 snapped = glm::round(candidate / spacing) * spacing;
        if (glm::distance(snapped, centroid) <= longest) candidate = snapped;
      }
      candidates.add(candidate, ProbeKind::kFiller, spacing);
    }
    if (candidates.size() == 0) break;
    r.rounds = round + 1;
    const size_t added = appendCandidates(probes, candidates, options.minDistance, inside, r.rejected);
    if (!added) break;
    // Keep the round only when it did not make the worst tet worse (circumcentres of neighbouring slivers
    // can form new slivers among themselves); otherwise undo it and stop.
    TetMesh mesh = delaunay(probes.positions, options.backend);
    const MeshQuality q = meshQuality(probes.positions, mesh);
    const MeshQuality& current = r.after;
    if (q.worstMinDihedralDeg < current.worstMinDihedralDeg ||
        (q.worstMinDihedralDeg == current.worstMinDihedralDeg &&
         q.tetsBelow10Deg >= current.tetsBelow10Deg)) {
      const size_t n = probes.size() - added;
      probes.positions.resize(n);
      probes.kinds.resize(n);
      probes.spacing.resize(n);
      r.rejected += added;
      break;
    }
    r.added += added;
    r.mesh = std::move(mesh);
    r.after = q;
  }
  if (r.added == 0) r.after = r.before;
  return r;
}

}  // namespace tetraprobe
