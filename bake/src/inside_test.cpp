// Inside-geometry test for probes: a point is inside when more than a fraction of rays cast uniformly over
// the sphere meet back faces (the Unity Adaptive Probe Volumes validity rule, 25 %). Rays that escape count
// as not back-face. Directions are a spherical Fibonacci set under a per-point random rotation. Only opaque
// surfaces count: a transmissive pane is a thin film that encloses nothing, and cutout holes are open.
// References: Unity APV documentation ("probe validity"); Marques et al. 2013 (spherical Fibonacci).
#include <limits>

#include "rng.h"
#include "sampling.h"
#include "tetraprobe/bake/bake.h"
#include "tetraprobe/common/parallel.h"
#include "tracer_impl.h"

namespace tetraprobe {

using namespace bake_detail;

namespace {

constexpr uint64_t kInsideSalt = 0x1e51dec0ffeeull;

bool insideOne(const SceneTracer& tracer, const glm::vec3& p, size_t index, int rays,
               double backFaceFraction) {
  DenormalScope denormals;
  Rng rng(streamKey(kInsideSalt, index));
  const double u1 = rng.uniformDouble(), u2 = rng.uniformDouble(), u3 = rng.uniformDouble();
  const glm::dmat3 rotation = randomRotation(u1, u2, u3);
  int back = 0;
  for (int k = 0; k < rays; ++k) {
    const glm::vec3 d = glm::vec3(glm::normalize(rotation * sphericalFibonacci(k, rays)));
    const Hit hit = tracer.intersect(p, d, 0.0f, std::numeric_limits<float>::infinity(), 0.0f);
    if (hit.hit && !hit.frontFace) ++back;
  }
  return double(back) > backFaceFraction * double(rays);
}

}  // namespace

std::vector<uint8_t> probesInsideGeometry(const SceneTracer& tracer, const std::vector<glm::dvec3>& points,
                                          int rays, double backFaceFraction, int threads) {
  std::vector<uint8_t> inside(points.size(), 0);
  if (rays < 1) return inside;
  parallelFor(
      points.size(), threads,
      [&](size_t i) {
        inside[i] = insideOne(tracer, glm::vec3(points[i]), i, rays, backFaceFraction) ? 1 : 0;
      },
      64);
  return inside;
}

}  // namespace tetraprobe
