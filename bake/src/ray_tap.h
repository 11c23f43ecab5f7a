// Per-thread ray accounting for the bake: SceneTracer::intersect/occluded report every ray to the calling
// thread's current RayTap, if any (one thread-local pointer load and a branch per ray when none is set).
// Work items install a tap around their own work, so counts are per item and the sums are deterministic for
// any thread count. A tap may also record the rays (origin, direction, segment, query kind) for replay by
// bench_rays.cpp. Internal to the bake module.
#pragma once

#include <cstdint>
#include <vector>

#include "tetraprobe/bake/bench_rays.h"

namespace tetraprobe::bake_detail {

struct RayTap {
  uint64_t intersects = 0;
  uint64_t occludeds = 0;
  std::vector<RecordedRay>* record = nullptr;  // when set, every ray is appended
};

// The calling thread's tap (nullptr: nothing is counted).
inline thread_local RayTap* tCurrentRayTap = nullptr;
inline RayTap*& currentRayTap() {
  return tCurrentRayTap;
}

// Installs `tap` on this thread for the scope's lifetime and restores the previous one after.
class RayTapScope {
 public:
  explicit RayTapScope(RayTap& tap) : saved_(currentRayTap()) { currentRayTap() = &tap; }
  ~RayTapScope() { currentRayTap() = saved_; }
  RayTapScope(const RayTapScope&) = delete;
  RayTapScope& operator=(const RayTapScope&) = delete;

 private:
  RayTap* saved_;
};

}  // namespace tetraprobe::bake_detail
