// Deringing by the nearest non-negative irradiance (DeringMode::kAuto; contract in bake.h, nearestNonNegativeSh).
//
// Per channel, the irradiance E(n) = sum_i e_i Y_i(n) with e_i = A_l(i) L_i is an orthonormal expansion, so the
// L2 distance of two fields over the sphere is the Euclidean distance of their e (Parseval). With e_0 (the mean)
// held, the nearest field whose E is non-negative everywhere is the projection of x0 = (e_1 .. e_8) onto the
// convex set {x : b0 + a(n) . x >= 0 for every unit n}, b0 = e_0 Y_00, a(n) = (Y_1(n) .. Y_8(n)): a quadratic
// programme with one half-space per direction, solved by the dual active-set method (Goldfarb & Idnani) with
// the sphere's exact minimum direction (E on the sphere is a quadratic form plus a linear term: the
// trust-region subproblem) added as the next constraint until E is nowhere below the bound.
//
// The window (dering.cpp) is one point of the same set (bands scaled, mean held), so this field is never
// farther from the projected one; where a probe sees a bright region on one side and nothing on the other, the
// window lifts the dark side by a share of the bright side's light, the projection leaves it near zero.
// References: Goldfarb & Idnani 1983 ("A numerically stable dual method for solving strictly convex quadratic
// programs"); More & Sorensen 1983 ("Computing a trust region step", the secular equation and its hard case);
// Ramamoorthi & Hanrahan 2001 (the A_l factors).
#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <vector>

#include <glm/geometric.hpp>

#include "tetraprobe/bake/bake.h"

