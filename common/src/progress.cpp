// Terminal progress bar: label, bar, count, rate and ETA, redrawn at most 10 times a second.
#include "tetraprobe/common/progress.h"

#include <unistd.h>

#include <cstdio>
#include <cstdlib>

namespace tetraprobe {

bool Progress::enabled() {
  return ::isatty(STDERR_FILENO) && std::getenv("TETRAPROBE_NO_PROGRESS") == nullptr;
}

Progress::Progress(std::string label, uint64_t total, std::string unit)
    : label_(std::move(label)),
      unit_(std::move(unit)),
      total_(total),
      start_(std::chrono::steady_clock::now()),
      enabled_(enabled()) {}

Progress::~Progress() {
  finish();
}

void Progress::advance(uint64_t n) {
  const uint64_t done = done_.fetch_add(n, std::memory_order_relaxed) + n;
  if (!enabled_) return;
  const int64_t now =
      std::chrono::duration_cast<std::chrono::nanoseconds>(std::chrono::steady_clock::now() - start_).count();
  int64_t last = lastDrawNs_.load(std::memory_order_relaxed);
  if (now - last < 100'000'000 && done < total_) return;
  if (!lastDrawNs_.compare_exchange_strong(last, now)) return;
  draw(done, false);
}

void Progress::finish() {
  if (finished_) return;
  finished_ = true;
  if (enabled_) draw(done_.load(), true);
}

void Progress::draw(uint64_t done, bool final) {
  std::lock_guard<std::mutex> lock(drawMutex_);
  const double elapsed = std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
  const double frac = total_ ? double(done) / double(total_) : 1.0;
  const int width = 30;
  const int filled = int(frac * width + 0.5);
  char bar[width + 1];
  for (int i = 0; i < width; ++i) bar[i] = i < filled ? '#' : '.';
  bar[width] = 0;
  const double rate = elapsed > 0 ? double(done) / elapsed : 0.0;
  const double eta = rate > 0 ? double(total_ - (done < total_ ? done : total_)) / rate : 0.0;
  std::fprintf(stderr, "\r%-10s [%s] %llu/%llu %s  %.0f/s  %s %.0fs\x1b[K", label_.c_str(), bar,
               (unsigned long long)done, (unsigned long long)total_, unit_.c_str(), rate,
               final ? "took" : "eta", final ? elapsed : eta);
  if (final) std::fputc('\n', stderr);
  std::fflush(stderr);
}

}  // namespace tetraprobe
