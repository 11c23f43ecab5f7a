// Measuring the baker against bare Embree: record the rays the probe bake traces, then replay them with
// plain rtcIntersect1 / rtcOccluded1 on the same scene. The ratio of the two rates is the share of Embree's
// throughput the baker keeps (the rest is shading, sampling, RNG and SH projection). Build side.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include <glm/vec3.hpp>

#include "tetraprobe/bake/bake.h"
#include "tetraprobe/bake/tracer.h"

namespace tetraprobe {

// One ray as the baker traced it (world metres; `dir` unit; segment [tnear, tfar], tfar may be +inf).
struct RecordedRay {
  glm::vec3 origin{0.0f};
  float tnear = 0.0f;
  glm::vec3 dir{0.0f};
  float tfar = 0.0f;
  uint32_t occluded = 0;  // 0: closest hit (rtcIntersect1), 1: any hit (rtcOccluded1)
  uint32_t hit = 0;       // the answer the baker got (1: hit / blocked)
};
static_assert(sizeof(RecordedRay) == 40, "RecordedRay is 10 packed 4-byte fields");

// Bakes the probes `probes[k]` with bake indices `indices[k]` (the index keys each probe's random streams,
// as in bakeProbes) single-threaded and returns every ray traced, in order, probe after probe. The SH
// results are discarded. Allocates about 40 bytes a ray (samplesPerProbe x path length x (1 + shadow rays)
// per probe). Throws InputError for mismatched sizes or bad options (as bakeProbes).
std::vector<RecordedRay> recordBakeRays(const SceneTracer& tracer, const std::vector<glm::dvec3>& probes,
                                        const std::vector<size_t>& indices, const BakeOptions& options);

struct ReplayResult {
  uint64_t rays = 0;        // rays traced (all passes)
  uint64_t mismatches = 0;  // replayed answers that differ from the recorded ones (expected 0)
  double seconds = 0.0;     // wall time of the passes
  double raysPerSecond() const { return seconds > 0.0 ? double(rays) / seconds : 0.0; }
};

// Traces `rays` with bare rtcIntersect1 / rtcOccluded1 (a fresh RTCIntersectContext per ray, as the tracer
// does) on `threads` threads (0 = all cores) in blocks of consecutive rays, repeating whole passes until at
// least `minSeconds` have elapsed (at least one pass). Enters a FlushDenormalsScope on every thread.
ReplayResult replayRays(const SceneTracer& tracer, const std::vector<RecordedRay>& rays, int threads,
                        double minSeconds = 0.5);

}  // namespace tetraprobe
