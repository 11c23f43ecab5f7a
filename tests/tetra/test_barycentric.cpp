// The barycentric frame the runtime derives from the probe positions (level.h: baryFrame, in float as the
// GPU and occlusion evaluate it), over the tets buildTetRecords() writes.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>

#include <glm/geometric.hpp>
#include <glm/mat3x3.hpp>
#include <glm/matrix.hpp>
#include <glm/vec4.hpp>

#include "tetraprobe/runtime/level.h"
#include "tetraprobe/tetra/tetrahedralize.h"

namespace tetraprobe {
namespace {

std::vector<glm::dvec3> randomPoints(size_t n, uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(-10.0, 10.0);
  std::vector<glm::dvec3> pts(n);
  for (auto& p : pts) p = {u(rng), u(rng), u(rng)};
  return pts;
}

// The float probe positions a level stores (local frame).
std::vector<glm::vec3> floatProbes(const std::vector<glm::dvec3>& pts, const glm::dvec3& origin) {
  std::vector<glm::vec3> out(pts.size());
  for (size_t i = 0; i < pts.size(); ++i) out[i] = glm::vec3(pts[i] - origin);
  return out;
}

// level.h: the float frame derived from the probe positions (what occlusion and the GPU evaluate).
glm::dvec4 weights(const Tet& t, const std::vector<glm::vec3>& probes, const glm::dvec3& local) {
  return glm::dvec4(baryWeights(baryFrame(t, probes), glm::vec3(local)));
}

// Rounding noise of the float frame at local point x: a few float ulps of each weight's terms, times the
// condition of the frame (its gradients times the tet's longest edge). Large only for slivers.
double floatNoise(const Tet& t, const std::vector<glm::vec3>& probes, const glm::dvec3& x) {
  const BaryFrame f = baryFrame(t, probes);
  double edge = 0.0;
  for (int i = 0; i < 4; ++i)
    for (int j = i + 1; j < 4; ++j)
      edge = std::max(edge, double(glm::length(probes[size_t(t.v[i])] - probes[size_t(t.v[j])])));
  const glm::dvec3 d = x - glm::dvec3(f.origin);
  double n = 0.0, g = 0.0;
  for (int i = 0; i < 3; ++i) {
    n += std::abs(f.grad[i].x * d.x) + std::abs(f.grad[i].y * d.y) + std::abs(f.grad[i].z * d.z);
    g += glm::length(glm::dvec3(f.grad[i]));
  }
  return 8.0 * 0x1p-24 * (n + 1.0) * std::max(1.0, g * edge);
}

// A random point strictly inside tet t, and the barycentrics it was built from.
glm::dvec3 randomInside(const std::vector<glm::dvec3>& pts, const std::array<int32_t, 4>& t,
                        std::mt19937_64& rng, glm::dvec4& b) {
  std::exponential_distribution<double> e(1.0);  // normalized exponentials: uniform over the simplex
  double sum = 0.0;
  for (int i = 0; i < 4; ++i) sum += (b[i] = e(rng) + 1e-3);
  b /= sum;
  glm::dvec3 x(0.0);
  for (int i = 0; i < 4; ++i) x += b[i] * pts[size_t(t[size_t(i)])];
  return x;
}

// Interpolation weights must be a partition of unity, and a vertex must get all of its own probe's light.
TEST(Barycentric, WeightsSumToOne) {
  const auto pts = randomPoints(200, 11);
  const TetMesh mesh = tetrahedralizeDelaunay(pts);
  const auto recs = buildTetRecords(pts, mesh, glm::dvec3(0.0));
  const auto probes = floatProbes(pts, glm::dvec3(0.0));
  std::mt19937_64 rng(5);
  for (size_t t = 0; t < recs.size(); ++t) {
    glm::dvec4 b;
    const glm::dvec4 w = weights(recs[t], probes, randomInside(pts, mesh.tets[t], rng, b));
    EXPECT_NEAR(w.x + w.y + w.z + w.w, 1.0, 1e-6);
    for (int i = 0; i < 4; ++i) {
      EXPECT_GE(w[i], -1e-5) << "tet " << t;
      const glm::dvec4 atVertex = weights(recs[t], probes, pts[size_t(mesh.tets[t][size_t(i)])]);
      for (int j = 0; j < 4; ++j)
        EXPECT_NEAR(atVertex[j], i == j ? 1.0 : 0.0, 1e-4) << "tet " << t << " vertex " << i;
    }
  }
}

// Barycentric interpolation is exact for linear fields; anything else means the rows are wrong.
TEST(Barycentric, ReproducesLinearFieldExactly) {
  const auto pts = randomPoints(300, 12);
  const TetMesh mesh = tetrahedralizeDelaunay(pts);
  const auto recs = buildTetRecords(pts, mesh, glm::dvec3(0.0));
  const auto probes = floatProbes(pts, glm::dvec3(0.0));
  const glm::dvec3 grad(0.7, -1.3, 2.1);
  const double offset = 3.0;
  auto f = [&](const glm::dvec3& x) { return grad.x * x.x + grad.y * x.y + grad.z * x.z + offset; };
  const double scale = 10.0 * (std::abs(grad.x) + std::abs(grad.y) + std::abs(grad.z)) + offset;  // max |f|
  std::mt19937_64 rng(6);
  for (size_t t = 0; t < recs.size(); ++t)
    for (int k = 0; k < 4; ++k) {
      glm::dvec4 b;
      const glm::dvec3 x = randomInside(pts, mesh.tets[t], rng, b);
      const glm::dvec4 w = weights(recs[t], probes, x);
      double interp = 0.0;
      for (int i = 0; i < 4; ++i) interp += w[i] * f(pts[size_t(mesh.tets[t][size_t(i)])]);
      EXPECT_NEAR(interp, f(x), 1e-5 * scale) << "tet " << t;
    }
}

// Probes as placement makes them: a 2 m grid, jittered by up to 0.4 m (random clouds have slivers whose
// float frames carry ~2e-5 of rounding noise wherever they sit, which would hide what this test looks for).
std::vector<glm::dvec3> jitteredGrid(int n, uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> j(-0.4, 0.4);
  std::vector<glm::dvec3> pts;
  for (int z = 0; z < n; ++z)
    for (int y = 0; y < n; ++y)
      for (int x = 0; x < n; ++x)
        pts.push_back(2.0 * (glm::dvec3(x, y, z) - 0.5 * (n - 1)) + glm::dvec3(j(rng), j(rng), j(rng)));
  return pts;
}

// Levels sit kilometres from the world origin; the local origin must keep the float frame as precise as at 0.
TEST(Barycentric, FarFromOriginMatchesOrigin) {
  const auto pts = jitteredGrid(10, 13);
  const glm::dvec3 shift(10000.0, -10000.0, 10000.0);
  std::vector<glm::dvec3> far = pts;
  for (auto& p : far) p += shift;
  const TetMesh mesh = tetrahedralizeDelaunay(pts);
  const auto nearRecs = buildTetRecords(pts, mesh, glm::dvec3(0.0));
  const glm::dvec3 localOrigin = shift + glm::dvec3(1.5, 2.5, -3.5);  // e.g. the level's bounds centre
  const auto farRecs = buildTetRecords(far, mesh, localOrigin);
  const auto nearProbes = floatProbes(pts, glm::dvec3(0.0)), farProbes = floatProbes(far, localOrigin);
  std::mt19937_64 rng(7);
  size_t slivers = 0;  // tets that needed more than 1e-5
  for (size_t t = 0; t < mesh.tets.size(); ++t) {
    glm::dvec4 b;
    const glm::dvec3 x = randomInside(pts, mesh.tets[t], rng, b);
    const glm::dvec3 xFar = (x + shift) - localOrigin;
    const glm::dvec4 wNear = weights(nearRecs[t], nearProbes, x), wFar = weights(farRecs[t], farProbes, xFar);
    // 1e-5, or the float records' own rounding noise on slivers (the same near the origin and 10 km away;
    // with no local origin it would be ~1e3 times larger).
    const double tol =
        1e-5 + std::max(floatNoise(nearRecs[t], nearProbes, x), floatNoise(farRecs[t], farProbes, xFar));
    bool strict = true;
    for (int i = 0; i < 4; ++i) {
      EXPECT_NEAR(wFar[i], wNear[i], tol) << "tet " << t;
      EXPECT_NEAR(wFar[i], b[i], tol) << "tet " << t;
      strict = strict && std::abs(wFar[i] - wNear[i]) <= 1e-5;
    }
    slivers += strict ? 0 : 1;
  }
  EXPECT_LT(double(slivers), 0.05 * double(mesh.tets.size())) << slivers << " of " << mesh.tets.size();
  RecordProperty("tets_beyond_1e-5", int(slivers));
}

// The level stores no rows since format version 3: the float frame derived from the probe positions must
// give the gradients the stored rows had, i.e. the rows of the inverse of [P0-P3 | P1-P3 | P2-P3] computed in
// double, within float rounding times the tet's condition number (|M| x longest edge): 32 float ulps of it.
TEST(Barycentric, DerivedFrameMatchesRowsComputedInDouble) {
  const auto pts = jitteredGrid(8, 21);
  const TetMesh mesh = tetrahedralizeDelaunay(pts);
  const glm::dvec3 origin(0.25, -0.5, 0.75);
  const auto recs = buildTetRecords(pts, mesh, origin);
  const auto probes = floatProbes(pts, origin);
  double worst = 0.0, worstUlps = 0.0;
  for (size_t t = 0; t < recs.size(); ++t) {
    glm::dvec3 p[4];
    for (int i = 0; i < 4; ++i) p[i] = glm::dvec3(probes[size_t(recs[t].v[i])]);
    const glm::dmat3 m = glm::inverse(glm::dmat3(p[0] - p[3], p[1] - p[3], p[2] - p[3]));
    const BaryFrame f = baryFrame(recs[t], probes);
    double norm = 0.0, edge = 0.0;
    for (int i = 0; i < 3; ++i) norm = std::max(norm, glm::length(glm::dvec3(m[0][i], m[1][i], m[2][i])));
    for (int i = 0; i < 4; ++i)
      for (int j = i + 1; j < 4; ++j) edge = std::max(edge, glm::length(p[i] - p[j]));
    const double condition = norm * edge;
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) {
        const double err = std::abs(double(f.grad[i][j]) - m[j][i]) / norm;  // relative to the row's size
        worst = std::max(worst, err);
        worstUlps = std::max(worstUlps, err / (0x1p-24 * condition));
        ASSERT_LT(err, 32.0 * 0x1p-24 * condition)
            << "tet " << t << " row " << i << " column " << j << ", condition " << condition;
      }
    EXPECT_EQ(f.origin, probes[size_t(recs[t].v[3])]);
  }
  RecordProperty("worst_relative_gradient_error", std::to_string(worst));
  RecordProperty("worst_error_in_ulps_times_condition", std::to_string(worstUlps));
}

}  // namespace
}  // namespace tetraprobe
