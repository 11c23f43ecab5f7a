// Error-driven probe refinement (refine.h): the bake measures its own interpolation error against the
// unbiased oracle at area-uniform surface points and puts probes in front of the worst ones. Regular grids
// and voxel placement spend probes uniformly; this spends them where the light changes faster than the
// probes resolve it (corners, contact shadows, door gaps) or where occlusion data approximates badly.
#include "tetraprobe/eval/refine.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <unordered_map>
#include <unordered_set>

#include <glm/geometric.hpp>

#include "tetraprobe/common/parallel.h"
#include "tetraprobe/runtime/query.h"

namespace tetraprobe {

namespace {

constexpr double kFloor = 0.01;  // W/m^2, as eval

double luminance(const glm::vec3& c) {
  return 0.2126 * c.r + 0.7152 * c.g + 0.0722 * c.b;
}

uint64_t mix(uint64_t x) {
  x += 0x9e3779b97f4a7c15ull;
  x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ull;
  x = (x ^ (x >> 27)) * 0x94d049bb133111ebull;
  return x ^ (x >> 31);
}

struct CellHash {
  size_t operator()(const glm::i64vec3& c) const {
    return size_t(mix(uint64_t(c.x) ^ mix(uint64_t(c.y) ^ mix(uint64_t(c.z)))));
  }
};

glm::i64vec3 cellOf(const glm::dvec3& p, double size) {
  return glm::i64vec3(glm::floor(p / size));
}

}  // namespace

std::vector<RefinePoint> refinePoints(const SceneTracer& tracer, const RefineOptions& options) {
  const std::vector<SurfacePoint> surface = sampleSurfacePoints(tracer, options.points, options.seed);
  std::vector<RefinePoint> out(surface.size());
  BakeOptions bake;
  bake.bounces = kUnboundedBounces;
  bake.content = options.content;
  bake.progress = false;
  parallelFor(surface.size(), options.threads, [&](size_t i) {
    out[i].surface = surface[i];
    out[i].reference = referenceIrradiance(tracer, surface[i].position, surface[i].normal,
                                           options.samplesPerPoint, mix(options.seed ^ mix(i)), bake);
  });
  return out;
}

ErrorEstimate scoreRefinePoints(const Level& level, std::vector<RefinePoint>& points) {
  ErrorEstimate est;
  est.points = points.size();
  if (points.empty() || level.tets.empty()) return est;
  const ProbeQuery query(level);
  double sum = 0.0;
  size_t gross = 0;
  for (RefinePoint& p : points) {
    const glm::vec3 x = query.irradiance(p.surface.position, p.surface.normal);
    const double lx = luminance(x), lr = luminance(p.reference.irradiance);
    const double noise = 3.0 * luminance(p.reference.stderror);
    p.error =
        std::abs(lx - lr) <= noise ? 0.0 : std::abs(std::log2(std::max(lx, kFloor) / std::max(lr, kFloor)));
    sum += p.error;
    gross += p.error > 1.0 ? 1 : 0;
  }
  est.meanLogError = sum / double(points.size());
  est.gross = double(gross) / double(points.size());
  return est;
}

std::vector<glm::dvec3> proposeRefinement(const SceneTracer& tracer, const Level& level,
                                          const std::vector<RefinePoint>& points, size_t budget,
                                          double spacing, double minError) {
  std::vector<glm::dvec3> out;
  if (budget == 0 || !(spacing > 0.0)) return out;
  std::vector<size_t> order(points.size());
  std::iota(order.begin(), order.end(), size_t(0));
  std::stable_sort(order.begin(), order.end(),
                   [&](size_t a, size_t b) { return points[a].error > points[b].error; });
  // Existing probes within spacing / 10 (the placement's merge distance) of a proposal rule it out.
  const double nearR = spacing / 10.0;
  std::unordered_set<glm::i64vec3, CellHash> occupied, taken;
  std::vector<glm::dvec3> all;
  for (const glm::vec3& p : level.probes) all.push_back(glm::dvec3(p) + level.origin);
  std::unordered_multimap<glm::i64vec3, size_t, CellHash> grid;
  for (size_t i = 0; i < all.size(); ++i) grid.emplace(cellOf(all[i], nearR), i);
  auto nearExisting = [&](const glm::dvec3& q) {
    const glm::i64vec3 c = cellOf(q, nearR);
    for (int dz = -1; dz <= 1; ++dz)
      for (int dy = -1; dy <= 1; ++dy)
        for (int dx = -1; dx <= 1; ++dx) {
          auto [b, e] = grid.equal_range(c + glm::i64vec3(dx, dy, dz));
          for (auto it = b; it != e; ++it)
            if (glm::length(all[it->second] - q) < nearR) return true;
        }
    return false;
  };
  const float eps = tracer.rayEpsilon();
  FlushDenormalsScope ftz;
  for (size_t k : order) {
    if (out.size() >= budget) break;
    const RefinePoint& p = points[k];
    if (!(p.error > minError)) break;
    const glm::vec3 n = glm::normalize(p.surface.normal);
    const Hit hit = tracer.intersect(glm::vec3(p.surface.position) + n * eps, n, 0.0f,
                                     std::numeric_limits<float>::infinity());
    const double free = hit.hit ? double(hit.t) : std::numeric_limits<double>::infinity();
    const double d = std::min(spacing / 2.0, free / 2.0);
    if (d < spacing / 50.0) continue;
    const glm::dvec3 q = p.surface.position + glm::dvec3(n) * d;
    if (!taken.insert(cellOf(q, spacing / 2.0)).second || nearExisting(q)) continue;
    grid.emplace(cellOf(q, nearR), all.size());
    all.push_back(q);
    out.push_back(q);
  }
  return out;
}

}  // namespace tetraprobe
