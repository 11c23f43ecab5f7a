// Occlusion holes (occlusion_holes.h): where the stored per-tet occlusion leaves a surface point no visible
// probe, the lookup's only answer is a fallback. Rather than guess at run time, the bake puts a probe where
// the point can see it: in front of the surface, at most half a spacing out and half the free distance
// along the normal, so it stays on the point's side of any nearby geometry. The next tetrahedralization then
// gives the point a tet with a visible vertex; the pipeline repeats this a few rounds.
#include "tetraprobe/occlusion/occlusion_holes.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>
#include <string>
#include <unordered_map>
#include <unordered_set>

#include <glm/geometric.hpp>

#include "tetraprobe/bake/bake.h"
#include "tetraprobe/common/error.h"
#include "tetraprobe/occlusion/build_occlusion.h"
#include "tetraprobe/runtime/query.h"
#include "tetraprobe/runtime/shade.h"
#include "tetraprobe/scene/scene.h"

namespace tetraprobe {

namespace {

struct CellHash {
  size_t operator()(const glm::i64vec3& c) const {
    uint64_t h = uint64_t(c.x) * 0x9e3779b97f4a7c15ull;
    h ^= uint64_t(c.y) * 0xc2b2ae3d27d4eb4full + (h << 6) + (h >> 2);
    h ^= uint64_t(c.z) * 0x165667b19e3779f9ull + (h << 6) + (h >> 2);
    return size_t(h);
  }
};

glm::i64vec3 cellOf(const glm::dvec3& p, double size) {
  return glm::i64vec3(glm::floor(p / size));
}

// Points within `radius` of each other, on a grid of cell `radius`.
class NearGrid {
 public:
  explicit NearGrid(double radius) : r_(radius) {}
  void add(const glm::dvec3& p) { cells_[cellOf(p, r_)].push_back(p); }
  bool near(const glm::dvec3& p) const {
    const glm::i64vec3 c = cellOf(p, r_);
    for (int dz = -1; dz <= 1; ++dz)
      for (int dy = -1; dy <= 1; ++dy)
        for (int dx = -1; dx <= 1; ++dx) {
          const auto it = cells_.find(c + glm::i64vec3(dx, dy, dz));
          if (it == cells_.end()) continue;
          for (const glm::dvec3& q : it->second)
            if (glm::length(q - p) < r_) return true;
        }
    return false;
  }

