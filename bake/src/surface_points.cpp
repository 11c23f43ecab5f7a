// Random surface points for the evaluation: area-weighted triangle choice, uniform point in the triangle,
// and the side that faces open space, found by a small back-face ray test on each side (the Unity APV 25 %
// rule applied to a hemisphere; rays into the void below the level count as closed). Points enclosed on both sides, and points in alpha-cutout holes, are redrawn,
// within a bounded number of draws. The side test counts only opaque surfaces (a glass pane encloses
// nothing).
// References: Osada et al. 2002 ("Shape distributions", uniform triangle sampling); Unity APV docs.
#include <algorithm>
#include <limits>

#include <glm/geometric.hpp>

#include "rng.h"
#include "sampling.h"
#include "tetraprobe/bake/bake.h"
#include "tracer_impl.h"

namespace tetraprobe {

using namespace bake_detail;

namespace {

constexpr int kSideRays = 32;
constexpr double kSideBackFaceFraction = 0.25;
constexpr int kMaxDrawsPerPoint = 20;
// Under a sky, an escaping ray counts as closed when it leaves below the horizon (direction y < 0): there is
// no ground below it to stand on. Rays that pass the edge of a finite ground at a grazing angle escape too,
// so an overhang within about three heights of that edge may be judged outside (as under a black sky). A
// threshold of 30 degrees below the horizon keeps such overhangs, but it keeps more of a level's outside too:
// q3 dm4ish baked with it was no better than before at area points, baked with this one a sixth better
// (docs/evaluation.md#surface-points-and-the-void-below-a-level).
constexpr float kVoidBelowY = 0.0f;

// True when at most 25 % of kSideRays hemisphere rays from `origin` about `n` meet back faces. Under a black
// sky an escaping ray counts as closed too: the level is then an interior and a side that sees the void is
// its outside (the exterior face of a single-sided wall, a slab face coplanar with the ceiling), where no
// viewer stands and the reference is zero. Under any sky a ray that escapes below the horizon (kVoidBelowY)
// does too: the void under a level is its outside (the underside of a ground plane, which sees the sky below
// the horizon and is bright in the reference, and the outer walls of a level standing in the void, which
// no viewer on its ground ever sees).
bool sideIsOpen(const SceneTracer& tracer, const glm::vec3& origin, const glm::vec3& n, bool blackSky,
                Rng& rng) {
  int back = 0;
  for (int k = 0; k < kSideRays; ++k) {
    // Stratified in the first coordinate (cos theta) so 32 rays cover the hemisphere evenly.
    const float u1 = (float(k) + rng.uniform()) / float(kSideRays), u2 = rng.uniform();
    const glm::vec3 d = uniformHemisphere(n, u1, u2);
    const Hit hit = tracer.intersect(origin, d, 0.0f, std::numeric_limits<float>::infinity(), 0.0f);
    if ((hit.hit && !hit.frontFace) || (!hit.hit && (blackSky || d.y < kVoidBelowY))) ++back;
  }
  return double(back) <= kSideBackFaceFraction * kSideRays;
}

}  // namespace

std::vector<SurfacePoint> sampleSurfacePoints(const SceneTracer& tracer, int count, uint64_t seed) {
  std::vector<SurfacePoint> points;
  const SceneTracer::Impl& impl = tracer.impl();
  if (count < 1 || !(impl.totalArea > 0.0)) return points;
  DenormalScope denormals;
  points.reserve(size_t(count));
  const float eps = impl.rayEpsilon;
  const Scene& scene = tracer.scene();
  const bool blackSky = scene.skyRadiance == glm::vec3(0.0f) &&
                        (!scene.hasSkyGradient() || scene.skyHorizonRadiance == glm::vec3(0.0f));
  const int64_t maxDraws = int64_t(kMaxDrawsPerPoint) * count;
  for (int64_t draw = 0; draw < maxDraws && int(points.size()) < count; ++draw) {
    Rng rng(streamKey(seed, uint64_t(draw)));
    const double u = rng.uniformDouble() * impl.totalArea;
    const size_t tri =
        std::min(size_t(std::upper_bound(impl.areaCdf.begin(), impl.areaCdf.end(), u) - impl.areaCdf.begin()),
                 impl.areaCdf.size() - 1);
    if (!(impl.areas[tri] > 0.0f)) continue;
    const float u1 = rng.uniform(), u2 = rng.uniform();
    const glm::vec2 b = uniformTriangle(u1, u2);
    if (tracer.isHole(uint32_t(tri), b.x, b.y)) continue;  // no surface there
    const glm::vec3 p = impl.pointOn(uint32_t(tri), b.x, b.y);
    const glm::vec3 front = impl.normals[tri];
    glm::vec3 n(0.0f);
    if (sideIsOpen(tracer, p + front * eps, front, blackSky, rng))
      n = front;
    else if (sideIsOpen(tracer, p - front * eps, -front, blackSky, rng))
      n = -front;
    else
      continue;
    SurfacePoint sp;
    sp.position = glm::dvec3(p);
    sp.normal = n;
    sp.albedo = impl.material(uint32_t(tri)).albedo;
    sp.triangle = uint32_t(tri);
    points.push_back(sp);
  }
  return points;
}

}  // namespace tetraprobe
