// The last sliver pass: occlusion-hole and refinement probes land near surfaces and near existing probes, and
// the Delaunay tets around them can be far flatter than anything the filler left (addSliverFillers). Adding
// Delaunay-refinement points (Shewchuk 1998; Si 2015) at every sliver after refinement would cost a probe bake
// each, and TetGen's rule added 8-37 % probes there; here a small budget of circumcentre fillers goes first, and
// what they leave is fixed by removing the late probe that made the sliver. Removal is free (no bake) and
// always reaches the earlier mesh's bound: a Delaunay tet whose four corners are earlier points has a
// circumsphere empty of every point, so it is a tet of the earlier points' own Delaunay mesh (with CGAL's
// symbolic perturbation, ties included).
#include "tetraprobe/tetra/final_slivers.h"

#include <algorithm>
#include <array>
#include <cmath>

#include <glm/geometric.hpp>

#include "tetraprobe/tetra/placement.h"

namespace tetraprobe {
namespace {

TetMesh delaunay(const std::vector<glm::dvec3>& points, TetraBackend backend) {
  if (backend == TetraBackend::kTetGen) return tetrahedralizeTetGen(points).mesh;
  return tetrahedralizeDelaunay(points);
}

double tetMinDihedral(const std::vector<glm::dvec3>& p, const std::array<int32_t, 4>& t) {
  return tetQuality(p[size_t(t[0])], p[size_t(t[1])], p[size_t(t[2])], p[size_t(t[3])]).minDihedralDeg;
}

size_t countBelow(const std::vector<glm::dvec3>& p, const TetMesh& mesh, double deg) {
  size_t n = 0;
  for (const auto& t : mesh.tets) n += tetMinDihedral(p, t) < deg;
  return n;
}

// Circumcentre of the tet, or its centroid when the circumcentre is farther than the longest edge from it.
glm::dvec3 fillerPoint(const glm::dvec3& p0, const glm::dvec3& p1, const glm::dvec3& p2,
                       const glm::dvec3& p3) {
  const glm::dvec3 a = p1 - p0, b = p2 - p0, c = p3 - p0;
  const double det = glm::dot(a, glm::cross(b, c));
  const glm::dvec3 centroid = 0.25 * (p0 + p1 + p2 + p3);
  const glm::dvec3 pts[4] = {p0, p1, p2, p3};
  double longest = 0.0;
  for (int i = 0; i < 4; ++i)
    for (int j = i + 1; j < 4; ++j) longest = std::max(longest, glm::distance(pts[i], pts[j]));
  if (det == 0.0) return centroid;
  const glm::dvec3 cc = p0 + (glm::dot(a, a) * glm::cross(b, c) + glm::dot(b, b) * glm::cross(c, a) +
                              glm::dot(c, c) * glm::cross(a, b)) /
                                 (2.0 * det);
  if (std::isfinite(cc.x) && std::isfinite(cc.y) && std::isfinite(cc.z) &&
      glm::distance(cc, centroid) <= longest)
    return cc;
  return centroid;
}

// Step 1b's moves: each chosen corner v goes away from the faces opposite it in its slivers (the sum of their
// unit normals turned towards v) by options.nudgeFraction x the slivers' mean edge, at most options.maxNudge x
// its spacing. Appends the corners that have a direction to `which` and their new positions to `to`.
void movesOffSlivers(const std::vector<glm::dvec3>& pos, const std::vector<double>& spc,
                     const std::vector<std::array<int32_t, 4>>& slivers, const std::vector<uint8_t>& chosen,
                     const FinalSliverOptions& options, std::vector<size_t>& which,
                     std::vector<glm::dvec3>& to) {
  std::vector<glm::dvec3> dir(pos.size(), glm::dvec3(0.0));
  std::vector<double> edge(pos.size(), 0.0), n(pos.size(), 0.0);
  for (const auto& t : slivers)
    for (int k = 0; k < 4; ++k) {
      const size_t v = size_t(t[size_t(k)]);
      if (!chosen[v]) continue;
      const glm::dvec3 a = pos[size_t(t[size_t((k + 1) % 4)])], b = pos[size_t(t[size_t((k + 2) % 4)])],
                       c = pos[size_t(t[size_t((k + 3) % 4)])];
      glm::dvec3 normal = glm::cross(b - a, c - a);
      const double len = glm::length(normal);
      if (!(len > 0.0)) continue;
      normal /= len;
      if (glm::dot(normal, pos[v] - a) < 0.0) normal = -normal;
      dir[v] += normal;
      double sum = 0.0;
      for (int i = 0; i < 4; ++i)
        for (int j = i + 1; j < 4; ++j)
          sum += glm::distance(pos[size_t(t[size_t(i)])], pos[size_t(t[size_t(j)])]);
      edge[v] += sum / 6.0;
      n[v] += 1.0;
    }
  for (size_t v = 0; v < pos.size(); ++v) {
    const double len = glm::length(dir[v]);
    if (!chosen[v] || !(len > 0.0) || !(n[v] > 0.0)) continue;
    const double step = std::min(options.nudgeFraction * edge[v] / n[v], options.maxNudge * spc[v]);
    which.push_back(v);
    to.push_back(pos[v] + dir[v] / len * step);
  }
}

}  // namespace

FinalSliverResult fixFinalSlivers(
    const std::vector<glm::dvec3>& points, const std::vector<double>& spacing,
    const FinalSliverOptions& options,
    const std::function<std::vector<uint8_t>(const std::vector<glm::dvec3>&)>& inside) {
  FinalSliverResult r;
  // Working set: positions, spacing and where each came from (index into `points`, or -1 for a filler).
  std::vector<glm::dvec3> pos = points;
  std::vector<double> spc = spacing;
  std::vector<int64_t> from(points.size());
  for (size_t i = 0; i < from.size(); ++i) from[i] = int64_t(i);
  r.mesh = delaunay(pos, options.backend);
  r.before = meshQuality(pos, r.mesh);
  const double target = options.targetDeg;
  if (!(r.before.worstMinDihedralDeg < target)) {
    r.after = r.before;
    return r;
  }

  // (1) Fillers at the interior slivers, within the budget.
  size_t bad = countBelow(pos, r.mesh, target);
  size_t fillers = 0;
  for (int round = 0; round < options.fillerRounds && fillers < options.maxFillers && bad > 0; ++round) {
    PlacedProbes all;  // existing points as kUser (never dropped by the merge), candidates as kFiller
    for (size_t i = 0; i < pos.size(); ++i) all.add(pos[i], ProbeKind::kUser, spc[i]);
    size_t candidates = 0;
    for (size_t ti = 0; ti < r.mesh.tets.size(); ++ti) {
      const auto& t = r.mesh.tets[ti];
      const auto& nb = r.mesh.neighbours[ti];
      if (std::find(nb.begin(), nb.end(), -1) != nb.end()) continue;  // hull slivers: see filler.h
      if (!(tetMinDihedral(pos, t) < target)) continue;
      double s = 0.0;
      for (int k = 0; k < 4; ++k) s += 0.25 * spc[size_t(t[size_t(k)])];
      all.add(fillerPoint(pos[size_t(t[0])], pos[size_t(t[1])], pos[size_t(t[2])], pos[size_t(t[3])]),
              ProbeKind::kFiller, s);
      ++candidates;
    }
    if (candidates == 0) break;
    const size_t n = pos.size();
    mergeProbes(all, options.minDistance);
    std::vector<glm::dvec3> cand(all.positions.begin() + std::ptrdiff_t(n), all.positions.end());
    std::vector<double> candSpacing(all.spacing.begin() + std::ptrdiff_t(n), all.spacing.end());
    std::vector<uint8_t> in(cand.size(), 0);
    if (inside && !cand.empty()) in = inside(cand);
    size_t added = 0;
    for (size_t i = 0; i < cand.size() && fillers + added < options.maxFillers; ++i) {
      if (in[i]) continue;
      pos.push_back(cand[i]);
      spc.push_back(candSpacing[i]);
      from.push_back(-1);
      ++added;
    }
    r.rejected += candidates - added;
    if (added == 0) break;
    TetMesh mesh = delaunay(pos, options.backend);
    const size_t nowBad = countBelow(pos, mesh, target);
    if (nowBad >= bad) {  // the fillers made as many slivers as they fixed: undo and stop
      pos.resize(n);
      spc.resize(n);
      from.resize(n);
      r.rejected += added;
      break;
    }
    fillers += added;
    bad = nowBad;
    r.mesh = std::move(mesh);
    r.fillerRounds = round + 1;
  }

  // (1b) Move late corners off their slivers. The corners are chosen as step 2's cover chooses them.
  auto removable = [&](size_t v) { return from[v] < 0 || size_t(from[v]) >= options.firstLate; };
  auto cover = [&](const std::vector<std::array<int32_t, 4>>& slivers) {
    std::vector<uint8_t> chosen(pos.size(), 0);
    std::vector<uint32_t> count(pos.size(), 0);
    for (const auto& t : slivers)
      for (int k = 0; k < 4; ++k)
        if (removable(size_t(t[size_t(k)]))) ++count[size_t(t[size_t(k)])];
    std::vector<uint8_t> covered(slivers.size(), 0);
    for (;;) {
      size_t best = pos.size();
      for (size_t v = 0; v < pos.size(); ++v)
        if (count[v] > 0 && (best == pos.size() || count[v] >= count[best])) best = v;
      if (best == pos.size()) break;
      chosen[best] = 1;
      for (size_t s = 0; s < slivers.size(); ++s) {
        const auto& t = slivers[s];
        if (covered[s] || std::find(t.begin(), t.end(), int32_t(best)) == t.end()) continue;
        covered[s] = 1;
        for (int k = 0; k < 4; ++k)
          if (removable(size_t(t[size_t(k)]))) --count[size_t(t[size_t(k)])];
      }
    }
    return chosen;
  };
  auto sliversOf = [&](const TetMesh& mesh) {
    std::vector<std::array<int32_t, 4>> slivers;
    for (const auto& t : mesh.tets)
      if (tetMinDihedral(pos, t) < target) slivers.push_back(t);
    return slivers;
  };
  // `bad` counts the tets below the target in r.mesh (kept so by the filler rounds).
  for (int round = 0; round < options.nudgeRounds && bad > 0; ++round) {
    const std::vector<std::array<int32_t, 4>> slivers = sliversOf(r.mesh);
    std::vector<size_t> which;
    std::vector<glm::dvec3> cand;
    movesOffSlivers(pos, spc, slivers, cover(slivers), options, which, cand);
    if (cand.empty()) break;
    std::vector<uint8_t> in(cand.size(), 0);
    if (inside) in = inside(cand);
    std::vector<glm::dvec3> trial = pos;
    size_t movedCount = 0;
    for (size_t i = 0; i < cand.size(); ++i)
      if (!in[i]) {
        trial[which[i]] = cand[i];
        ++movedCount;
      }
    if (movedCount == 0) break;
    TetMesh mesh = delaunay(trial, options.backend);
    const size_t nowBad = countBelow(trial, mesh, target);
    if (nowBad >= bad) break;  // the moves made as many slivers as they fixed: undo and stop
    pos = std::move(trial);
    r.mesh = std::move(mesh);
    bad = nowBad;
    r.nudgeRounds = round + 1;
  }

  // (2) Remove late corners of the slivers left, until none is left or none has a late corner. Per round a
  // greedy cover: the removable corner of the most slivers goes first (ties: the one added last), and a
  // sliver one of whose corners goes is covered.
  for (;;) {
    const std::vector<uint8_t> drop = cover(sliversOf(r.mesh));
    const size_t dropped = size_t(std::count(drop.begin(), drop.end(), uint8_t(1)));
    if (dropped == 0) break;
    size_t w = 0;
    for (size_t i = 0; i < pos.size(); ++i) {
      if (drop[i]) continue;
      pos[w] = pos[i];
      spc[w] = spc[i];
      from[w] = from[i];
      ++w;
    }
    pos.resize(w);
    spc.resize(w);
    from.resize(w);
    r.mesh = delaunay(pos, options.backend);
    ++r.removalRounds;
  }

  std::vector<uint8_t> kept(points.size(), 0);
  for (size_t i = 0; i < pos.size(); ++i) {
    if (from[i] >= 0) {
      kept[size_t(from[i])] = 1;
      if (pos[i] != points[size_t(from[i])]) r.moved.emplace_back(size_t(from[i]), pos[i]);
    } else {
      r.added.push_back(pos[i]);
    }
  }
  for (size_t i = 0; i < points.size(); ++i)
    if (!kept[i]) r.removed.push_back(i);
  r.after = meshQuality(pos, r.mesh);
  return r;
}

}  // namespace tetraprobe
