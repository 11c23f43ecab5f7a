// Nearest-probe search over a uniform bucket grid: visit shells of cells around the query until the best
// distance found is smaller than the distance to any unvisited shell.
#include "tetraprobe/eval/nearest_probe.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include <glm/common.hpp>
#include <glm/geometric.hpp>

namespace tetraprobe {

NearestProbe::NearestProbe(const Level& level) : level_(level) {
  const auto& p = level.probes;
  if (p.empty()) return;
  glm::vec3 lo = p[0], hi = p[0];
  for (const auto& q : p) {
    lo = glm::min(lo, q);
    hi = glm::max(hi, q);
  }
  const glm::vec3 ext = glm::max(hi - lo, glm::vec3(1e-3f));
  const double volume = double(ext.x) * ext.y * ext.z;
  cell_ = float(std::cbrt(volume * 2.0 / double(p.size())));
  cell_ = std::max(cell_, 1e-3f * std::max({ext.x, ext.y, ext.z}));
  min_ = lo;
  dims_ = glm::max(glm::ivec3(glm::floor(ext / cell_)) + 1, glm::ivec3(1));
  const size_t cells = size_t(dims_.x) * dims_.y * dims_.z;
  std::vector<uint32_t> cellOf(p.size());
  cellStart_.assign(cells + 1, 0);
  for (size_t i = 0; i < p.size(); ++i) {
    const glm::ivec3 c = glm::clamp(glm::ivec3((p[i] - min_) / cell_), glm::ivec3(0), dims_ - 1);
    cellOf[i] = uint32_t(c.x + dims_.x * (c.y + dims_.y * c.z));
    ++cellStart_[cellOf[i] + 1];
  }
  for (size_t c = 0; c < cells; ++c) cellStart_[c + 1] += cellStart_[c];
  order_.resize(p.size());
  std::vector<uint32_t> fill(cellStart_.begin(), cellStart_.end() - 1);
  for (size_t i = 0; i < p.size(); ++i) order_[fill[cellOf[i]]++] = uint32_t(i);
}

RenderNearest NearestProbe::gpuBuckets() const {
  RenderNearest g;
  g.origin = level_.origin;
  g.min = min_;
  g.cell = cell_;
  g.dims = dims_;
  g.probeCount = level_.probes.size();
  g.cellStart = cellStart_.data();
  g.order = order_.data();
  g.positions = level_.probes.data();
  g.sh = level_.sh.data();
  return g;
}

int32_t NearestProbe::nearest(const glm::vec3& local) const {
  if (level_.probes.empty()) return -1;
  glm::vec3 q = local;
  if (!std::isfinite(q.x) || !std::isfinite(q.y) || !std::isfinite(q.z)) q = min_;
  const glm::ivec3 c = glm::clamp(glm::ivec3(glm::floor((q - min_) / cell_)), glm::ivec3(0), dims_ - 1);
  // Distance from q to the box of the grid, so shells beyond it are measured correctly for outside points.
  float best = std::numeric_limits<float>::infinity();
  int32_t bestIdx = -1;
  const int maxR = std::max({dims_.x, dims_.y, dims_.z});
  const glm::vec3 boxLo = min_, boxHi = min_ + glm::vec3(dims_) * cell_;
  const float outside = glm::length(glm::max(glm::max(boxLo - q, q - boxHi), glm::vec3(0.0f)));
  for (int r = 0; r <= maxR; ++r) {
    // Every cell on ring >= r is at least (r - 1) * cell_ (Chebyshev, so also Euclidean) and at least
    // `outside` away from q.
    if (bestIdx >= 0 && std::max(float(r - 1) * cell_, outside) > std::sqrt(best)) break;
    const glm::ivec3 lo = c - r, hi = c + r;
    for (int z = std::max(lo.z, 0); z <= std::min(hi.z, dims_.z - 1); ++z)
      for (int y = std::max(lo.y, 0); y <= std::min(hi.y, dims_.y - 1); ++y)
        for (int x = std::max(lo.x, 0); x <= std::min(hi.x, dims_.x - 1); ++x) {
          if (std::max({std::abs(x - c.x), std::abs(y - c.y), std::abs(z - c.z)}) != r) continue;
          const size_t cell = size_t(x) + size_t(dims_.x) * (size_t(y) + size_t(dims_.y) * size_t(z));
          for (uint32_t k = cellStart_[cell]; k < cellStart_[cell + 1]; ++k) {
            const uint32_t i = order_[k];
            const glm::vec3 d = level_.probes[i] - q;
            const float d2 = glm::dot(d, d);
            if (d2 < best || (d2 == best && int32_t(i) < bestIdx)) {
              best = d2;
              bestIdx = int32_t(i);
            }
          }
        }
  }
  return bestIdx;
}

}  // namespace tetraprobe
