// Outer cells outside the probe hull: construction from the hull faces, and the per-cell cubic that
// extrudes the hull triangle to a query point (Cupisz, GDC 2012, "Light probe interpolation using
// tetrahedral tessellations"; the cubic's coefficients as in /work/shared/REFERENCES.md §2).
//
// Numerics: everything is evaluated in double from the stored float positions and normals. The cubic's
// degree is reduced explicitly when its leading term is negligible at the problem's length scale (parallel
// normals make t^3 and t^2 vanish: the prism is straight and the equation is linear); the true cubic's roots
// are isolated between its critical points (monotone pieces) and refined by Newton steps kept inside a
// shrinking bracket, so a root is never missed, never NaN, and the smallest one >= 0 is taken.
#include "tetraprobe/runtime/outer_cells.h"

#include "tetraprobe/runtime/lookup_constants.h"
#include "tetraprobe/runtime/oct_normal.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <tuple>

#include <glm/geometric.hpp>

namespace tetraprobe {
namespace {

constexpr double kNegligible = 1e-13;  // a term below this fraction of the others (at t = scale) is dropped
constexpr double kZeroRoot = 1e-12;    // roots in [-kZeroRoot * scale, 0) count as t = 0
constexpr double kMaxT = kLookupOuterMaxT;  // roots beyond kMaxT * scale are not looked for

double horner(const double c[4], double t) {
  return ((c[3] * t + c[2]) * t + c[1]) * t + c[0];
}

// Real roots of a t^2 + b t + c (a != 0) without cancellation; returns how many (0 or 2, sorted).
int quadraticRoots(double a, double b, double c, double r[2]) {
  const double disc = b * b - 4.0 * a * c;
  if (disc < 0.0 || !std::isfinite(disc)) return 0;
  const double q = -0.5 * (b + std::copysign(std::sqrt(disc), b));
  if (q == 0.0) {  // b = 0 and c = 0: a double root at 0
    r[0] = r[1] = 0.0;
    return 2;
  }
  r[0] = q / a;
  r[1] = c / q;
  if (r[0] > r[1]) std::swap(r[0], r[1]);
  return 2;
}

// A root of the polynomial in [lo, hi], where f(lo) and f(hi) have opposite signs: Newton steps while they
// stay in the bracket, bisection otherwise.
double refineRoot(const double c[4], double lo, double hi) {
  double flo = horner(c, lo);
  // Start from the Newton step off the low end: the bracket reaches kMaxT while the root is usually within
  // a cell size of the face, so starting at the midpoint cost dozens of bisections (the query hot spot).
  const double dlo = (3.0 * c[3] * lo + 2.0 * c[2]) * lo + c[1];
  double t = dlo != 0.0 ? lo - flo / dlo : 0.5 * (lo + hi);
  if (!(t > lo && t < hi)) t = 0.5 * (lo + hi);
  for (int it = 0; it < 200; ++it) {
    const double f = horner(c, t);
    if (f == 0.0) return t;
    if ((f < 0.0) == (flo < 0.0)) {
      lo = t;
      flo = f;
    } else {
      hi = t;
    }
    if (hi - lo <= 4.0 * std::numeric_limits<double>::epsilon() * std::max(std::abs(lo), std::abs(hi))) break;
    const double df = (3.0 * c[3] * t + 2.0 * c[2]) * t + c[1];
    double next = df != 0.0 ? t - f / df : lo - 1.0;
    if (!(next > lo && next < hi)) next = 0.5 * (lo + hi);  // also catches NaN
    if (next == t) break;
    t = next;
  }
  return t;
}

// A few Newton steps on the full cubic from a root of its reduced form, kept only while they improve it.
double polish(const double c[4], double t) {
  for (int it = 0; it < 3; ++it) {
    const double f = horner(c, t), df = (3.0 * c[3] * t + 2.0 * c[2]) * t + c[1];
    if (f == 0.0 || df == 0.0) break;
    const double next = t - f / df;
    if (!std::isfinite(next) || !(std::abs(horner(c, next)) < std::abs(f))) break;
    t = next;
  }
  return t;
}

bool acceptRoot(double r, double* t) {
  if (!(r >= -kZeroRoot) || !(r <= kMaxT)) return false;
  *t = std::max(r, 0.0);
  return true;
}

}  // namespace

bool smallestNonNegativeRoot(const double coef[4], double scale, double* t) {
  for (int i = 0; i < 4; ++i)
    if (!std::isfinite(coef[i])) return false;
  if (!(scale > 0.0) || !std::isfinite(scale)) scale = 1.0;
  if (coef[0] == 0.0) {  // on the hull face's plane
    *t = 0.0;
    return true;
  }
  // In units of `scale` (tau = t / scale) every coefficient is a length^3 and comparable, and no power of a
  // far point's t can overflow (the GLSL twin does the same in float).
  const double c[4] = {coef[0] / (scale * scale * scale), coef[1] / (scale * scale), coef[2] / scale,
                       coef[3]};
  const double m0 = std::abs(c[0]), m1 = std::abs(c[1]), m2 = std::abs(c[2]), m3 = std::abs(c[3]);
  int degree = 3;
  if (m3 <= kNegligible * (m0 + m1 + m2)) degree = 2;
  if (degree == 2 && m2 <= kNegligible * (m0 + m1)) degree = 1;
  if (degree == 1 && m1 <= kNegligible * m0) degree = 0;

  double tau = 0.0;
  bool found = false;
  switch (degree) {
    case 0:  // constant and non-zero: the extruded triangle's plane never reaches X
      break;
    case 1:  // straight prism (parallel normals): det is linear in t
      found = acceptRoot(polish(c, -c[0] / c[1]), &tau);
      break;
    case 2: {
      double r[2];
      if (quadraticRoots(c[2], c[1], c[0], r) == 2)
        for (double x : r)
          if (!found) found = acceptRoot(polish(c, x), &tau);
      break;
    }
    default: {
      // A root in [-kZeroRoot, 0] counts as 0 (the point is on the face within rounding).
      if ((horner(c, -kZeroRoot) < 0.0) != (c[0] < 0.0)) {
        found = true;
        break;
      }
      // Monotone pieces between the critical points (roots of 3 c3 t^2 + 2 c2 t + c1), in order.
      std::array<double, 4> knots{};
      int k = 0;
      knots[size_t(k++)] = 0.0;
      double crit[2];
      if (quadraticRoots(3.0 * c[3], 2.0 * c[2], c[1], crit) == 2)
        for (double x : crit)
          if (x > knots[size_t(k - 1)] && x < kMaxT) knots[size_t(k++)] = x;
      knots[size_t(k++)] = kMaxT;
      double flo = c[0];
      for (int i = 0; i + 1 < k && !found; ++i) {
        const double lo = knots[size_t(i)], hi = knots[size_t(i + 1)], fhi = horner(c, hi);
        if (flo == 0.0)
          found = acceptRoot(lo, &tau);
        else if ((flo < 0.0) != (fhi < 0.0))
          found = acceptRoot(refineRoot(c, lo, hi), &tau);
        flo = fhi;
      }
    }
  }
  if (found) *t = tau * scale;
  return found;
}

void outerCellCubic(const OuterCell& cell, const std::vector<glm::vec3>& probes, const glm::dvec3& x,
                    double c[4]) {
  const glm::dvec3 p0(probes[size_t(cell.v[0])]), p1(probes[size_t(cell.v[1])]),
      p2(probes[size_t(cell.v[2])]);
  const glm::dvec3 n0(cell.normal[0][0], cell.normal[0][1], cell.normal[0][2]);
  const glm::dvec3 n1(cell.normal[1][0], cell.normal[1][1], cell.normal[1][2]);
  const glm::dvec3 n2(cell.normal[2][0], cell.normal[2][1], cell.normal[2][2]);
  const glm::dvec3 a = p0 - p2, ad = n0 - n2, b = p1 - p2, bd = n1 - n2, y = x - p2;
  const glm::dvec3 axb = glm::cross(a, b), mixed = glm::cross(a, bd) + glm::cross(ad, b),
                   adxbd = glm::cross(ad, bd);
  c[3] = -glm::dot(adxbd, n2);
  c[2] = glm::dot(adxbd, y) - glm::dot(mixed, n2);
  c[1] = glm::dot(mixed, y) - glm::dot(axb, n2);
  c[0] = glm::dot(axb, y);
}

OuterWeights outerCellWeights(const OuterCell& cell, const std::vector<glm::vec3>& probes,
                              const glm::dvec3& x) {
  OuterWeights out;
  glm::dvec3 p[3], n[3];
  for (int i = 0; i < 3; ++i) {
    p[i] = glm::dvec3(probes[size_t(cell.v[i])]);
    n[i] = glm::dvec3(cell.normal[i][0], cell.normal[i][1], cell.normal[i][2]);
  }
  double c[4];
  outerCellCubic(cell, probes, x, c);
  const double edge =
      std::max({glm::length(p[0] - p[2]), glm::length(p[1] - p[2]), glm::length(p[0] - p[1])});
  const double scale = glm::length(x - p[2]) + edge;
  double t = 0.0;
  out.valid = smallestNonNegativeRoot(c, scale, &t);
  if (!out.valid) t = 0.0;  // steer by the projection onto the face's plane
  out.t = t;
  const glm::dvec3 q0 = p[0] + t * n[0], q1 = p[1] + t * n[1], q2 = p[2] + t * n[2];
  const glm::dvec3 e1 = q0 - q2, e2 = q1 - q2, y = x - q2, nrm = glm::cross(e1, e2);
  const double nn = glm::dot(nrm, nrm);
  if (!(nn > 0.0) || !std::isfinite(nn)) {
    out.valid = false;
    out.b[0] = out.b[1] = out.b[2] = 1.0 / 3.0;
    return out;
  }
  out.b[0] = glm::dot(glm::cross(y, e2), nrm) / nn;
  out.b[1] = glm::dot(glm::cross(e1, y), nrm) / nn;
  out.b[2] = 1.0 - out.b[0] - out.b[1];
  return out;
}

int32_t findOuterCell(const std::vector<OuterCell>& cells, int32_t tet, int32_t face) {
  size_t lo = 0, hi = cells.size();
  while (lo < hi) {
    const size_t mid = lo + (hi - lo) / 2;
    const OuterCell& c = cells[mid];
    if (c.tet < tet || (c.tet == tet && c.face < face))
      lo = mid + 1;
    else
      hi = mid;
  }
  return lo < cells.size() && cells[lo].tet == tet && cells[lo].face == face ? int32_t(lo) : -1;
}

std::vector<OuterCell> buildOuterCells(const std::vector<glm::vec3>& probes, const std::vector<Tet>& tets) {
  std::vector<OuterCell> cells;
  // Faces in (tet, face) order: the order findOuterCell searches.
  for (size_t t = 0; t < tets.size(); ++t) {
    const Tet& tet = tets[t];
    for (int f = 0; f < 4; ++f) {
      if (tet.n[f] >= 0) continue;
      OuterCell c{};
      c.tet = int32_t(t);
      c.face = f;
      int k = 0;
      for (int i = 0; i < 4; ++i)
        if (i != f) c.v[k++] = tet.v[i];
      // Outward winding: (P1-P0) x (P2-P0) points away from the opposite vertex.
      const glm::dvec3 p0(probes[size_t(c.v[0])]), p1(probes[size_t(c.v[1])]), p2(probes[size_t(c.v[2])]),
          opp(probes[size_t(tet.v[f])]);
      if (glm::dot(glm::cross(p1 - p0, p2 - p0), p0 - opp) < 0.0) std::swap(c.v[1], c.v[2]);
      c.n[0] = c.n[1] = c.n[2] = -1;
      cells.push_back(c);
    }
  }

  // Angle-weighted vertex normals, accumulated per probe in cell order (deterministic).
  std::vector<glm::dvec3> accum(probes.size(), glm::dvec3(0.0));
  std::vector<glm::dvec3> faceNormal(cells.size(), glm::dvec3(0.0));
  for (size_t k = 0; k < cells.size(); ++k) {
    const OuterCell& c = cells[k];
    glm::dvec3 p[3];
    for (int i = 0; i < 3; ++i) p[i] = glm::dvec3(probes[size_t(c.v[i])]);
    const glm::dvec3 n = glm::cross(p[1] - p[0], p[2] - p[0]);
    const double len = glm::length(n);
    if (!(len > 0.0)) continue;  // a degenerate hull face contributes nothing
    faceNormal[k] = n / len;
    for (int i = 0; i < 3; ++i) {
      const glm::dvec3 u = p[(i + 1) % 3] - p[i], v = p[(i + 2) % 3] - p[i];
      const double angle = std::atan2(glm::length(glm::cross(u, v)), glm::dot(u, v));
      accum[size_t(c.v[i])] += angle * faceNormal[k];
    }
  }
  // Far from the hull a point X ~ t * sum(b_i N_i): the cells partition the far field only when every
  // cell's normal triangle is positively oriented on the sphere (det[N0, N1, N2] > 0). Angle-weighted
  // normals can fold there (a bumpy hull); the vertices of a folded cell are blended towards the radial
  // direction from the hull's centroid, which never folds (radial projection of a convex hull from an
  // interior point tiles the sphere), in steps until no cell folds.
  glm::dvec3 centroid(0.0);
  std::vector<uint8_t> onHull(probes.size(), 0);
  size_t hullCount = 0;
  for (const OuterCell& c : cells)
    for (int i = 0; i < 3; ++i)
      if (!onHull[size_t(c.v[i])]) {
        onHull[size_t(c.v[i])] = 1;
        centroid += glm::dvec3(probes[size_t(c.v[i])]);
        ++hullCount;
      }
  if (hullCount > 0) centroid /= double(hullCount);
  std::vector<double> alpha(probes.size(), 0.0);
  std::vector<glm::dvec3> normal(probes.size(), glm::dvec3(0.0));
  const auto vertexNormal = [&](int32_t p, const glm::dvec3& fallback) {
    glm::dvec3 aw = accum[size_t(p)];
    const double la = glm::length(aw);
    aw = la > 0.0 ? aw / la : fallback;
    glm::dvec3 radial = glm::dvec3(probes[size_t(p)]) - centroid;
    const double lr = glm::length(radial);
    radial = lr > 0.0 ? radial / lr : aw;
    glm::dvec3 n = (1.0 - alpha[size_t(p)]) * aw + alpha[size_t(p)] * radial;
    const double ln = glm::length(n);
    // On the octahedral code lattice (oct_normal.h), as the GPU receives it: the fold check below sees the
    // normals the lookups use, and the CPU and GPU extrude along the same directions.
    return glm::dvec3(quantizeOctNormal(ln > 0.0 ? n / ln : aw));
  };
  for (int round = 0; round <= 8; ++round) {
    for (size_t k = 0; k < cells.size(); ++k)
      for (int i = 0; i < 3; ++i) normal[size_t(cells[k].v[i])] = vertexNormal(cells[k].v[i], faceNormal[k]);
    bool folded = false;
    for (size_t k = 0; k < cells.size(); ++k) {
      const OuterCell& c = cells[k];
      const glm::dvec3 n0 = normal[size_t(c.v[0])], n1 = normal[size_t(c.v[1])], n2 = normal[size_t(c.v[2])];
      if (glm::dot(n0, glm::cross(n1, n2)) > 0.0) continue;
      folded = true;
      for (int i = 0; i < 3; ++i)
        alpha[size_t(c.v[i])] = round == 7 ? 1.0 : std::min(1.0, alpha[size_t(c.v[i])] + 0.25);
    }
    if (!folded) break;
  }
  for (size_t k = 0; k < cells.size(); ++k) {
    OuterCell& c = cells[k];
    for (int i = 0; i < 3; ++i) {
      const glm::dvec3 n = normal[size_t(c.v[i])];
      for (int a = 0; a < 3; ++a) c.normal[i][a] = float(n[a]);
      c.normal[i][3] = 0.0f;
    }
  }

  // Links across hull edges: sort (edge, cell, slot) records; an edge with exactly two faces links them.
  std::vector<std::tuple<int32_t, int32_t, int32_t, int32_t>> edges;  // (min probe, max probe, cell, slot)
  edges.reserve(cells.size() * 3);
  for (size_t k = 0; k < cells.size(); ++k)
    for (int i = 0; i < 3; ++i) {
      const int32_t a = cells[k].v[(i + 1) % 3], b = cells[k].v[(i + 2) % 3];
      edges.emplace_back(std::min(a, b), std::max(a, b), int32_t(k), i);
    }
  std::sort(edges.begin(), edges.end());
  for (size_t i = 0; i < edges.size();) {
    size_t j = i;
    while (j < edges.size() && std::get<0>(edges[j]) == std::get<0>(edges[i]) &&
           std::get<1>(edges[j]) == std::get<1>(edges[i]))
      ++j;
    if (j - i == 2) {
      const auto& [a0, b0, c0, s0] = edges[i];
      const auto& [a1, b1, c1, s1] = edges[i + 1];
      cells[size_t(c0)].n[s0] = c1;
      cells[size_t(c1)].n[s1] = c0;
    }
    i = j;
  }
  return cells;
}

}  // namespace tetraprobe
