// Regular SH L2 irradiance grid: lattice sizing to a node or byte budget, bake (inside test, path tracing,
// dilation, dering) and trilinear lookup. Contract: eval/grid_volume.h.
// References: Unity Adaptive Probe Volumes documentation (validity by back-face rays, dilation);
// Ramamoorthi & Hanrahan 2001 (SH irradiance, runtime/sh.h).
#include "tetraprobe/eval/grid_volume.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <sstream>
#include <stdexcept>

#include "tetraprobe/common/error.h"

namespace tetraprobe {

namespace {

// Nodes per axis for extent `ext` at spacing h: enough intervals to cover it, at least 2 nodes.
int64_t axisNodes(double ext, double h) {
  // The small slack keeps an extent that is an exact multiple of h from gaining a node to rounding.
  return std::max<int64_t>(2, int64_t(std::ceil(ext / h - 1e-9)) + 1);
}

double nodeCount(const glm::dvec3& ext, double h) {
  return double(axisNodes(ext.x, h)) * double(axisNodes(ext.y, h)) * double(axisNodes(ext.z, h));
}

}  // namespace

glm::dvec3 GridLayout::node(size_t index) const {
  const size_t i = index % size_t(dims.x), j = (index / size_t(dims.x)) % size_t(dims.y),
               k = index / (size_t(dims.x) * size_t(dims.y));
  return min + glm::dvec3(double(i), double(j), double(k)) * step;
}

GridLayout gridLayoutForNodes(const glm::dvec3& lo, const glm::dvec3& hi, uint64_t maxNodes) {
  for (int a = 0; a < 3; ++a)
    if (!std::isfinite(lo[a]) || !std::isfinite(hi[a]) || lo[a] > hi[a])
      throw std::invalid_argument("gridLayoutForNodes: the box must be finite with lo <= hi");
  const glm::dvec3 ext = hi - lo;
  const double longest = std::max({ext.x, ext.y, ext.z});
  GridLayout layout;
  double h = longest > 0.0 ? longest : 1.0;  // 2 nodes on the longest axis: 8 nodes in all
  if (longest > 0.0 && double(maxNodes) >= 8.0) {
    // nodeCount falls as h grows: bisect for the smallest h within the budget.
    double lo_h = longest * 1e-6, hi_h = longest;
    if (nodeCount(ext, lo_h) <= double(maxNodes)) hi_h = lo_h;
    for (int it = 0; it < 200 && hi_h - lo_h > 1e-12 * longest; ++it) {
      const double mid = 0.5 * (lo_h + hi_h);
      (nodeCount(ext, mid) <= double(maxNodes) ? hi_h : lo_h) = mid;
    }
    h = hi_h;
  }
  layout.step = h;
  layout.dims = glm::ivec3(int(axisNodes(ext.x, h)), int(axisNodes(ext.y, h)), int(axisNodes(ext.z, h)));
  const glm::dvec3 span = glm::dvec3(layout.dims - 1) * h;
  layout.min = (lo + hi) * 0.5 - span * 0.5;
  return layout;
}

GridLayout gridLayoutForBytes(const glm::dvec3& lo, const glm::dvec3& hi, uint64_t maxBytes) {
  const uint64_t nodes = maxBytes > kGridHeaderBytes ? (maxBytes - kGridHeaderBytes) / kGridNodeBytes : 0;
  return gridLayoutForNodes(lo, hi, nodes);
}

GridVolume::GridVolume(const GridLayout& layout, std::vector<ShRgb> sh, std::vector<uint8_t> invalid)
    : layout_(layout), sh_(std::move(sh)), invalid_(std::move(invalid)) {
  if (sh_.size() != layout_.nodes() || invalid_.size() != layout_.nodes())
    throw std::invalid_argument("GridVolume: " + std::to_string(sh_.size()) + " SH and " +
                                std::to_string(invalid_.size()) + " flags for " +
                                std::to_string(layout_.nodes()) + " nodes");
  std::vector<glm::dvec3> positions(layout_.nodes());
  for (size_t i = 0; i < positions.size(); ++i) positions[i] = layout_.node(i);
  dilateInvalidProbes(positions, invalid_, sh_);
}

size_t GridVolume::invalidNodes() const {
  return size_t(std::count_if(invalid_.begin(), invalid_.end(), [](uint8_t v) { return v != 0; }));
}

ShRgb GridVolume::blend(const glm::dvec3& p) const {
  int i0[3];
  float f[3];
  for (int a = 0; a < 3; ++a) {
    const double u = std::clamp((p[a] - layout_.min[a]) / layout_.step, 0.0, double(layout_.dims[a] - 1));
    const int i = std::min(int(u), layout_.dims[a] - 2);
    i0[a] = i;
    f[a] = float(u - double(i));
  }
  const size_t sx = 1, sy = size_t(layout_.dims.x), sz = size_t(layout_.dims.x) * size_t(layout_.dims.y);
  const size_t base = size_t(i0[0]) * sx + size_t(i0[1]) * sy + size_t(i0[2]) * sz;
  ShRgb out;
  for (int corner = 0; corner < 8; ++corner) {
    const int cx = corner & 1, cy = (corner >> 1) & 1, cz = corner >> 2;
    const float w = (cx ? f[0] : 1.0f - f[0]) * (cy ? f[1] : 1.0f - f[1]) * (cz ? f[2] : 1.0f - f[2]);
    const ShRgb& s = sh_[base + size_t(cx) * sx + size_t(cy) * sy + size_t(cz) * sz];
    for (int c = 0; c < kShCoeffCount; ++c) out.c[size_t(c)] += w * s.c[size_t(c)];
  }
  return out;
}

glm::vec3 GridVolume::irradiance(const glm::dvec3& p, const glm::vec3& n) const {
  return shIrradiance(blend(p), n);
}

GridVolume bakeGridVolume(const SceneTracer& tracer, const GridLayout& layout, const BakeOptions& bake,
                          const DeringOptions& dering, GridBakeStats* stats) {
  const auto start = std::chrono::steady_clock::now();
  std::vector<glm::dvec3> positions(layout.nodes());
  for (size_t i = 0; i < positions.size(); ++i) positions[i] = layout.node(i);
  std::vector<uint8_t> inside = probesInsideGeometry(tracer, positions, 64, 0.25, bake.threads);
  GridBakeStats local;
  std::vector<ShRgb> sh = bakeProbes(tracer, positions, bake, &local.bake, &inside);
  GridVolume grid(layout, std::move(sh), std::move(inside));
  // Dering after dilation, as the bake pipeline does (the copies get the same window as their source).
  DeringOptions d = dering;
  d.threads = bake.threads;
  std::vector<ShRgb> deringed = grid.sh();
  local.dering = deringProbes(deringed, d);
  // Stored as a level stores its probes (half precision, sh_half.h): the grid is charged kGridNodeBytes.
  for (ShRgb& s : deringed) s = quantizeSh(s);
  std::vector<uint8_t> flags = grid.invalid();
  // Rebuilding with the windowed SH: dilation copies valid nodes, so the invalid ones are overwritten with
  // the same windowed values their source now holds.
  grid = GridVolume(layout, std::move(deringed), std::move(flags));
  local.nodes = layout.nodes();
  local.invalidNodes = grid.invalidNodes();
  local.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  if (stats) *stats = local;
  return grid;
}

std::vector<std::pair<std::string, std::string>> generatorFields(const std::string& generator) {
  std::vector<std::pair<std::string, std::string>> out;
  // The "key=value; " form never holds an option ("--name"); a ';' in the option list's values does not
  // make it one.
  const bool items = generator.find(';') != std::string::npos && generator.find(" --") == std::string::npos;
  std::istringstream in(generator);
  std::string item;
  while (items ? static_cast<bool>(std::getline(in, item, ';')) : static_cast<bool>(in >> item)) {
    const size_t eq = item.find('=');
    if (eq == std::string::npos) continue;
    std::string key = item.substr(0, eq);
    key.erase(0, key.find_first_not_of(' '));
    key.erase(key.find_last_not_of(' ') + 1);
    out.emplace_back(std::move(key), item.substr(eq + 1));
  }
  return out;
}

}  // namespace tetraprobe
