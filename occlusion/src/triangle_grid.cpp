// Uniform grid of scene triangles (by bounding box) for finding the triangles that may cut a tet. Built in
// two passes into CSR arrays (count, then fill), so cells list triangles in increasing index order.
#include <algorithm>
#include <cmath>

#include <glm/common.hpp>
#include <glm/vector_relational.hpp>

#include "tet_geometry.h"

namespace tetraprobe::occlusion_detail {
namespace {

constexpr double kCellsPerTriangle = 2.0;      // target grid size relative to the triangle count
constexpr double kMaxCells = double(1 << 21);  // memory bound: 8 MB of cell starts
constexpr int kMaxDim = 512;

}  // namespace

TriangleGrid::TriangleGrid(const Scene& scene, const std::vector<glm::dvec3>& local, const glm::dvec3& lo,
                           const glm::dvec3& hi) {
  const glm::dvec3 ext = glm::max(hi - lo, glm::dvec3(1e-6));
  lo_ = lo;
  const double target = std::clamp(kCellsPerTriangle * double(scene.triangles.size()), 1.0, kMaxCells);
  const double side = std::cbrt(ext.x * ext.y * ext.z / target);
  for (int a = 0; a < 3; ++a) dims_[a] = std::clamp(int(std::ceil(ext[a] / side)), 1, kMaxDim);
  cell_ = ext / glm::dvec3(dims_);
  const size_t cells = size_t(dims_.x) * size_t(dims_.y) * size_t(dims_.z);
  start_.assign(cells + 1, 0);

  auto range = [&](uint32_t t, glm::ivec3& a, glm::ivec3& b) {
    const glm::uvec3 tri = scene.triangles[t];
    const glm::dvec3 tlo = glm::min(local[tri.x], glm::min(local[tri.y], local[tri.z]));
    const glm::dvec3 thi = glm::max(local[tri.x], glm::max(local[tri.y], local[tri.z]));
    if (glm::any(glm::lessThan(thi, lo)) || glm::any(glm::greaterThan(tlo, hi))) return false;
    a = cellOf(tlo);
    b = cellOf(thi);
    return true;
  };
  auto visit = [&](auto&& fn) {
    for (uint32_t t = 0; t < uint32_t(scene.triangles.size()); ++t) {
      glm::ivec3 a, b;
      if (!range(t, a, b)) continue;
      for (int z = a.z; z <= b.z; ++z)
        for (int y = a.y; y <= b.y; ++y)
          for (int x = a.x; x <= b.x; ++x)
            fn(t, size_t(x) + size_t(dims_.x) * (size_t(y) + size_t(dims_.y) * z));
    }
  };
  visit([&](uint32_t, size_t c) { ++start_[c + 1]; });
  for (size_t c = 0; c < cells; ++c) start_[c + 1] += start_[c];
  items_.resize(start_[cells]);
  std::vector<uint32_t> fill(start_.begin(), start_.end() - 1);
  visit([&](uint32_t t, size_t c) { items_[fill[c]++] = t; });
}

glm::ivec3 TriangleGrid::cellOf(const glm::dvec3& p) const {
  glm::ivec3 c;
  for (int a = 0; a < 3; ++a) {
    const double f = std::floor((p[a] - lo_[a]) / cell_[a]);
    c[a] = int(std::clamp(f, 0.0, double(dims_[a] - 1)));
  }
  return c;
}

void TriangleGrid::query(const glm::dvec3& lo, const glm::dvec3& hi, std::vector<uint32_t>& out) const {
  out.clear();
  const glm::ivec3 a = cellOf(lo), b = cellOf(hi);
  for (int z = a.z; z <= b.z; ++z)
    for (int y = a.y; y <= b.y; ++y)
      for (int x = a.x; x <= b.x; ++x) {
        const size_t c = size_t(x) + size_t(dims_.x) * (size_t(y) + size_t(dims_.y) * z);
        out.insert(out.end(), items_.begin() + start_[c], items_.begin() + start_[c + 1]);
      }
  std::sort(out.begin(), out.end());
  out.erase(std::unique(out.begin(), out.end()), out.end());
}

}  // namespace tetraprobe::occlusion_detail
