// `tetraprobe bake` as a scheduler runs it, stderr into a pipe (not a terminal): the log says where the bake
// is. Each stage that runs past the grace period prints a start line, a heartbeat every interval whether or
// not a unit completed, and an end line (common/progress.h). The heartbeat interval is shortened to 0.05 s
// (TETRAPROBE_PROGRESS_SECONDS) so a bake of a second or two shows many.
#include <gtest/gtest.h>

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <string>
#include <vector>

namespace fs = std::filesystem;

namespace {

constexpr double kInterval = 0.05;  // seconds, TETRAPROBE_PROGRESS_SECONDS
// A loaded machine (2 cores, several builds) may wake the timer thread or the reader late; the contract is a
// line at least every 10 s at the 5 s default, so slack of 1 s on 0.05 s still catches a missing heartbeat.
constexpr double kSlack = 1.0;

struct Line {
  double at;  // seconds since the bake started, when the line reached the pipe's reader
  std::string text;
};

// Runs the CLI with stderr into a pipe (stdout discarded), each line stamped as it arrives.
std::vector<Line> runLogged(const std::string& env, const std::string& args, int& code) {
  const std::string cmd =
      "env -u TETRAPROBE_NO_PROGRESS " + env + " " + TETRAPROBE_CLI + " " + args + " 2>&1 >/dev/null";
  const auto t0 = std::chrono::steady_clock::now();
  std::FILE* pipe = ::popen(cmd.c_str(), "r");
  std::vector<Line> lines;
  if (!pipe) return lines;
  std::string line;
  for (int c; (c = std::fgetc(pipe)) != EOF;) {
    if (c != '\n') {
      line += char(c);
      continue;
    }
    lines.push_back({std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count(), line});
    line.clear();
  }
  if (!line.empty()) lines.push_back({-1.0, line + " [no newline]"});
  const int status = ::pclose(pipe);
  code = WIFEXITED(status) ? WEXITSTATUS(status) : 128;
  return lines;
}

std::string dump(const std::vector<Line>& lines) {
  std::string s;
  char at[32];
  for (const Line& l : lines) {
    std::snprintf(at, sizeof at, "%7.3f  ", l.at);
    s += at + l.text + "\n";
  }
  return s;
}

bool startsWith(const std::string& s, const std::string& prefix) {
  return s.compare(0, prefix.size(), prefix) == 0;
}

// "D/N unit ..." at the start of `s` -> D and N; false when `s` does not start so.
bool parseCount(const std::string& s, unsigned long long& done, unsigned long long& total) {
  return std::sscanf(s.c_str(), "%llu/%llu", &done, &total) == 2;
}

class ProgressLog : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("tetraprobe_progress_" + std::to_string(::getpid()) + "_" +
                                        ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  static std::string sample() {
    return std::string(TETRAPROBE_SOURCE_DIR) + "/samples/two_rooms/two_rooms.scene.json";
  }
  fs::path dir_;
};

}  // namespace

