// Progress of a long stage on stderr, in one of two forms chosen by where stderr goes:
//  - a terminal: one bar redrawn in place (label, bar, done/total, rate, ETA), at most 10 times a second;
//    for a stage without units, its label and elapsed time redrawn every second once it has run for one;
//  - anything else (a file, a pipe, a scheduler's or CI's log): plain newline-terminated lines without escape
//    codes, for a log that says where a bake is:
//      progress: LABEL: start, TOTAL UNIT
//      progress: LABEL: DONE/TOTAL UNIT (P %), R UNIT/s, eta E s, elapsed T s      (every interval)
//      progress: LABEL: done DONE/TOTAL UNIT in T s (R UNIT/s)
//    and, for a stage without units (empty `unit`), "start", "running, elapsed T s" and "done in T s".
//    A stage shorter than the grace period (1 s, or the interval when that is shorter) prints nothing at all,
//    so a short run (and a run failing early) keeps stderr to its own lines; a longer one prints its start
//    line at the grace period, a heartbeat every interval after that whether or not a unit completed (a
//    timer thread per Progress), and its end line when it finishes: "done", or "stopped at DONE/TOTAL UNIT
//    after T s" when it ends while an exception unwinds the stack.
// The interval is 5 s; TETRAPROBE_PROGRESS_SECONDS=S sets it (0.05 in tests). TETRAPROBE_NO_PROGRESS
// (any value) silences both forms. advance() is thread-safe and cheap (one relaxed atomic add; on a terminal a
// clock read too).
#pragma once

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <cstdio>
#include <mutex>
#include <string>
#include <thread>

namespace tetraprobe {

enum class ProgressMode {
  kOff,  // counts only, prints nothing
  kBar,  // a bar redrawn in place (a terminal)
  kLog,  // plain lines: start, heartbeat every interval, end
};

struct ProgressOptions {
  ProgressMode mode = ProgressMode::kOff;
  double intervalSeconds = 5.0;  // kLog: between heartbeats
  double graceSeconds = 1.0;     // kLog: a stage that finishes sooner prints nothing
  std::FILE* out = stderr;       // where the lines go (not owned)

  // What stderr and the environment ask for: kOff under TETRAPROBE_NO_PROGRESS, else kBar on a terminal and
  // kLog elsewhere; the interval from TETRAPROBE_PROGRESS_SECONDS (clamped to [0.01, 3600] s; unset or not a
  // number: 5 s) and the grace period min(1 s, interval).
  static ProgressOptions fromEnvironment();
};

class Progress {
 public:
  // `label` names the work ("bake", "tetrahedralize"); `total` counts its units; `unit` names them ("probes"),
  // empty for a stage without units (then `total` and advance() are ignored and the lines give elapsed time).
  // shown = false: prints nothing (for callers whose own options turn progress off).
  Progress(std::string label, uint64_t total, std::string unit, bool shown = true);
  Progress(std::string label, uint64_t total, std::string unit, const ProgressOptions& options);
  ~Progress();  // finish()
  Progress(const Progress&) = delete;
  Progress& operator=(const Progress&) = delete;

  void advance(uint64_t n = 1);
  // Ends the stage: the bar's last draw or the log's end line (only if its start line was printed), and
  // joins the timer thread. Idempotent; call it from the thread that made the Progress.
  void finish();

  static bool enabled();  // TETRAPROBE_NO_PROGRESS is unset (the bar on a terminal, lines elsewhere)

 private:
  void draw(uint64_t done, bool final);
  void drawElapsed(bool final);  // kBar without units: label and elapsed time
  void heartbeatLoop();
  void writeLine(const std::string& text);
  std::string countText(uint64_t done) const;
  double elapsedSeconds() const;

  std::string label_, unit_;
  uint64_t total_;
  ProgressOptions options_;
  std::atomic<uint64_t> done_{0};
  std::atomic<int64_t> lastDrawNs_{0};
  std::chrono::steady_clock::time_point start_;
  std::mutex drawMutex_;
  bool finished_ = false;
  // kLog: the timer thread sleeps on `wake_` until the next line is due or finish() sets `stopping_`.
  std::thread timer_;
  std::mutex timerMutex_;
  std::condition_variable wake_;
  bool stopping_ = false;
  bool started_ = false;  // the start line was printed (guarded by timerMutex_)
  int uncaught_ = 0;      // std::uncaught_exceptions() at construction
};

}  // namespace tetraprobe
