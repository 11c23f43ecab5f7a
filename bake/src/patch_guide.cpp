// Lit-patch sampling of a probe's first bounce. Contract: patch_guide.h.
#include "patch_guide.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "path_tracer.h"
#include "rng.h"
#include "sampling.h"
#include "tetraprobe/common/parallel.h"
#include "tracer_impl.h"

namespace tetraprobe::bake_detail {

int cellsPerEdge(float area, double cellArea) {
  if (!(area > 0.0f) || !(cellArea > 0.0)) return 1;
  const double k = std::ceil(std::sqrt(double(area) / cellArea));
  return int(std::clamp(k, 1.0, 64.0));
}

uint32_t cellOf(float u, float v, int k) {
  const double a = double(std::clamp(u, 0.0f, 1.0f)) * k, b = double(std::clamp(v, 0.0f, 1.0f)) * k;
  int i = std::clamp(int(std::floor(a)), 0, k - 1), j = std::clamp(int(std::floor(b)), 0, k - 1);
  if (i + j > k - 1) j = std::max(0, k - 1 - i);  // rounding past the hypotenuse
  const bool inverted = i + j < k - 1 && (a - i) + (b - j) > 1.0;
  return uint32_t(2 * (i * k + j) + (inverted ? 1 : 0));
}

namespace {

// Barycentrics of the point at coordinates (s, t) of cell `cell`'s own unit triangle (k to an edge): an
// upright cell's corners are (i, j), (i + 1, j), (i, j + 1) over k, an inverted one's (i + 1, j + 1),
// (i, j + 1), (i + 1, j).
glm::vec2 cellToTriangle(uint32_t cell, int k, float s, float t) {
  const int c = int(cell / 2), i = c / k, j = c % k;
  if (cell & 1u) return glm::vec2((float(i + 1) - s) / float(k), (float(j + 1) - t) / float(k));
  return glm::vec2((float(i) + s) / float(k), (float(j) + t) / float(k));
}

}  // namespace

glm::vec2 cellPoint(uint32_t cell, int k, float u1, float u2) {
  const glm::vec2 b = uniformTriangle(u1, u2);
  return cellToTriangle(cell, k, b.x, b.y);
}

namespace {

// Points a lit-map cell is lit-tested at (a cell half in shadow then mostly gets a weight between).
constexpr int kLitMapPointsPerCell = 4;

bool cellExists(uint32_t cell, int k) {
  const int c = int(cell / 2), i = c / k, j = c % k;
  return (cell & 1u) ? i + j <= k - 2 : i + j <= k - 1;
}

// Barycentrics of a cell's centroid.
glm::vec2 cellCentre(uint32_t cell, int k) {
  const float third = 1.0f / 3.0f;
  return cellToTriangle(cell, k, third, third);
}

}  // namespace

LitMap::LitMap(const SceneTracer& tracer, double cellArea, double voxel, uint64_t seed, int threads)
    : tracer_(&tracer), cellArea_(cellArea), inverseVoxel_(1.0 / voxel) {
  const SceneTracer::Impl& impl = tracer.impl();
  const size_t triangles = impl.areas.size();
  offset_.resize(triangles + 1);
  size_t slots = 0;
  for (size_t t = 0; t < triangles; ++t) {
    offset_[t] = slots;
    const int k = cellsPerEdge(uint32_t(t));
    slots += size_t(2 * k * k);
  }
  offset_[triangles] = slots;
  weight_.assign(slots, 0.0f);
  parallelFor(triangles, threads, [&](size_t t) {
    DenormalScope denormals;
    const uint32_t tri = uint32_t(t);
    const Material& m = impl.material(tri);
    const float reflect = reflectedShare(m);
    if (maxComponent(m.albedo) <= 0.0f || !(reflect > 0.0f) || !(impl.areas[t] > 0.0f)) return;
    const int k = cellsPerEdge(tri);
    const float cellArea = impl.areas[t] / float(k * k);
    const glm::vec3 nt = impl.normals[t];
    const float eps = impl.rayEpsilon;
    for (uint32_t cell = 0; cell < uint32_t(2 * k * k); ++cell) {
      if (!cellExists(cell, k)) continue;
      Rng rng(streamKey(seed, t, cell));
      glm::vec3 e(0.0f);
      for (int s = 0; s < kLitMapPointsPerCell; ++s) {
        // Stratified: point s in the s-th quarter of the cell's first coordinate's range.
        const float u1 = (float(s) + rng.uniform()) / float(kLitMapPointsPerCell), u2 = rng.uniform();
        const glm::vec2 uv = cellPoint(cell, k, u1, u2);
        if (tracer.isHole(tri, uv.x, uv.y)) continue;
        const glm::vec3 y = impl.pointOn(tri, uv.x, uv.y);
        for (const glm::vec3 n : {nt, -nt}) {
          const glm::vec3 p = y + n * eps;
          e += punctualIrradiance(tracer, p, p, n, rng);
        }
      }
      const float w = luminance(m.albedo * e) * (reflect * cellArea / float(kLitMapPointsPerCell));
      if (w > 0.0f && std::isfinite(w)) weight_[offset_[t] + cell] = w;
    }
  });
  // Voxels in triangle and cell order, so each voxel's list (and its cumulative sums) is the same for any
  // thread count.
  for (size_t t = 0; t < triangles; ++t) {
    const int k = cellsPerEdge(uint32_t(t));
    for (uint32_t cell = 0; cell < uint32_t(2 * k * k); ++cell) {
      const float w = weight_[offset_[t] + cell];
      if (!(w > 0.0f)) continue;
      Voxel& v = voxels_[voxelOf(uint32_t(t), cell)];
      v.cells.push_back((uint64_t(t) << 32) | cell);
      v.cdf.push_back((v.cdf.empty() ? 0.0 : v.cdf.back()) + double(w));
    }
  }
}

int LitMap::cellsPerEdge(uint32_t triangle) const {
  return bake_detail::cellsPerEdge(tracer_->impl().areas[triangle], cellArea_);
}

uint64_t LitMap::voxelOf(uint32_t triangle, uint32_t cell) const {
  const glm::vec2 c = cellCentre(cell, cellsPerEdge(triangle));
  const glm::vec3 p = tracer_->impl().pointOn(triangle, c.x, c.y);
  // 21 bits a coordinate (two's complement, wrapped): voxels 2^21 apart share a key, far beyond any level.
  auto q = [this](float x) { return uint64_t(int64_t(std::floor(double(x) * inverseVoxel_))) & 0x1fffffull; };
  return q(p.x) | (q(p.y) << 21) | (q(p.z) << 42);
}

uint64_t LitMap::voxelAt(uint32_t triangle, float u, float v) const {
  return voxelOf(triangle, cellOf(u, v, cellsPerEdge(triangle)));
}

const LitMap::Voxel* LitMap::voxel(uint64_t key) const {
  const auto it = voxels_.find(key);
  return it == voxels_.end() ? nullptr : &it->second;
}

void PatchHistogram::add(uint64_t key, double value) {
  if (std::isfinite(value) && value > 0.0) sum[key] += value;
}

PatchGuide::PatchGuide(const PatchHistogram& histogram, const SceneTracer& tracer, const LitMap& map)
    : tracer_(&tracer), map_(&map) {
  std::vector<std::pair<uint64_t, double>> voxels;
  for (const auto& [key, value] : histogram.sum)
    if (map.voxel(key) != nullptr) voxels.emplace_back(key, value);
  std::sort(voxels.begin(), voxels.end());
  double total = 0.0;
  for (const auto& v : voxels) total += v.second;
  if (!(total > 0.0) || !std::isfinite(total)) return;
  double run = 0.0;
  for (const auto& [key, value] : voxels) {
    const double p = value / total;
    run += p;
    keys_.push_back(key);
    cdf_.push_back(run);
    probability_[key] = p / map.voxel(key)->cdf.back();
  }
  cdf_.back() = 1.0;
}

PatchPoint PatchGuide::sample(double u1, double u2, float u3, float u4) const {
  const size_t n =
      std::min(size_t(std::upper_bound(cdf_.begin(), cdf_.end(), u1) - cdf_.begin()), keys_.size() - 1);
  const uint64_t key = keys_[n];
  const LitMap::Voxel& v = *map_->voxel(key);
  const double target = u2 * v.cdf.back();
  const size_t c = std::min(size_t(std::upper_bound(v.cdf.begin(), v.cdf.end(), target) - v.cdf.begin()),
                            v.cells.size() - 1);
  const uint32_t tri = uint32_t(v.cells[c] >> 32), cell = uint32_t(v.cells[c] & 0xffffffffu);
  const int k = map_->cellsPerEdge(tri);
  const glm::vec2 uv = cellPoint(cell, k, u3, u4);
  PatchPoint out;
  out.triangle = tri;
  out.u = uv.x;
  out.v = uv.y;
  const double cellArea = double(tracer_->impl().areas[tri]) / double(k * k);
  out.pdfArea = float(probability_.at(key) * double(map_->weight(tri, cell)) / cellArea);
  return out;
}

float PatchGuide::pdfArea(uint32_t triangle, float u, float v) const {
  if (keys_.empty()) return 0.0f;
  const int k = map_->cellsPerEdge(triangle);
  const uint32_t cell = cellOf(u, v, k);
  const float w = map_->weight(triangle, cell);
  if (!(w > 0.0f)) return 0.0f;
  const auto it = probability_.find(map_->voxelOf(triangle, cell));
  if (it == probability_.end()) return 0.0f;
  const double cellArea = double(tracer_->impl().areas[triangle]) / double(k * k);
  return float(it->second * double(w) / cellArea);
}

}  // namespace tetraprobe::bake_detail
