// A thread-safe progress bar with rate and ETA on stderr, shown only when stderr is a terminal (CI logs stay
// clean). Cheap to advance from many threads.
#pragma once

#include <atomic>
#include <chrono>
#include <cstdint>
#include <mutex>
#include <string>

namespace tetraprobe {

class Progress {
 public:
  // `label` names the work ("bake", "reference"); `total` counts its units; `unit` names them ("probes").
  Progress(std::string label, uint64_t total, std::string unit);
  ~Progress();  // finishes the line
  void advance(uint64_t n = 1);
  void finish();

  static bool enabled();  // stderr is a terminal and TETRAPROBE_NO_PROGRESS is unset

 private:
  void draw(uint64_t done, bool final);
  std::string label_, unit_;
  uint64_t total_;
  std::atomic<uint64_t> done_{0};
  std::atomic<int64_t> lastDrawNs_{0};
  std::chrono::steady_clock::time_point start_;
  std::mutex drawMutex_;
  bool enabled_;
  bool finished_ = false;
};

}  // namespace tetraprobe
