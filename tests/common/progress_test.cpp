// Progress in a log (common/progress.h): the lines a scheduler's log shows for a stage, from a fake slow loop
// writing to a temporary file instead of stderr.
#include <gtest/gtest.h>

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include "tetraprobe/common/progress.h"

using namespace tetraprobe;

namespace {

// A log-mode Progress writing to a temporary file; lines() reads back what it wrote.
struct LogSink {
  std::FILE* file = std::tmpfile();
  ~LogSink() { std::fclose(file); }
  ProgressOptions options(double interval, double grace) const {
    ProgressOptions o;
    o.mode = ProgressMode::kLog;
    o.intervalSeconds = interval;
    o.graceSeconds = grace;
    o.out = file;
    return o;
  }
  std::string text() const {
    std::fflush(file);
    std::rewind(file);
    std::string s;
    char buf[4096];
    for (size_t n; (n = std::fread(buf, 1, sizeof buf, file)) > 0;) s.append(buf, n);
    return s;
  }
  std::vector<std::string> lines() const {
    std::vector<std::string> out;
    const std::string s = text();
    for (size_t at = 0, nl; (nl = s.find('\n', at)) != std::string::npos; at = nl + 1)
      out.push_back(s.substr(at, nl - at));
    return out;
  }
};

bool startsWith(const std::string& s, const std::string& prefix) {
  return s.compare(0, prefix.size(), prefix) == 0;
}

// "progress: LABEL: D/T ..." -> D (the count a heartbeat or end line reports).
uint64_t doneOf(const std::string& line) {
  const size_t slash = line.find('/');
  size_t digits = slash;
  while (digits > 0 && line[digits - 1] >= '0' && line[digits - 1] <= '9') --digits;
  return std::stoull(line.substr(digits, slash - digits));
}

void sleepSeconds(double s) {
  std::this_thread::sleep_for(std::chrono::duration<double>(s));
}

}  // namespace

// A loop whose units each take far longer than the interval still gets a heartbeat every interval (the timer
// thread, not advance(), prints them): start line, heartbeats repeating the same count, counts never going
// down, an ETA in each heartbeat, and the end line with the final count.
TEST(Progress, LogHeartbeatsComeWhileNoUnitCompletes) {
  LogSink sink;
  {
    Progress p("slow", 3, "units", sink.options(0.05, 0.05));
    for (int i = 0; i < 3; ++i) {
      sleepSeconds(0.4);
      p.advance();
    }
  }
  const std::vector<std::string> lines = sink.lines();
  ASSERT_GE(lines.size(), 3u) << sink.text();
  EXPECT_EQ(lines.front(), "progress: slow: start, 3 units");
  EXPECT_TRUE(startsWith(lines.back(), "progress: slow: done 3/3 units in ")) << lines.back();
  uint64_t last = 0;
  int atZero = 0, heartbeats = 0;
  for (size_t i = 1; i + 1 < lines.size(); ++i) {
    const std::string& l = lines[i];
    ASSERT_TRUE(startsWith(l, "progress: slow: ")) << l;
    EXPECT_NE(l.find(" units ("), std::string::npos) << l;
    EXPECT_NE(l.find("%), "), std::string::npos) << l;
    EXPECT_NE(l.find(", eta "), std::string::npos) << l;
    EXPECT_NE(l.find(", elapsed "), std::string::npos) << l;
    const uint64_t done = doneOf(l);
    EXPECT_GE(done, last) << l;
    last = done;
    atZero += done == 0;
    ++heartbeats;
  }
  // 1.2 s at a 0.05 s interval is ~20 heartbeats; a loaded machine may delay some, never most.
  EXPECT_GE(heartbeats, 8) << sink.text();
  EXPECT_GE(atZero, 2) << "no heartbeat before the first unit completed:\n" << sink.text();
  EXPECT_EQ(sink.text().find('\x1b'), std::string::npos) << "escape codes in a log";
  EXPECT_EQ(sink.text().find('\r'), std::string::npos) << "carriage returns in a log";
}

// A stage shorter than the grace period prints nothing: no start line, no end line (so a fast run, or one
// failing early, keeps stderr to its own one-line error).
TEST(Progress, LogShortStagePrintsNothing) {
  LogSink sink;
  {
    Progress p("quick", 100, "units", sink.options(0.05, 0.5));
    for (int i = 0; i < 100; ++i) p.advance();
  }
  { Progress p("quick", 0, "", sink.options(0.05, 0.5)); }
  EXPECT_EQ(sink.text(), "");
}

