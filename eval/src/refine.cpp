// Error-driven probe refinement (refine.h): the bake measures its own interpolation error against the
// unbiased oracle at area-uniform surface points and puts probes in front of the worst ones. Regular grids
// and voxel placement spend probes uniformly; this spends them where the light changes faster than the
// probes resolve it (corners, contact shadows, door gaps) or where occlusion data approximates badly.
#include "tetraprobe/eval/refine.h"

#include <algorithm>
#include <cmath>
#include <numeric>

#include <glm/geometric.hpp>

#include "tetraprobe/common/splitmix.h"
#include "tetraprobe/occlusion/occlusion_holes.h"
#include "tetraprobe/runtime/luminance.h"
#include "tetraprobe/runtime/query.h"

namespace tetraprobe {

namespace {

constexpr double kFloor = 0.01;  // W/m^2, as eval

}  // namespace

std::vector<RefinePoint> refinePoints(const SceneTracer& tracer, const RefineOptions& options) {
  const std::vector<SurfacePoint> surface = sampleSurfacePoints(tracer, options.points, options.seed);
  std::vector<RefinePoint> out(surface.size());
  ReferenceBatch batch;
  batch.options.bounces = kUnboundedBounces;
  batch.options.content = options.content;
  batch.options.progress = options.progress;
  batch.options.farm = options.farm;
  batch.samples = options.samplesPerPoint;
  batch.items.resize(surface.size());
  for (size_t i = 0; i < surface.size(); ++i)
    batch.items[i] = {surface[i].position, surface[i].normal, splitmix64(options.seed ^ splitmix64(i)), {}};
  traceReferences(tracer, batch, options.threads, "refine (oracle)");
  for (size_t i = 0; i < surface.size(); ++i) {
    out[i].surface = surface[i];
    out[i].reference = batch.items[i].result;
  }
  return out;
}

ErrorEstimate scoreRefinePoints(const Level& level, std::vector<RefinePoint>& points) {
  ErrorEstimate est;
  est.points = points.size();
  if (points.empty() || level.tets.empty()) return est;
  const ProbeQuery query(level, kStoredCellGridOnly);  // a level being built may have no grid yet
  double sum = 0.0;
  size_t gross = 0;
  for (RefinePoint& p : points) {
    const glm::vec3 x = query.irradiance(p.surface.position, p.surface.normal);
    const double lx = luminance(glm::dvec3(x)), lr = luminance(glm::dvec3(p.reference.irradiance));
    const double noise = 3.0 * luminance(glm::dvec3(p.reference.stderror));
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
                                          double spacing, double minError, double maxOffset) {
  if (budget == 0 || !(spacing > 0.0)) return {};
  std::vector<size_t> order(points.size());
  std::iota(order.begin(), order.end(), size_t(0));
  std::stable_sort(order.begin(), order.end(),
                   [&](size_t a, size_t b) { return points[a].error > points[b].error; });
  ProbesInFront proposals(tracer, level, spacing,
                          maxOffset > 0.0 ? maxOffset : spacing * kRefineOffsetFraction);
  FlushDenormalsScope ftz;
  for (size_t k : order) {
    if (proposals.probes().size() >= budget || !(points[k].error > minError)) break;
    proposals.propose(points[k].surface.position, points[k].surface.normal);
  }
  return proposals.probes();
}

}  // namespace tetraprobe