namespace tetraprobe {

namespace {

constexpr int kBands = kShCoeffCount - 1;  // e_1 .. e_8
using Row = std::array<double, kBands>;

Row rowAt(const glm::dvec3& n, int dims) {
  const auto y = shBasis<double>(n.x, n.y, n.z);
  Row r{};
  for (int i = 0; i + 1 < dims; ++i) r[size_t(i)] = y[size_t(i + 1)];
  return r;
}

double dot(const Row& a, const Row& x, int dims) {
  double s = 0.0;
  for (int i = 0; i + 1 < dims; ++i) s += a[size_t(i)] * x[size_t(i)];
  return s;
}

// Eigen-decomposition of a symmetric 3x3 matrix by cyclic Jacobi rotations: a = v diag(q) v^T, q ascending,
// the columns of v the eigenvectors.
void symmetricEigen3(std::array<std::array<double, 3>, 3> a, std::array<double, 3>& q,
                     std::array<glm::dvec3, 3>& vectors) {
  double v[3][3] = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  for (int sweep = 0; sweep < 50; ++sweep) {
    const double off = std::abs(a[0][1]) + std::abs(a[0][2]) + std::abs(a[1][2]);
    const double diag = std::abs(a[0][0]) + std::abs(a[1][1]) + std::abs(a[2][2]);
    if (off <= 1e-18 * (off + diag) || off == 0.0) break;
    for (int p = 0; p < 2; ++p)
      for (int r = p + 1; r < 3; ++r) {
        if (a[size_t(p)][size_t(r)] == 0.0) continue;
        const double theta =
            (a[size_t(r)][size_t(r)] - a[size_t(p)][size_t(p)]) / (2.0 * a[size_t(p)][size_t(r)]);
        const double t = (theta >= 0.0 ? 1.0 : -1.0) / (std::abs(theta) + std::sqrt(theta * theta + 1.0));
        const double c = 1.0 / std::sqrt(t * t + 1.0), sn = t * c;
        for (int k = 0; k < 3; ++k) {  // a <- a J (columns p, r)
          const double akp = a[size_t(k)][size_t(p)], akr = a[size_t(k)][size_t(r)];
          a[size_t(k)][size_t(p)] = c * akp - sn * akr;
          a[size_t(k)][size_t(r)] = sn * akp + c * akr;
        }
        for (int k = 0; k < 3; ++k) {  // a <- J^T a (rows p, r)
          const double apk = a[size_t(p)][size_t(k)], ark = a[size_t(r)][size_t(k)];
          a[size_t(p)][size_t(k)] = c * apk - sn * ark;
          a[size_t(r)][size_t(k)] = sn * apk + c * ark;
        }
        for (int k = 0; k < 3; ++k) {
          const double vkp = v[k][p], vkr = v[k][r];
          v[k][p] = c * vkp - sn * vkr;
          v[k][r] = sn * vkp + c * vkr;
        }
      }
  }
  std::array<int, 3> order = {0, 1, 2};
  std::sort(order.begin(), order.end(), [&](int i, int j) {
    return a[size_t(i)][size_t(i)] < a[size_t(j)][size_t(j)] ||
           (a[size_t(i)][size_t(i)] == a[size_t(j)][size_t(j)] && i < j);
  });
  for (int k = 0; k < 3; ++k) {
    const int i = order[size_t(k)];
    q[size_t(k)] = a[size_t(i)][size_t(i)];
    vectors[size_t(k)] = glm::dvec3(v[0][i], v[1][i], v[2][i]);
  }
}

// The exact minimum of E(n) = b0 + a(n) . x over unit n. On the sphere 3 z^2 - 1 = 2 z^2 - x^2 - y^2, so E is
// n^T Q n + g . n + b0 with Q the band-2 coefficients' quadratic form and g band 1's vector: the trust-region
// subproblem on the sphere's surface, whose global minimiser is n = -(Q - lambda I)^-1 g / 2 for the one
// lambda below Q's least eigenvalue q1 with |n| = 1 (a monotone equation in lambda, solved by bisection in
// [q1 - |g| / 2, q1)), or, when g has no part along q1's eigenvector (the hard case), lambda = q1 and n that
// part completed to unit length (More & Sorensen 1983).
double sphereMinimum(double b0, const Row& x, int dims, glm::dvec3& at) {
  using namespace sh_const;
  // Row index i holds coefficient i + 1: 1 y, 2 z, 3 x, 4 xy, 5 yz, 6 3z^2-1, 7 xz, 8 x^2-y^2.
  const glm::dvec3 g(kY1 * x[2], kY1 * x[0], kY1 * x[1]);
  std::array<std::array<double, 3>, 3> qf{};
  if (dims > 4) {
    qf[0][1] = qf[1][0] = 0.5 * kY2n2 * x[3];
    qf[1][2] = qf[2][1] = 0.5 * kY2n2 * x[4];
    qf[0][2] = qf[2][0] = 0.5 * kY2n2 * x[6];
    qf[0][0] = -kY20 * x[5] + kY22 * x[7];
    qf[1][1] = -kY20 * x[5] - kY22 * x[7];
    qf[2][2] = 2.0 * kY20 * x[5];
  }
  std::array<double, 3> q{};
  std::array<glm::dvec3, 3> v{};
  symmetricEigen3(qf, q, v);
  const std::array<double, 3> beta = {glm::dot(v[0], g), glm::dot(v[1], g), glm::dot(v[2], g)};
  const double gn = glm::length(g);
  const double scale = std::abs(q[0]) + std::abs(q[2]) + gn;
  auto normAt = [&](double lambda) {  // |n(lambda)|^2
    double s = 0.0;
    for (int i = 0; i < 3; ++i) {
      const double d = q[size_t(i)] - lambda;
      if (d > 0.0) s += beta[size_t(i)] * beta[size_t(i)] / (4.0 * d * d);
    }
    return s;
  };
  if (scale == 0.0) {
    at = glm::dvec3(0, 0, 1);
    return b0;
  }
  // Easy case: the root of |n(lambda)| = 1 below q1, where |n| grows past 1 as lambda approaches q1.
  const double eps = 1e-12 * scale;
  double lo = q[0] - 0.5 * gn - eps, hi = q[0];
  bool hard = !(std::abs(beta[0]) > 1e-12 * (gn + scale)) && normAt(q[0] - eps) <= 1.0;
  glm::dvec3 n(0.0);
  if (!hard) {
    for (int it = 0; it < 200; ++it) {
      const double mid = 0.5 * (lo + hi);
      if (mid <= lo || mid >= hi) break;
      if (normAt(mid) > 1.0)
        hi = mid;
      else
        lo = mid;
    }
    const double lambda = lo;
    for (int i = 0; i < 3; ++i) {
      const double d = q[size_t(i)] - lambda;
      if (d > 0.0) n += v[size_t(i)] * (-beta[size_t(i)] / (2.0 * d));
    }
  } else {
    for (int i = 1; i < 3; ++i) {
      const double d = q[size_t(i)] - q[0];
      if (d > eps) n += v[size_t(i)] * (-beta[size_t(i)] / (2.0 * d));
    }
    const double rest = std::max(0.0, 1.0 - glm::dot(n, n));
    n += v[0] * std::sqrt(rest);
  }
  // Rounding: back onto the sphere; E evaluated through the basis, as the constraints are.
  const double len = glm::length(n);
  n = len > 0.0 ? n / len : v[0];
  at = n;
  return b0 + dot(rowAt(n, dims), x, dims);
}

// Solves the small dense system m y = b (n <= 8) by Gaussian elimination with partial pivoting; false when a
// pivot is below 1e-12 of the largest (the active normals nearly dependent).
bool solveSmall(std::vector<double> m, std::vector<double> b, size_t n, std::vector<double>& y) {
  double big = 0.0;
  for (double v : m) big = std::max(big, std::abs(v));
  for (size_t col = 0; col < n; ++col) {
    size_t piv = col;
    for (size_t r = col + 1; r < n; ++r)
      if (std::abs(m[r * n + col]) > std::abs(m[piv * n + col])) piv = r;
    if (!(std::abs(m[piv * n + col]) > 1e-12 * big)) return false;
    if (piv != col) {
      for (size_t k = 0; k < n; ++k) std::swap(m[col * n + k], m[piv * n + k]);
      std::swap(b[col], b[piv]);
    }
    for (size_t r = col + 1; r < n; ++r) {
      const double f = m[r * n + col] / m[col * n + col];
      for (size_t k = col; k < n; ++k) m[r * n + k] -= f * m[col * n + k];
      b[r] -= f * b[col];
    }
  }
  y.assign(n, 0.0);
  for (size_t i = n; i-- > 0;) {
    double v = b[i];
    for (size_t k = i + 1; k < n; ++k) v -= m[i * n + k] * y[k];
    y[i] = v / m[i * n + i];
  }
  return true;
}

constexpr int kMaxAdded =
    200;  // constraints added (sphere minima) before leaving the rest to the caller's window

// One channel: x (e_1 .. e_{dims-1}) moved to the nearest point with E >= -slack everywhere, by the dual
// active-set method of Goldfarb & Idnani (1983) for the Hessian I: from the unconstrained optimum x0, the
// sphere's minimum direction is added as a constraint while E is below -slack there, each time stepping along
// the part of its normal the active normals do not span and dropping an active constraint whose multiplier
// would turn negative. Should it stop first (kMaxAdded, nearly dependent normals), deringProbes' check of the
// result windows what is left.
void projectChannel(double b0, Row& x, int dims, double slack) {
  std::vector<Row> active;
  std::vector<double> mu;
  const size_t n = size_t(dims - 1);
  for (int added = 0; added < kMaxAdded; ++added) {
    // The next constraint: where E is least.
    glm::dvec3 at;
    double s = sphereMinimum(b0, x, dims, at);
    if (s >= -slack) return;
    const Row a = rowAt(at, dims);
    double muNew = 0.0;
    for (int step = 0; step < 2 * int(n) + 2; ++step) {
      // r = (N^T N)^-1 N^T a, z = a - N r (a's part outside the active normals' span).
      std::vector<double> r;
      Row z = a;
      const size_t k = active.size();
      if (k > 0) {
        std::vector<double> g(k * k), rhs(k);
        for (size_t i = 0; i < k; ++i) {
          rhs[i] = dot(active[i], a, dims);
          for (size_t j = 0; j < k; ++j) g[i * k + j] = dot(active[i], active[j], dims);
        }
        if (!solveSmall(g, rhs, k, r)) return;
        for (size_t i = 0; i < k; ++i)
          for (size_t c = 0; c < n; ++c) z[c] -= r[i] * active[i][c];
      }
      const double zz = dot(z, z, dims);
      const double full = zz > 1e-14 * dot(a, a, dims) ? -s / zz : std::numeric_limits<double>::infinity();
      double partial = std::numeric_limits<double>::infinity();
      size_t drop = k;
      for (size_t i = 0; i < k; ++i)
        if (r[i] > 0.0 && mu[i] / r[i] < partial) {
          partial = mu[i] / r[i];
          drop = i;
        }
      const double t = std::min(full, partial);
      if (!std::isfinite(t)) return;
      for (size_t c = 0; c < n; ++c) x[c] += t * z[c];
      for (size_t i = 0; i < k; ++i) mu[i] -= t * r[i];
      muNew += t;
      s += t * zz;
      if (full <= partial) {  // the new constraint holds with equality: it joins the active set
        active.push_back(a);
        mu.push_back(muNew);
        break;
      }
      active.erase(active.begin() + std::ptrdiff_t(drop));
      mu.erase(mu.begin() + std::ptrdiff_t(drop));
    }
  }
}

}  // namespace

bool nearestNonNegativeSh(ShRgb& sh, bool* fixable) {
  if (fixable) *fixable = true;
  // A probe without band 2 (an L1 bake) keeps none.
  bool band2 = false;
  for (int i = 4; i < kShCoeffCount; ++i)
    for (int c = 0; c < 3; ++c) band2 = band2 || sh.c[size_t(i)][c] != 0.0f;
  const int dims = band2 ? kShCoeffCount : 4;
  double maxMean = 0.0;
  for (int c = 0; c < 3; ++c)
    maxMean = std::max(maxMean, sh_const::kA0 * sh_const::kY00 * double(sh.c[0][c]));
  // Aim a tenth inside the window's tolerance, so that float coefficients pass the same check.
  const double slack = 0.1 * kDeringTolerance * maxMean;
  bool changed = false;
  for (int c = 0; c < 3; ++c) {
    const double b0 = sh_const::kA0 * sh_const::kY00 * double(sh.c[0][c]);
    Row x{};
    for (int i = 1; i < dims; ++i) x[size_t(i - 1)] = shCosineLobe(i) * double(sh.c[size_t(i)][c]);
    glm::dvec3 at;
    if (sphereMinimum(b0, x, dims, at) >= -slack) continue;
    changed = true;
    if (!(b0 > 0.0)) {  // a negative mean (imported SH): the constant is the nearest, and still negative
      for (int i = 1; i < dims; ++i) sh.c[size_t(i)][c] = 0.0f;
      if (fixable) *fixable = false;
      continue;
    }
    projectChannel(b0, x, dims, slack);
    for (int i = 1; i < dims; ++i) sh.c[size_t(i)][c] = float(x[size_t(i - 1)] / shCosineLobe(i));
  }
  return changed;
}

}  // namespace tetraprobe
