// Baseline lookup: the nearest probe's SH, found through a uniform bucket grid. Used by the evaluation as the
// simplest competitor to tetrahedral interpolation.
#pragma once

#include <cstdint>
#include <vector>

#include <glm/vec3.hpp>

#include "tetraprobe/runtime/level.h"

namespace tetraprobe {

class NearestProbe {
 public:
  // Keeps a reference to `level` (must outlive this). Builds buckets of ~2 probes each.
  explicit NearestProbe(const Level& level);
  // Index of the probe nearest to a local-frame point (ties: lowest index); -1 for a level with no probes.
  int32_t nearest(const glm::vec3& local) const;
  // The bucket grid's memory (bounds, cell size, dims, prefix sums and probe order), bytes; the probes'
  // positions and SH are the level's.
  // The bucket grid, for the GPU pass (render.h RenderNearest): lower corner (local frame), cell size, cells
  // per axis, prefix sums (cells + 1) and probe order.
  const glm::vec3& bucketMin() const { return min_; }
  float bucketCell() const { return cell_; }
  const glm::ivec3& bucketDims() const { return dims_; }
  const std::vector<uint32_t>& bucketStart() const { return cellStart_; }
  const std::vector<uint32_t>& bucketOrder() const { return order_; }
  uint64_t bytes() const {
    return sizeof(min_) + sizeof(cell_) + sizeof(dims_) +
           (cellStart_.size() + order_.size()) * sizeof(uint32_t);
  }

 private:
  const Level& level_;
  glm::vec3 min_{0.0f};
  float cell_ = 1.0f;
  glm::ivec3 dims_{0};
  std::vector<uint32_t> cellStart_;  // prefix sums into order_, size cells + 1
  std::vector<uint32_t> order_;      // probe indices sorted by cell
};

}  // namespace tetraprobe
