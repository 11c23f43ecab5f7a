// Chunked parallel loop over std::thread with exception forwarding.
#include "tetraprobe/common/parallel.h"

#include <algorithm>
#include <atomic>
#include <exception>
#include <mutex>
#include <thread>
#include <vector>

namespace tetraprobe {

int resolveThreads(int threads) {
  if (threads > 0) return threads;
  return std::max(1u, std::thread::hardware_concurrency());
}

void parallelFor(size_t count, int threads, const std::function<void(size_t)>& fn, size_t chunk) {
  if (count == 0) return;
  chunk = std::max<size_t>(1, chunk);
  const int n = int(std::min<size_t>(size_t(resolveThreads(threads)), (count + chunk - 1) / chunk));
  std::atomic<size_t> next{0};
  std::atomic<bool> stop{false};
  std::exception_ptr first;
  std::mutex errMutex;
  auto worker = [&] {
    while (!stop.load(std::memory_order_relaxed)) {
      const size_t begin = next.fetch_add(chunk);
      if (begin >= count) break;
      const size_t end = std::min(count, begin + chunk);
      try {
        for (size_t i = begin; i < end; ++i) fn(i);
      } catch (...) {
        std::lock_guard<std::mutex> lock(errMutex);
        if (!first) first = std::current_exception();
        stop = true;
      }
    }
  };
  if (n <= 1) {
    worker();
  } else {
    std::vector<std::thread> pool;
    for (int t = 0; t < n; ++t) pool.emplace_back(worker);
    for (auto& t : pool) t.join();
  }
  if (first) std::rethrow_exception(first);
}

}  // namespace tetraprobe
