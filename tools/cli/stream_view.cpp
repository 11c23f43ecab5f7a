// `render --stream-window N` (stream_view.h).
#include "stream_view.h"

#include <algorithm>
#include <cstring>
#include <utility>
#include <vector>

#include <glm/geometric.hpp>

#include "tetraprobe/common/error.h"

namespace tetraprobe::cli {

std::unique_ptr<StreamView> openStreamView(const std::string& path, size_t window, const glm::dvec3& target) {
  auto v = std::make_unique<StreamView>();
  if (LevelResult r = v->level.open(path); !r)
    throw InputError(r.message +
                     " (--stream-window needs a level with a streaming index: tetraprobe stream)");
  std::vector<GpuSectorSizes> sizes;
  std::string error;
  if (!measureSectors(v->level, sizes, &error)) throw InputError(error);
  v->window = std::min(window, sizes.size());
  if (std::string e = v->pool.init(v->level, gpuPoolCapacityFor(sizes, uint32_t(v->window))); !e.empty())
    throw InputError(e);
  const CellGrid& g = v->level.sectorGrid();
  const glm::dvec3 local = target - v->level.origin();
  std::vector<std::pair<double, SectorKey>> byDistance;
  for (const SectorKey& k : v->level.sectors()) {
    const glm::dvec3 d = glm::dvec3(g.min) + (glm::dvec3(k.x, k.y, k.z) + 0.5) * double(g.cellSize) - local;
    byDistance.emplace_back(glm::dot(d, d), k);
  }
  std::sort(byDistance.begin(), byDistance.end());
  for (size_t i = 0; i < v->window; ++i) {
    if (LevelResult r = v->pool.load(byDistance[i].second); !r) throw InputError(r.message);
  }
  return v;
}

StreamViewPixels compareStreamView(const StreamView& view, const glm::dvec3& origin, const RenderResult& full,
                                   const RenderResult& streamed) {
  StreamViewPixels n;
  const std::vector<float>& pos = full.position.rgba;
  for (size_t i = 0; i + 3 < pos.size(); i += 4) {
    if (pos[i + 3] == 0.0f) continue;
    const glm::dvec3 p = origin + glm::dvec3(pos[i], pos[i + 1], pos[i + 2]);
    if (!view.pool.answersFromLoaded(p)) {
      ++n.coarse;
      continue;
    }
    ++n.loaded;
    n.identical += std::memcmp(&full.color.rgba[i], &streamed.color.rgba[i], 3 * sizeof(float)) == 0;
  }
  return n;
}

}  // namespace tetraprobe::cli
