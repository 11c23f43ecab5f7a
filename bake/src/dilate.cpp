// Dilation of invalid probes: each takes the SH of its nearest valid probe. Contract: bake/bake.h
// (dilateInvalidProbes).
#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#include <glm/common.hpp>
#include <glm/geometric.hpp>

#include "tetraprobe/bake/bake.h"

namespace tetraprobe {

namespace {

constexpr double kValidPerCell = 4.0;  // grid density: about this many valid probes per cell
constexpr int64_t kMaxCellsPerAxis = 1024;

}  // namespace

size_t dilateInvalidProbes(const std::vector<glm::dvec3>& positions, const std::vector<uint8_t>& invalid,
                           std::vector<ShRgb>& sh, std::vector<uint32_t>* source) {
  if (positions.size() != invalid.size() || positions.size() != sh.size())
    throw std::invalid_argument("dilateInvalidProbes: positions, invalid flags and SH differ in size");
  if (source) {
    source->resize(positions.size());
    for (size_t i = 0; i < positions.size(); ++i) (*source)[i] = uint32_t(i);
  }
  std::vector<uint32_t> valid;
  for (size_t i = 0; i < positions.size(); ++i)
    if (!invalid[i]) valid.push_back(uint32_t(i));
  if (valid.empty() || valid.size() == positions.size()) return 0;

  // Uniform grid over the valid probes' bounds.
  glm::dvec3 lo(std::numeric_limits<double>::infinity()), hi(-std::numeric_limits<double>::infinity());
  for (uint32_t i : valid) {
    lo = glm::min(lo, positions[i]);
    hi = glm::max(hi, positions[i]);
  }
  const glm::dvec3 ext = glm::max(hi - lo, glm::dvec3(1e-6));
  const double cell = std::max(std::cbrt(ext.x * ext.y * ext.z * kValidPerCell / double(valid.size())),
                               std::max({ext.x, ext.y, ext.z}) / double(kMaxCellsPerAxis));
  glm::i64vec3 dims;
  for (int a = 0; a < 3; ++a) dims[a] = std::clamp<int64_t>(int64_t(ext[a] / cell) + 1, 1, kMaxCellsPerAxis);
  auto cellOf = [&](const glm::dvec3& p) {
    glm::i64vec3 c;
    for (int a = 0; a < 3; ++a)
      c[a] = std::clamp<int64_t>(int64_t(std::floor((p[a] - lo[a]) / cell)), 0, dims[a] - 1);
    return c;
  };
  const size_t cells = size_t(dims.x * dims.y * dims.z);
  std::vector<uint32_t> start(cells + 1, 0), items(valid.size());
  auto index = [&](const glm::i64vec3& c) { return size_t(c.x + dims.x * (c.y + dims.y * c.z)); };
  for (uint32_t i : valid) ++start[index(cellOf(positions[i])) + 1];
  for (size_t c = 0; c < cells; ++c) start[c + 1] += start[c];
  {
    std::vector<uint32_t> fill(start.begin(), start.end() - 1);
    for (uint32_t i : valid) items[fill[index(cellOf(positions[i]))]++] = i;  // ascending within a cell
  }

  const std::vector<ShRgb> original = sh;
  size_t replaced = 0;
  const int64_t maxRing = std::max({dims.x, dims.y, dims.z});
  for (size_t i = 0; i < positions.size(); ++i) {
    if (!invalid[i]) continue;
    const glm::dvec3 p = positions[i];
    // The query's cell, clamped to the grid; its distance outside the grid is added to every ring bound.
    const glm::i64vec3 c = cellOf(p);
    const glm::dvec3 outside = glm::max(glm::max(lo - p, p - hi), glm::dvec3(0.0));
    const double offGrid = std::max({outside.x, outside.y, outside.z});
    uint32_t best = 0;
    double bestD = std::numeric_limits<double>::infinity();
    for (int64_t r = 0; r <= maxRing; ++r) {
      for (int64_t z = std::max<int64_t>(c.z - r, 0); z <= std::min(c.z + r, dims.z - 1); ++z)
        for (int64_t y = std::max<int64_t>(c.y - r, 0); y <= std::min(c.y + r, dims.y - 1); ++y)
          for (int64_t x = std::max<int64_t>(c.x - r, 0); x <= std::min(c.x + r, dims.x - 1); ++x) {
            if (std::max({std::abs(x - c.x), std::abs(y - c.y), std::abs(z - c.z)}) != r) continue;
            const size_t k = index({x, y, z});
            for (uint32_t s = start[k]; s < start[k + 1]; ++s) {
              const uint32_t j = items[s];
              const glm::dvec3 d = positions[j] - p;
              const double d2 = glm::dot(d, d);
              if (d2 < bestD || (d2 == bestD && j < best)) {
                bestD = d2;
                best = j;
              }
            }
          }
      // Every valid probe in ring r + 1 or beyond is at least r cells away along one axis, and every valid
      // probe is at least the off-grid gap away along another (or the same) axis.
      const double bound2 = double(r) * cell * double(r) * cell + offGrid * offGrid;
      if (bestD < std::numeric_limits<double>::infinity() && bestD <= bound2) break;
    }
    sh[i] = original[best];
    if (source) (*source)[i] = best;
    ++replaced;
  }
  return replaced;
}

}  // namespace tetraprobe
