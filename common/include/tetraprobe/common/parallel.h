// parallelFor: runs fn(i) for i in [0, count) on up to `threads` std::threads (0 = hardware concurrency).
// Work is handed out in chunks through an atomic counter; callers keep results deterministic by writing to
// out[i] and seeding randomness per item, never per thread. The first exception thrown by fn is rethrown
// on the calling thread after all workers stop.
#pragma once

#include <cstddef>
#include <functional>

namespace tetraprobe {

int resolveThreads(int threads);  // 0 -> hardware concurrency (at least 1)

void parallelFor(size_t count, int threads, const std::function<void(size_t)>& fn, size_t chunk = 1);

}  // namespace tetraprobe
