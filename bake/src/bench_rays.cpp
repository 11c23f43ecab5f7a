// Ray recording and bare-Embree replay for `tetraprobe bench bake` and bench/bench_bake.cpp: the rays a
// probe bake traces are captured through the per-thread RayTap (ray_tap.h) and traced again with nothing but
// rtcIntersect1 / rtcOccluded1, so the two rates compare the same work.
// References: Embree 3 API manual (rtcIntersect1, rtcOccluded1, rtcInitIntersectContext).
#include "tetraprobe/bake/bench_rays.h"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <string>

#include <embree3/rtcore.h>

#include "probe_bake.h"
#include "ray_tap.h"
#include "tetraprobe/common/error.h"
#include "tetraprobe/common/parallel.h"
#include "tracer_impl.h"

namespace tetraprobe {

namespace {

constexpr size_t kReplayBlock = 1024;  // consecutive rays per work item (one probe's paths stay together)

// Traces rays [begin, end) and returns how many answers differ from the recorded ones.
uint64_t traceBlock(RTCScene scene, const RecordedRay* rays, size_t begin, size_t end) {
  uint64_t mismatches = 0;
  for (size_t i = begin; i < end; ++i) {
    const RecordedRay& r = rays[i];
    RTCIntersectContext context;
    rtcInitIntersectContext(&context);
    if (r.occluded) {
      RTCRay ray;
      ray.org_x = r.origin.x;
      ray.org_y = r.origin.y;
      ray.org_z = r.origin.z;
      ray.tnear = r.tnear;
      ray.dir_x = r.dir.x;
      ray.dir_y = r.dir.y;
      ray.dir_z = r.dir.z;
      ray.time = 0.0f;
      ray.tfar = r.tfar;
      ray.mask = ~0u;
      ray.id = 0;
      ray.flags = 0;
      rtcOccluded1(scene, &context, &ray);
      mismatches += uint32_t(ray.tfar < 0.0f) != r.hit;
    } else {
      RTCRayHit rh;
      rh.ray.org_x = r.origin.x;
      rh.ray.org_y = r.origin.y;
      rh.ray.org_z = r.origin.z;
      rh.ray.tnear = r.tnear;
      rh.ray.dir_x = r.dir.x;
      rh.ray.dir_y = r.dir.y;
      rh.ray.dir_z = r.dir.z;
      rh.ray.time = 0.0f;
      rh.ray.tfar = r.tfar;
      rh.ray.mask = ~0u;
      rh.ray.id = 0;
      rh.ray.flags = 0;
      rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
      rh.hit.primID = RTC_INVALID_GEOMETRY_ID;
      rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
      rtcIntersect1(scene, &context, &rh);
      mismatches += uint32_t(rh.hit.geomID != RTC_INVALID_GEOMETRY_ID) != r.hit;
    }
  }
  return mismatches;
}

}  // namespace

std::vector<RecordedRay> recordBakeRays(const SceneTracer& tracer, const std::vector<glm::dvec3>& probes,
                                        const std::vector<size_t>& indices, const BakeOptions& options) {
  if (probes.size() != indices.size())
    throw InputError("recordBakeRays: " + std::to_string(probes.size()) + " probes but " +
                     std::to_string(indices.size()) + " indices");
  bake_detail::validateBakeOptions(options);
  std::vector<RecordedRay> rays;
  bake_detail::RayTap tap;
  tap.record = &rays;
  bake_detail::RayTapScope scope(tap);
  for (size_t k = 0; k < probes.size(); ++k) {
    const glm::dvec3 p = probes[k];
    if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z))
      throw InputError("recordBakeRays: probe " + std::to_string(k) + " has a non-finite position");
    bake_detail::bakeProbe(tracer, glm::vec3(p), indices[k], options);
  }
  return rays;
}

ReplayResult replayRays(const SceneTracer& tracer, const std::vector<RecordedRay>& rays, int threads,
                        double minSeconds) {
  ReplayResult result;
  if (rays.empty()) return result;
  const RTCScene scene = tracer.impl().rtcScene;
  const size_t blocks = (rays.size() + kReplayBlock - 1) / kReplayBlock;
  const auto t0 = std::chrono::steady_clock::now();
  do {
    std::atomic<uint64_t> mismatches{0};
    parallelFor(blocks, threads, [&](size_t b) {
      bake_detail::DenormalScope denormals;
      const size_t begin = b * kReplayBlock, end = std::min(rays.size(), begin + kReplayBlock);
      const uint64_t m = traceBlock(scene, rays.data(), begin, end);
      if (m) mismatches.fetch_add(m, std::memory_order_relaxed);
    });
    result.rays += rays.size();
    result.mismatches += mismatches.load();
    result.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  } while (result.seconds < minSeconds);
  return result;
}

}  // namespace tetraprobe