// A stage without units reports its elapsed time: start, "running, elapsed" heartbeats, "done in".
TEST(Progress, LogStageWithoutUnitsReportsElapsedTime) {
  LogSink sink;
  {
    Progress p("tetrahedralize", 0, "", sink.options(0.05, 0.05));
    sleepSeconds(0.4);
  }
  const std::vector<std::string> lines = sink.lines();
  ASSERT_GE(lines.size(), 3u) << sink.text();
  EXPECT_EQ(lines.front(), "progress: tetrahedralize: start");
  for (size_t i = 1; i + 1 < lines.size(); ++i)
    EXPECT_TRUE(startsWith(lines[i], "progress: tetrahedralize: running, elapsed ")) << lines[i];
  EXPECT_TRUE(startsWith(lines.back(), "progress: tetrahedralize: done in ")) << lines.back();
}

// A stage left by an exception says where it stopped, not "done".
TEST(Progress, LogStageLeftByExceptionSaysStopped) {
  LogSink sink;
  try {
    Progress p("bake", 10, "probes", sink.options(0.05, 0.05));
    p.advance(4);
    sleepSeconds(0.2);
    throw std::runtime_error("boom");
  } catch (const std::runtime_error&) {
  }
  const std::vector<std::string> lines = sink.lines();
  ASSERT_GE(lines.size(), 2u) << sink.text();
  EXPECT_TRUE(startsWith(lines.back(), "progress: bake: stopped at 4/10 probes after ")) << lines.back();
}

// Off prints nothing however long the stage; finish() is idempotent and the destructor after it adds nothing.
TEST(Progress, OffPrintsNothingAndFinishIsIdempotent) {
  LogSink sink;
  {
    ProgressOptions o = sink.options(0.05, 0.05);
    o.mode = ProgressMode::kOff;
    Progress p("off", 5, "units", o);
    sleepSeconds(0.2);
    p.advance(5);
  }
  EXPECT_EQ(sink.text(), "");
  {
    Progress p("twice", 2, "units", sink.options(0.05, 0.05));
    sleepSeconds(0.15);
    p.advance(2);
    p.finish();
    p.finish();
  }
  const std::vector<std::string> lines = sink.lines();
  ASSERT_FALSE(lines.empty());
  int ends = 0;
  for (const std::string& l : lines) ends += startsWith(l, "progress: twice: done ");
  EXPECT_EQ(ends, 1) << sink.text();
}

// advance() from many threads at once loses no unit (the end line's count is the sum).
TEST(Progress, AdvanceFromManyThreadsCountsEveryUnit) {
  LogSink sink;
  {
    Progress p("threads", 40000, "units", sink.options(0.01, 0.0));
    std::vector<std::thread> workers;
    for (int t = 0; t < 4; ++t)
      workers.emplace_back([&] {
        for (int i = 0; i < 10000; ++i) p.advance();
      });
    for (std::thread& w : workers) w.join();
    sleepSeconds(0.05);  // past the (zero) grace period on a loaded machine too: the end line is printed
  }
  const std::vector<std::string> lines = sink.lines();
  ASSERT_FALSE(lines.empty()) << sink.text();
  EXPECT_TRUE(startsWith(lines.back(), "progress: threads: done 40000/40000 units")) << lines.back();
}

// The environment: TETRAPROBE_PROGRESS_SECONDS sets the interval (and the grace period, when shorter than
// 1 s); a value that is not a number leaves 5 s; TETRAPROBE_NO_PROGRESS turns everything off.
TEST(Progress, EnvironmentSetsIntervalAndSilences) {
  ::unsetenv("TETRAPROBE_NO_PROGRESS");
  ::setenv("TETRAPROBE_PROGRESS_SECONDS", "0.2", 1);
  ProgressOptions o = ProgressOptions::fromEnvironment();
  EXPECT_NE(o.mode, ProgressMode::kOff);
  EXPECT_DOUBLE_EQ(o.intervalSeconds, 0.2);
  EXPECT_DOUBLE_EQ(o.graceSeconds, 0.2);
  ::setenv("TETRAPROBE_PROGRESS_SECONDS", "30", 1);
  o = ProgressOptions::fromEnvironment();
  EXPECT_DOUBLE_EQ(o.intervalSeconds, 30.0);
  EXPECT_DOUBLE_EQ(o.graceSeconds, 1.0);
  ::setenv("TETRAPROBE_PROGRESS_SECONDS", "soon", 1);
  EXPECT_DOUBLE_EQ(ProgressOptions::fromEnvironment().intervalSeconds, 5.0);
  ::unsetenv("TETRAPROBE_PROGRESS_SECONDS");
  ::setenv("TETRAPROBE_NO_PROGRESS", "1", 1);
  EXPECT_EQ(ProgressOptions::fromEnvironment().mode, ProgressMode::kOff);
  EXPECT_FALSE(Progress::enabled());
  ::unsetenv("TETRAPROBE_NO_PROGRESS");
}
