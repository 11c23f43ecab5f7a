// Progress of a long stage: a bar redrawn in place on a terminal (at most 10 times a second), plain lines in a
// log (start after a grace period, a heartbeat every interval from a timer thread, end), nothing when off.
#include "tetraprobe/common/progress.h"

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <exception>

namespace tetraprobe {

namespace {

constexpr double kMaxGraceSeconds = 1.0;

std::chrono::steady_clock::duration toDuration(double seconds) {
  return std::chrono::duration_cast<std::chrono::steady_clock::duration>(
      std::chrono::duration<double>(seconds));
}

// Rates and times with as many digits as a reader needs: 12345 probes/s, 42.5 probes/s, 0.125 probes/s.
std::string number(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, v >= 100.0 ? "%.0f" : v >= 1.0 ? "%.1f" : "%.3g", v);
  return buf;
}

}  // namespace

ProgressOptions ProgressOptions::fromEnvironment() {
  ProgressOptions o;
  if (std::getenv("TETRAPROBE_NO_PROGRESS") != nullptr) return o;
  o.mode = ::isatty(STDERR_FILENO) ? ProgressMode::kBar : ProgressMode::kLog;
  if (const char* s = std::getenv("TETRAPROBE_PROGRESS_SECONDS")) {
    char* end = nullptr;
    const double v = std::strtod(s, &end);
    if (end != s && *end == '\0' && std::isfinite(v)) o.intervalSeconds = std::clamp(v, 0.01, 3600.0);
  }
  o.graceSeconds = std::min(kMaxGraceSeconds, o.intervalSeconds);
  return o;
}

bool Progress::enabled() {
  return std::getenv("TETRAPROBE_NO_PROGRESS") == nullptr;
}

Progress::Progress(std::string label, uint64_t total, std::string unit, bool shown)
    : Progress(std::move(label), total, std::move(unit),
               shown ? ProgressOptions::fromEnvironment() : ProgressOptions{}) {}

Progress::Progress(std::string label, uint64_t total, std::string unit, const ProgressOptions& options)
    : label_(std::move(label)),
      unit_(std::move(unit)),
      total_(total),
      options_(options),
      start_(std::chrono::steady_clock::now()),
      uncaught_(std::uncaught_exceptions()) {
  // A log always has a timer; a bar only for a stage without units (nothing else would redraw it).
  if (options_.mode == ProgressMode::kLog || (options_.mode == ProgressMode::kBar && unit_.empty()))
    timer_ = std::thread([this] { heartbeatLoop(); });
}

Progress::~Progress() {
  finish();
}

void Progress::advance(uint64_t n) {
  const uint64_t done = done_.fetch_add(n, std::memory_order_relaxed) + n;
  if (options_.mode != ProgressMode::kBar) return;  // the log's timer thread reads done_ itself
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
  if (options_.mode == ProgressMode::kBar && !unit_.empty()) draw(done_.load(), true);
  if (!timer_.joinable()) return;
  bool started;
  {
    std::lock_guard<std::mutex> lock(timerMutex_);
    stopping_ = true;
    started = started_;
  }
  wake_.notify_all();
  timer_.join();
  if (!started) return;  // a short stage: nothing printed, nothing to close
  if (options_.mode == ProgressMode::kBar) {
    drawElapsed(true);
    return;
  }
  const uint64_t done = done_.load();
  const double t = elapsedSeconds();
  if (std::uncaught_exceptions() > uncaught_)
    writeLine(unit_.empty() ? "stopped after " + number(t) + " s"
                            : "stopped at " + countText(done) + " after " + number(t) + " s");
  else if (unit_.empty())
    writeLine("done in " + number(t) + " s");
  else
    writeLine("done " + countText(done) + " in " + number(t) + " s (" +
              number(t > 0 ? double(done) / t : 0.0) + " " + unit_ + "/s)");
}

double Progress::elapsedSeconds() const {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
}

std::string Progress::countText(uint64_t done) const {
  char buf[96];
  std::snprintf(buf, sizeof buf, "%llu/%llu ", (unsigned long long)done, (unsigned long long)total_);
  return buf + unit_;
}

void Progress::writeLine(const std::string& text) {
  // One fwrite of the whole line, so lines from several threads or stages never interleave mid-line.
  const std::string line = "progress: " + label_ + ": " + text + "\n";
  std::lock_guard<std::mutex> lock(drawMutex_);
  std::fwrite(line.data(), 1, line.size(), options_.out);
  std::fflush(options_.out);
}

void Progress::heartbeatLoop() {
  std::unique_lock<std::mutex> lock(timerMutex_);
  const auto stopping = [this] { return stopping_; };
  if (wake_.wait_until(lock, start_ + toDuration(options_.graceSeconds), stopping)) return;
  started_ = true;
  if (options_.mode == ProgressMode::kBar) {
    do drawElapsed(false);
    while (!wake_.wait_until(lock, std::chrono::steady_clock::now() + toDuration(options_.graceSeconds),
                             stopping));
    return;
  }
  writeLine(unit_.empty() ? std::string("start") : "start, " + std::to_string(total_) + " " + unit_);
  for (;;) {
    if (wake_.wait_until(lock, std::chrono::steady_clock::now() + toDuration(options_.intervalSeconds),
                         stopping))
      return;
    const double t = elapsedSeconds();
    if (unit_.empty()) {
      writeLine("running, elapsed " + number(t) + " s");
      continue;
    }
    const uint64_t done = std::min(done_.load(std::memory_order_relaxed), total_);
    const double rate = t > 0.0 ? double(done) / t : 0.0;
    char pct[32];
    std::snprintf(pct, sizeof pct, " (%.1f %%), ", total_ ? 100.0 * double(done) / double(total_) : 100.0);
    writeLine(countText(done) + pct + number(rate) + " " + unit_ + "/s, eta " +
              (rate > 0.0 ? number(double(total_ - done) / rate) + " s" : std::string("unknown")) +
              ", elapsed " + number(t) + " s");
  }
}

void Progress::drawElapsed(bool final) {
  std::lock_guard<std::mutex> lock(drawMutex_);
  std::fprintf(options_.out, "\r%-10s %s %.0fs\x1b[K", label_.c_str(), final ? "took" : "running",
               elapsedSeconds());
  if (final) std::fputc('\n', options_.out);
  std::fflush(options_.out);
}

void Progress::draw(uint64_t done, bool final) {
  std::lock_guard<std::mutex> lock(drawMutex_);
  const double elapsed = elapsedSeconds();
  const double frac = total_ ? double(done) / double(total_) : 1.0;
  const int width = 30;
  const int filled = int(frac * width + 0.5);
  char bar[width + 1];
  for (int i = 0; i < width; ++i) bar[i] = i < filled ? '#' : '.';
  bar[width] = 0;
  const double rate = elapsed > 0 ? double(done) / elapsed : 0.0;
  const double eta = rate > 0 ? double(total_ - (done < total_ ? done : total_)) / rate : 0.0;
  std::fprintf(options_.out, "\r%-10s [%s] %llu/%llu %s  %.0f/s  %s %.0fs\x1b[K", label_.c_str(), bar,
               (unsigned long long)done, (unsigned long long)total_, unit_.c_str(), rate,
               final ? "took" : "eta", final ? elapsed : eta);
  if (final) std::fputc('\n', options_.out);
  std::fflush(options_.out);
}

}  // namespace tetraprobe