// Every stderr line of a bake is a progress line, grouped in stages: "start", heartbeats no further apart
// than the interval plus slack, counts that never go down and never pass the total, an ETA in every
// heartbeat of a stage with units, and one end line ("done") with the whole count. The bake (a fixed 8192
// paths per probe on one thread, then refinement; about 1 s of CPU) is long enough for several heartbeats
// in the probe bake (29 probes traced) on a fast machine too.
TEST_F(ProgressLog, BakeWithoutTerminalPrintsHeartbeatsForEveryLongStage) {
  int code = -1;
  const std::vector<Line> lines =
      runLogged("TETRAPROBE_PROGRESS_SECONDS=" + std::to_string(kInterval),
                "bake " + sample() + " -o " + (dir_ / "l.tpb").string() +
                    " --samples 8192 --noise 0 --fill-holes 0 --probe-budget 4 --refine-points 512 "
                    "--occlusion none --threads 1",
                code);
  ASSERT_EQ(code, 0) << dump(lines);
  ASSERT_TRUE(fs::exists(dir_ / "l.tpb"));
  const std::string log = dump(lines);

  std::string open;  // the stage whose start line came last and whose end line has not
  bool units = false;
  unsigned long long last = 0, total = 0;
  double lastAt = 0.0;
  int stages = 0, unitHeartbeats = 0;
  bool sawBake = false;
  for (const Line& l : lines) {
    ASSERT_TRUE(startsWith(l.text, "progress: ")) << "not a progress line: " << l.text << "\n" << log;
    ASSERT_GE(l.at, 0.0) << log;
    const size_t colon = l.text.find(": ", 10);
    ASSERT_NE(colon, std::string::npos) << l.text;
    const std::string label = l.text.substr(10, colon - 10), rest = l.text.substr(colon + 2);
    if (open.empty()) {
      ASSERT_TRUE(startsWith(rest, "start")) << "a stage must open with its start line: " << l.text << "\n"
                                             << log;
      open = label;
      units = rest != "start";
      if (units) {
        ASSERT_EQ(std::sscanf(rest.c_str(), "start, %llu", &total), 1) << l.text;
      }
      last = 0;
      lastAt = l.at;
      ++stages;
      sawBake |= label == "bake" && units;
      continue;
    }
    ASSERT_EQ(label, open) << "stages overlap or a stage did not end:\n" << log;
    EXPECT_LE(l.at - lastAt, kInterval + kSlack) << "no line for too long in " << label << "\n" << log;
    lastAt = l.at;
    if (startsWith(rest, "done")) {
      if (units) {
        unsigned long long done = 0, n = 0;
        ASSERT_TRUE(parseCount(rest.substr(5), done, n)) << l.text;
        EXPECT_EQ(n, total) << l.text;
        EXPECT_EQ(done, total) << "a finished bake stage did all its units: " << l.text;
        EXPECT_GE(done, last) << l.text;
      } else {
        EXPECT_TRUE(startsWith(rest, "done in ")) << l.text;
      }
      open.clear();
      continue;
    }
    if (units) {
      unsigned long long done = 0, n = 0;
      ASSERT_TRUE(parseCount(rest, done, n)) << "heartbeat without done/total: " << l.text;
      EXPECT_EQ(n, total) << l.text;
      EXPECT_GE(done, last) << "count went down: " << l.text << "\n" << log;
      EXPECT_LE(done, total) << l.text;
      last = done;
      EXPECT_NE(rest.find(" %), "), std::string::npos) << "no percentage: " << l.text;
      EXPECT_NE(rest.find("/s, eta "), std::string::npos) << "no rate and ETA: " << l.text;
      ++unitHeartbeats;
    } else {
      EXPECT_TRUE(startsWith(rest, "running, elapsed ")) << l.text;
    }
  }
  EXPECT_TRUE(open.empty()) << "stage " << open << " has no end line\n" << log;
  EXPECT_TRUE(sawBake) << "the probe bake printed no progress\n" << log;
  EXPECT_GE(stages, 2) << log;
  EXPECT_GE(unitHeartbeats, 3) << log;
}

// TETRAPROBE_NO_PROGRESS silences the log whatever the interval: stderr of a successful bake stays empty.
TEST_F(ProgressLog, NoProgressSilencesTheLog) {
  int code = -1;
  const std::vector<Line> lines =
      runLogged("TETRAPROBE_NO_PROGRESS=1 TETRAPROBE_PROGRESS_SECONDS=0.01",
                "bake " + sample() + " -o " + (dir_ / "l.tpb").string() +
                    " --samples 64 --noise 0 --fill-holes 0 --probe-budget 0 --occlusion none --threads 2",
                code);
  EXPECT_EQ(code, 0) << dump(lines);
  EXPECT_TRUE(lines.empty()) << dump(lines);
}
