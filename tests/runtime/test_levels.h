// Test levels built from point sets (through the build side's tetrahedralization) for the runtime tests.
#pragma once

#include <algorithm>
#include <cmath>
#include <map>
#include <random>
#include <vector>

#include <glm/geometric.hpp>
#include "tetraprobe/runtime/level.h"
#include "tetraprobe/runtime/query.h"
#include "tetraprobe/runtime/sh_half.h"

#include "tetraprobe/tetra/tetrahedralize.h"

namespace tetraprobe::test {

inline std::vector<glm::dvec3> randomBoxPoints(size_t n, uint64_t seed, const glm::dvec3& lo,
                                               const glm::dvec3& hi, bool withCorners = true) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::vector<glm::dvec3> pts;
  if (withCorners)
    for (int c = 0; c < 8; ++c)
      pts.emplace_back(c & 1 ? hi.x : lo.x, c & 2 ? hi.y : lo.y, c & 4 ? hi.z : lo.z);
  while (pts.size() < n) pts.push_back(lo + (hi - lo) * glm::dvec3(u(rng), u(rng), u(rng)));
  return pts;
}

// A level over world-space `points` with local frame `origin`, random SH (L2) unless `sh` is given.
inline Level makeLevel(const std::vector<glm::dvec3>& points, const glm::dvec3& origin, uint64_t seed = 1,
                       const ShRgb* sh = nullptr) {
  Level level;
  level.origin = origin;
  level.generator = "tetraprobe tests";
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<float> u(-1.0f, 1.0f);
  for (const glm::dvec3& p : points) {
    level.probes.emplace_back(p - origin);
    ShRgb s;
    if (sh) {
      s = *sh;
    } else {
      for (auto& c : s.c) c = glm::vec3(u(rng), u(rng), u(rng));
    }
    level.sh.push_back(quantizeSh(s));  // as a level file holds them (sh_half.h)
  }
  level.tets = buildTetRecords(points, tetrahedralizeDelaunay(points), origin);
  return level;
}

// Barycentric weights of local point x in tet t, in double from the probe positions (signed volumes of the tet
// with each vertex moved to x, over their sum): the exact reference the float rows approximate.
inline void exactTetWeights(const Level& level, const Tet& t, const glm::dvec3& x, double w[4]) {
  glm::dvec3 p[4];
  for (int i = 0; i < 4; ++i) p[i] = glm::dvec3(level.probes[size_t(t.v[i])]);
  const auto vol = [](const glm::dvec3& a, const glm::dvec3& b, const glm::dvec3& c, const glm::dvec3& d) {
    return glm::dot(a - d, glm::cross(b - d, c - d));
  };
  const double v[4] = {vol(x, p[1], p[2], p[3]), vol(p[0], x, p[2], p[3]), vol(p[0], p[1], x, p[3]),
                       vol(p[0], p[1], p[2], x)};
  const double sum = v[0] + v[1] + v[2] + v[3];
  for (int i = 0; i < 4; ++i) w[i] = v[i] / sum;
}

// The interpolation a location stands for: probe -> weight (independent of which of two tets sharing a face
// was named).
inline std::map<int32_t, double> probeWeights(const Level& level, const Location& loc) {
  std::map<int32_t, double> m;
  for (int i = 0; i < 4; ++i)
    if (loc.weights[i] != 0.0f) m[level.tets[size_t(loc.tet)].v[i]] += loc.weights[i];
  return m;
}

// Largest weight difference between two probe -> weight maps (a probe missing from one counts as 0).
inline double maxDifference(const std::map<int32_t, double>& a, const std::map<int32_t, double>& b) {
  double d = 0.0;
  for (const auto& [p, w] : a) d = std::max(d, std::abs(w - (b.count(p) ? b.at(p) : 0.0)));
  for (const auto& [p, w] : b) d = std::max(d, std::abs(w - (a.count(p) ? a.at(p) : 0.0)));
  return d;
}

}  // namespace tetraprobe::test
