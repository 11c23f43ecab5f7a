// Lit-patch sampling of a probe's first bounce: where the sun (or a point or spot light) lights surfaces that
// a probe sees, most of the probe's light is that one bounce, and it comes from sharp-edged lit patches
// (a sunlit floor past a doorway, a sunlit strip of wall). Directions drawn over the sphere, even guided by a
// histogram of directions (probe_guide.h, bins of about 18 degrees), find them by chance: q3 dm4ish stops
// 3,548 of its 3,905 traced probes at the path cap at a mean relative stderr of 0.116, and 92-97 % of its
// probes' light is that one bounce. Lit-patch sampling draws points on the lit surfaces themselves, as the
// bake draws points on emissive triangles, in two levels:
// - a LitMap, the same for every probe: each triangle cut into cells of about `cellArea`, each cell weighted
//   by its one-bounce light at a point drawn in it (area x albedo / pi x the punctual lights' irradiance,
//   shadow-tested, both sides), and the lit cells grouped by the voxel (edge `voxel`) holding their centre;
// - a PatchGuide per probe: its own batches record in which voxels their first hit found lit surface, and
//   later batches pick a voxel in proportion, a cell of it by the map's weights and a uniform point in the
//   cell, shadow-test it from the probe and take its one-bounce light, MIS-weighted (power heuristic)
//   against the sphere directions, whose first hit weighs its punctual light the same way.
// Unbiased whatever the map and the voxels hold: where the guide's density is 0 (a voxel the probe's paths
// have not found lit, a cell the map missed) the sphere directions carry the light with weight 1 (Veach
// 1997, ch. 9). Internal to the bake module. Figures: docs/accuracy.md#lit-patch-sampling.
#pragma once

#include <cstddef>
#include <cstdint>
#include <unordered_map>
#include <vector>

#include <glm/vec2.hpp>

namespace tetraprobe {
class SceneTracer;
}

namespace tetraprobe::bake_detail {

// Cells an edge of a triangle of `area` is cut into: ceil(sqrt(area / cellArea)), in [1, 64].
int cellsPerEdge(float area, double cellArea);

// The cell of barycentrics (u, v) (point = (1-u-v) P0 + u P1 + v P2) on a triangle cut k to an edge:
// 2 (i k + j) + (inverted ? 1 : 0), i = floor(u k), j = floor(v k). Points on or outside the edges go to the
// nearest cell. Cells with i + j <= k - 1 exist (the inverted one only for i + j <= k - 2).
uint32_t cellOf(float u, float v, int k);
// Barycentrics of a uniform point of cell `cell` (k to an edge) from two uniforms.
glm::vec2 cellPoint(uint32_t cell, int k, float u1, float u2);

class LitMap {
 public:
  struct Voxel {
    std::vector<uint64_t> cells;  // (triangle << 32) | cell, lit cells whose centre is in the voxel
    std::vector<double> cdf;      // cumulative weights, the last the voxel's total
  };

  LitMap() = default;
  // cellArea and voxel finite and > 0. Threads never change the result.
  LitMap(const SceneTracer& tracer, double cellArea, double voxel, uint64_t seed, int threads);

  double cellArea() const { return cellArea_; }
  int cellsPerEdge(uint32_t triangle) const;
  // The lit cell of barycentrics (u, v) of `triangle`: its weight (0 when unlit) and voxel key.
  float weight(uint32_t triangle, uint32_t cell) const { return weight_[offset_[triangle] + cell]; }
  uint64_t voxelOf(uint32_t triangle, uint32_t cell) const;
  // The voxel of the cell holding barycentrics (u, v) of `triangle`.
  uint64_t voxelAt(uint32_t triangle, float u, float v) const;
  // The voxel of `key`, null when it holds no lit cell.
  const Voxel* voxel(uint64_t key) const;

 private:
  const SceneTracer* tracer_ = nullptr;
  double cellArea_ = 1.0, inverseVoxel_ = 1.0;
  std::vector<size_t>
      offset_;  // per triangle (and one past the last): its first cell slot (2 k^2 a triangle)
  std::vector<float> weight_;
  std::unordered_map<uint64_t, Voxel> voxels_;
};

// Light per voxel key, summed over samples (non-finite or non-positive values are ignored).
struct PatchHistogram {
  std::unordered_map<uint64_t, double> sum;
  void add(uint64_t key, double value);
};

// A point drawn by a PatchGuide.
struct PatchPoint {
  uint32_t triangle = 0;
  float u = 0.0f, v = 0.0f;  // barycentrics
  float pdfArea = 0.0f;      // density per m^2: P(voxel) x the cell's share of the voxel / the cell's area
};

class PatchGuide {
 public:
  PatchGuide() = default;  // no voxels: active() false
  // Each voxel the map holds lit cells in takes the histogram's share of it (voxels in key order, so the
  // result does not depend on the map's order).
  PatchGuide(const PatchHistogram& histogram, const SceneTracer& tracer, const LitMap& map);

  bool active() const { return !keys_.empty(); }
  // u1 picks the voxel, u2 a cell of it by the map's weights, u3 and u4 a uniform point in the cell; u in
  // [0, 1). Needs active().
  PatchPoint sample(double u1, double u2, float u3, float u4) const;
  // The density per m^2 at barycentrics (u, v) of `triangle` (0 off the guide's voxels and the map's lit
  // cells).
  float pdfArea(uint32_t triangle, float u, float v) const;

 private:
  const SceneTracer* tracer_ = nullptr;
  const LitMap* map_ = nullptr;
  std::vector<uint64_t> keys_;
  std::vector<double> cdf_;
  std::unordered_map<uint64_t, double> probability_;  // voxel key -> P(voxel) / voxel total weight
};

}  // namespace tetraprobe::bake_detail