 private:
  double r_;
  std::unordered_map<glm::i64vec3, std::vector<glm::dvec3>, CellHash> cells_;
};

}  // namespace

struct ProbesInFront::Grids {
  explicit Grids(double r) : near(r) {}
  NearGrid near;
  std::unordered_set<glm::i64vec3, CellHash> taken;
};

ProbesInFront::ProbesInFront(const SceneTracer& tracer, const Level& level, double spacing, double maxOffset)
    : tracer_(tracer),
      spacing_(spacing),
      maxOffset_(maxOffset > 0.0 ? maxOffset : spacing / 2.0),
      grids_(std::make_unique<Grids>(spacing / 10.0)) {
  for (const glm::vec3& p : level.probes) grids_->near.add(glm::dvec3(p) + level.origin);
}

ProbesInFront::~ProbesInFront() = default;

bool ProbesInFront::propose(const glm::dvec3& point, const glm::vec3& normal) {
  const glm::vec3 n = glm::normalize(normal);
  const Hit hit = tracer_.intersect(glm::vec3(point) + n * tracer_.rayEpsilon(), n, 0.0f,
                                    std::numeric_limits<float>::infinity());
  const double free = hit.hit ? double(hit.t) : std::numeric_limits<double>::infinity();
  const double d = std::min(maxOffset_, free / 2.0);
  if (d < spacing_ / 50.0) return false;
  const glm::dvec3 probe = point + glm::dvec3(n) * d;
  if (!grids_->taken.insert(cellOf(probe, spacing_ / 2.0)).second) return false;
  if (grids_->near.near(probe)) return false;
  grids_->near.add(probe);
  probes_.push_back(probe);
  return true;
}

namespace {

// Whether the fallback at a point (its shading record, ProbeQuery::explain) answers with the light of a probe
// the point sees: the probe it leans on (record.fallbackProbe, as occludedIrradiance weighs them) lies in
// front, a ray reaches it, and the unoccluded blend capping the fallback is not darker in any channel.
bool fallbackProbeSeen(const SceneTracer& tracer, const Level& level, const ShadeRecord& record,
                       const glm::dvec3& point, const glm::vec3& normal) {
  const Location& loc = record.location;
  if (loc.tet < 0) return false;
  const int best = record.fallbackProbe;
  if (!(record.front[best] > 0.5f)) return false;
  // The fallback is min(that probe, the unoccluded blend) per channel: where the blend (which may hold probes
  // behind a wall) is the darker, the answer is not the seen probe's light.
  const glm::vec3 own = record.probeIrradiance[best], blend = record.unoccludedIrradiance;
  if (!(own.x <= blend.x && own.y <= blend.y && own.z <= blend.z)) return false;
  const int32_t probe = level.tets[size_t(loc.tet)].v[best];
  const glm::vec3 n = glm::normalize(normal);
  const glm::vec3 origin = glm::vec3(point) + n * tracer.rayEpsilon();
  const glm::vec3 d = glm::vec3(glm::dvec3(level.probes[size_t(probe)]) + level.origin) - origin;
  const float dist = glm::length(d);
  return dist > 0.0f && !tracer.occluded(origin, d / dist, 0.0f, dist, kOcclusionWallTransmission);
}

}  // namespace

float occlusionFallbackShare(const Level& level, const ProbeQuery& query, const glm::dvec3& point,
                             const glm::vec3& normal) {
  if (level.occlusion.empty()) return 0.0f;
  ShadeRecord record;
  query.explain(point, normal, record);
  return record.ownFallback;
}

OcclusionHoles findOcclusionHoles(const SceneTracer& tracer, const Level& level,
                                  const OcclusionHoleOptions& options) {
  if (!(options.spacing > 0.0) || !std::isfinite(options.spacing))
    throw InputError("occlusion holes: spacing must be positive and finite");
  OcclusionHoles out;
  if (level.occlusion.empty() || level.tets.empty()) return out;
  const double density = options.pointsPerSquareMetre / (options.spacing * options.spacing);
  const int maxPoints = options.maxPoints > 0 ? std::min(options.maxPoints, kMaxHolePoints) : kMaxHolePoints;
  const double wanted = std::clamp(surfaceArea(tracer.scene()) * density, double(options.minPoints),
                                   double(std::max(options.minPoints, maxPoints)));
  const std::vector<SurfacePoint> points = sampleSurfacePoints(tracer, int(wanted), options.seed);
  out.pointsChecked = points.size();

  const ProbeQuery query(level, kStoredCellGridOnly);  // a level being built may have no grid yet
  std::optional<ProbesInFront> proposals;
  if (options.propose) proposals.emplace(tracer, level, options.spacing, options.maxOffset);
  FlushDenormalsScope ftz;
  ShadeRecord record;
  for (const SurfacePoint& sp : points) {
    // The tet's own data decides a hole; the lookup's answer (after the face blend) is counted apart.
    query.explain(sp.position, sp.normal, record);
    out.lookupFallbackPoints += record.fallback > 0.0f;
    if (options.keepLookupFallbacks && record.fallback > 0.0f) out.lookupFallbacks.push_back(sp);
    if (!((options.lookupOnly ? record.fallback : record.ownFallback) > 0.0f)) continue;
    ++out.holePoints;
    if (options.onlyUnseen && fallbackProbeSeen(tracer, level, record, sp.position, sp.normal)) {
      ++out.seenPoints;
      continue;
    }
    if (proposals) proposals->propose(sp.position, sp.normal);
  }
  if (proposals) out.probes = proposals->probes();
  return out;
}

}  // namespace tetraprobe
