// Baseline lookup: the nearest probe's SH, found through a uniform bucket grid. Used by the evaluation as the
// simplest competitor to tetrahedral interpolation.
#pragma once

#include <cstdint>
#include <vector>

#include <glm/vec3.hpp>

#include "tetraprobe/render/render.h"
#include "tetraprobe/runtime/level.h"

namespace tetraprobe {

class NearestProbe {
 public:
  // Keeps a reference to `level` (must outlive this). Builds buckets of ~2 probes each.
  explicit NearestProbe(const Level& level);
  // Index of the probe nearest to a local-frame point (ties: lowest index); -1 for a level with no probes.
  int32_t nearest(const glm::vec3& local) const;
  // These buckets and the level's probes as renderNearestProbe (render.h) reads them, in the level's local
  // frame; the pointers are into this object and the level (both must outlive the render).
  RenderNearest gpuBuckets() const;
  // The bucket grid's memory (bounds, cell size, dims, prefix sums and probe order), bytes; the probes'
  // positions and SH are the level's.
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
