// The per-tet barycentric rows buildTetRecords() writes, evaluated the way level.h documents them.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>

#include <glm/vec4.hpp>

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

// level.h: w_i = dot(row[i].xyz, X) + row[i].w for i < 3, w_3 = 1 - sum (X in the local frame).
glm::dvec4 weights(const Tet& t, const glm::dvec3& local) {
  glm::dvec4 w;
  for (int i = 0; i < 3; ++i)
    w[i] = t.row[i][0] * local.x + t.row[i][1] * local.y + t.row[i][2] * local.z + t.row[i][3];
  w[3] = 1.0 - w[0] - w[1] - w[2];
  return w;
}

// Rounding noise of the float record at local point x: a few float ulps of the largest terms of each weight
// (w_3 sums all three rows). Large only for slivers, whose rows are large.
double floatNoise(const Tet& t, const glm::dvec3& x) {
  double n = 0.0;
  for (int i = 0; i < 3; ++i)
    n += std::abs(t.row[i][0] * x.x) + std::abs(t.row[i][1] * x.y) + std::abs(t.row[i][2] * x.z) +
         std::abs(t.row[i][3]);
  return 4.0 * 0x1p-24 * n;
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
  std::mt19937_64 rng(5);
  for (size_t t = 0; t < recs.size(); ++t) {
    glm::dvec4 b;
    const glm::dvec4 w = weights(recs[t], randomInside(pts, mesh.tets[t], rng, b));
    EXPECT_NEAR(w.x + w.y + w.z + w.w, 1.0, 1e-12);
    for (int i = 0; i < 4; ++i) {
      EXPECT_GE(w[i], -1e-5) << "tet " << t;
      const glm::dvec4 atVertex = weights(recs[t], pts[size_t(mesh.tets[t][size_t(i)])]);
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
  const glm::dvec3 grad(0.7, -1.3, 2.1);
  const double offset = 3.0;
  auto f = [&](const glm::dvec3& x) { return grad.x * x.x + grad.y * x.y + grad.z * x.z + offset; };
  const double scale = 10.0 * (std::abs(grad.x) + std::abs(grad.y) + std::abs(grad.z)) + offset;  // max |f|
  std::mt19937_64 rng(6);
  for (size_t t = 0; t < recs.size(); ++t)
    for (int k = 0; k < 4; ++k) {
      glm::dvec4 b;
      const glm::dvec3 x = randomInside(pts, mesh.tets[t], rng, b);
      const glm::dvec4 w = weights(recs[t], x);
      double interp = 0.0;
      for (int i = 0; i < 4; ++i) interp += w[i] * f(pts[size_t(mesh.tets[t][size_t(i)])]);
      EXPECT_NEAR(interp, f(x), 1e-5 * scale) << "tet " << t;
    }
}

// Probes as placement makes them: a 2 m grid, jittered by up to 0.4 m (random clouds have slivers whose
// float rows carry ~2e-5 of rounding noise wherever they sit, which would hide what this test looks for).
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

// Levels sit kilometres from the world origin; the local origin must keep float rows as precise as at 0.
TEST(Barycentric, FarFromOriginMatchesOrigin) {
  const auto pts = jitteredGrid(10, 13);
  const glm::dvec3 shift(10000.0, -10000.0, 10000.0);
  std::vector<glm::dvec3> far = pts;
  for (auto& p : far) p += shift;
  const TetMesh mesh = tetrahedralizeDelaunay(pts);
  const auto nearRecs = buildTetRecords(pts, mesh, glm::dvec3(0.0));
  const glm::dvec3 localOrigin = shift + glm::dvec3(1.5, 2.5, -3.5);  // e.g. the level's bounds centre
  const auto farRecs = buildTetRecords(far, mesh, localOrigin);
  std::mt19937_64 rng(7);
  size_t slivers = 0;  // tets that needed more than 1e-5
  for (size_t t = 0; t < mesh.tets.size(); ++t) {
    glm::dvec4 b;
    const glm::dvec3 x = randomInside(pts, mesh.tets[t], rng, b);
    const glm::dvec3 xFar = (x + shift) - localOrigin;
    const glm::dvec4 wNear = weights(nearRecs[t], x), wFar = weights(farRecs[t], xFar);
    // 1e-5, or the float records' own rounding noise on slivers (the same near the origin and 10 km away;
    // with no local origin it would be ~1e3 times larger).
    const double tol = 1e-5 + std::max(floatNoise(nearRecs[t], x), floatNoise(farRecs[t], xFar));
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

}  // namespace
}  // namespace tetraprobe
