// End-to-end tests of the tetraprobe CLI: each runs the real binary the way a user or CI pipeline does and
// checks what they rely on: exit codes (0 ok, 1 failure, 2 bad usage/input), one-line errors naming the
// problem, no partial output after a failure, reports with the documented keys, bit-identical levels for any
// thread count, and light where the sample level's light is.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <random>
#include <set>
#include <sstream>
#include <string>

#include <glm/geometric.hpp>
#include <nlohmann/json.hpp>

#include "image_compare.h"
#include "level_bytes.h"
#include "missing_capability.h"
#include "tetraprobe/runtime/gpu_sector_pool.h"
#include "tetraprobe/runtime/level.h"
#include "tetraprobe/runtime/luminance.h"
#include "tetraprobe/runtime/query.h"
#include "tetraprobe/runtime/streaming.h"

namespace fs = std::filesystem;

namespace {

struct CliRun {
  int code = -1;
  std::string out;  // stdout
  std::string err;  // stderr
};

std::string slurp(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

class Cli : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("tetraprobe_cli_" + std::to_string(::getpid()) + "_" +
                                        ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }

  CliRun run(const std::string& args) {
    const fs::path out = dir_ / "stdout.txt", err = dir_ / "stderr.txt";
    const std::string cmd =
        std::string(TETRAPROBE_CLI) + " " + args + " >" + out.string() + " 2>" + err.string();
    const int status = std::system(cmd.c_str());
    CliRun r;
    r.code = WIFEXITED(status) ? WEXITSTATUS(status) : 128;
    r.out = slurp(out);
    r.err = slurp(err);
    return r;
  }
  fs::path write(const std::string& name, const std::string& text) {
    const fs::path p = dir_ / name;
    std::ofstream(p) << text;
    return p;
  }
  fs::path path(const std::string& name) const { return dir_ / name; }
  // box.obj (+ .mtl) baked cheaply into l.tpb (16 paths a probe, no noise target: well under a second), for
  // the eval tests; fails the test when the bake does.
  void bakeBox();  // defined after kBoxObj and kBoxMtl
  // No file in the directory other than the test's own inputs and captured streams.
  bool onlyInputsLeft(const std::vector<std::string>& inputs) const {
    for (const auto& e : fs::directory_iterator(dir_)) {
      const std::string n = e.path().filename().string();
      if (n == "stdout.txt" || n == "stderr.txt") continue;
      if (std::find(inputs.begin(), inputs.end(), n) == inputs.end()) return false;
    }
    return true;
  }

  static std::string sample() {
    return std::string(TETRAPROBE_SOURCE_DIR) + "/samples/two_rooms/two_rooms.scene.json";
  }

  fs::path dir_;
};

int lineCount(const std::string& s) {
  return int(std::count(s.begin(), s.end(), '\n'));
}

// A closed 4 x 3 x 4 m box whose faces point inward (counter-clockwise seen from inside) with an emissive
// ceiling tile facing down: small enough to bake in well under a second.
const char* kBoxObj = R"(mtllib box.mtl
v 0 0 0
v 4 0 0
v 4 0 4
v 0 0 4
v 0 3 0
v 4 3 0
v 4 3 4
v 0 3 4
v 1.5 2.99 1.5
v 2.5 2.99 1.5
v 2.5 2.99 2.5
v 1.5 2.99 2.5
usemtl wall
f 3 2 1
f 4 3 1
f 7 8 5
f 6 7 5
f 6 5 1
f 2 6 1
f 7 6 2
f 3 7 2
f 8 7 3
f 4 8 3
f 5 8 4
f 1 5 4
usemtl light
f 11 12 9
f 10 11 9
)";
const char* kBoxMtl = "newmtl wall\nKd 0.7 0.7 0.7\nnewmtl light\nKd 0 0 0\nKe 10 10 10\n";

void Cli::bakeBox() {
  write("box.obj", kBoxObj);
  write("box.mtl", kBoxMtl);
  const CliRun bake = run("bake " + path("box.obj").string() + " -o " + path("l.tpb").string() +
                          " --samples 16 --noise 0 --threads 2");
  ASSERT_EQ(bake.code, 0) << bake.err;
}

}  // namespace

// The default spacing follows the scene's size: a box 2 m across (the 4 m test box halved, the size of the
// Cornell box) would have every 1 m voxel touch a wall and place no probe. auto gives 8 voxels along its
// largest extent (0.25 m) and a level; an explicit 1 m fails with exit 2, one line naming the spacing, the
// scene's size and what auto would pick, and no output. A scene of 8 m or more keeps 1 m
// (autoSpacing, tools/cli/pipeline.h).
TEST_F(Cli, SmallSceneBakesAtAnAutomaticSpacing) {
  std::string half;  // kBoxObj with every coordinate halved
  std::istringstream in(kBoxObj);
  for (std::string line; std::getline(in, line);) {
    if (line.rfind("v ", 0) == 0) {
      std::istringstream v(line.substr(2));
      double x, y, z;
      v >> x >> y >> z;
      line = "v " + std::to_string(x / 2) + " " + std::to_string(y / 2) + " " + std::to_string(z / 2);
    }
    half += line + "\n";
  }
  write("small.obj", half.c_str());
  write("box.mtl", kBoxMtl);
  const std::string quick = " --samples 16 --noise 0 --probe-budget 0 --fill-holes 0 --threads 2";
  const CliRun fixed = run("bake " + path("small.obj").string() + " --spacing 1" + quick + " -o " +
                           path("fixed.tpb").string());
  EXPECT_EQ(fixed.code, 2) << fixed.err;
  EXPECT_EQ(std::count(fixed.err.begin(), fixed.err.end(), '\n'), 1) << fixed.err;
  EXPECT_NE(fixed.err.find("at --spacing 1 m in a scene 2 m across"), std::string::npos) << fixed.err;
  EXPECT_NE(fixed.err.find("auto picks 0.25 m"), std::string::npos) << fixed.err;
  EXPECT_FALSE(fs::exists(path("fixed.tpb")));

  const CliRun automatic = run("bake " + path("small.obj").string() + quick + " -o " +
                               path("auto.tpb").string() + " --report " + path("auto.json").string());
  ASSERT_EQ(automatic.code, 0) << automatic.err;
  EXPECT_NE(automatic.out.find("spacing 0.25 m (auto"), std::string::npos) << automatic.out;
  const auto j = nlohmann::json::parse(slurp(path("auto.json")));
  EXPECT_EQ(j["options"]["spacing"].get<double>(), 0.25);
  EXPECT_TRUE(j["options"]["spacing_auto"].get<bool>());
  EXPECT_GE(j["probes"]["count"].get<size_t>(), 100u);

  // The 4 m box: 0.5 m (4 m / 8); the bundled two-room sample (8.2 m): 1 m, as before auto existed.
  write("box.obj", kBoxObj);
  const CliRun box = run("bake " + path("box.obj").string() + quick + " -o " + path("box.tpb").string() +
                         " --report " + path("box.json").string());
  ASSERT_EQ(box.code, 0) << box.err;
  EXPECT_EQ(nlohmann::json::parse(slurp(path("box.json")))["options"]["spacing"].get<double>(), 0.5);
}

// Every command answers --help with usage on stdout and exit 0.
TEST_F(Cli, HelpExitsZeroForEveryCommand) {
  for (const char* c : {"bake", "merge", "stream", "inspect", "query", "render", "eval", "diff", "reference",
                        "export-sh", "bench"}) {
    const CliRun r = run(std::string(c) + " --help");
    EXPECT_EQ(r.code, 0) << c << ": " << r.err;
    EXPECT_NE(r.out.find("usage: tetraprobe"), std::string::npos) << c;
  }
  EXPECT_EQ(run("--help").code, 0);
}

// Bad usage is exit 2 with exactly one line on stderr.
TEST_F(Cli, BadUsageExitsTwoWithOneLine) {
  for (const char* a :
       {"", "frobnicate", "bake", "bake x.obj", "bake x.obj -o", "bake x.obj -o l.tpb --spacing abc",
        "bake x.obj -o l.tpb --no-such-flag", "bake x.obj -o l.tpb --share-caps maybe",
        "bake x.obj -o l.tpb --dering windowed", "query", "render a b", "eval a"}) {
    const CliRun r = run(a);
    EXPECT_EQ(r.code, 2) << "'" << a << "': " << r.err;
    if (std::string(a).size() > 0) {
      EXPECT_EQ(lineCount(r.err), 1) << "'" << a << "': " << r.err;
    }
  }
}

// Bad input files: exit 2, the message names the file or problem, and no level file (or temporary) is left.
TEST_F(Cli, BadInputExitsTwoAndLeavesNoOutput) {
  write("box.mtl", kBoxMtl);
  write("broken.obj", "v 0 0 0\nv 1 0 0\nf 1 2 7\n");
  write("nan.obj", "v 0 0 0\nv nan 0 0\nv 0 1 0\nf 1 2 3\n");
  write("empty.obj", "# nothing\n");
  write("box.obj", kBoxObj);
  write("coplanar.csv", "1 ,1,1\n2,1,1\n1,1,2\n2,1,2\n");
  write("bad.scene.json", "{ \"mesh\": ");
  struct Case {
    std::string args, mentions;
  } cases[] = {
      {"bake " + path("missing.obj").string() + " -o " + path("l.tpb").string(), "missing.obj"},
      {"bake " + path("broken.obj").string() + " -o " + path("l.tpb").string(), "broken.obj"},
      {"bake " + path("nan.obj").string() + " -o " + path("l.tpb").string(), "nan.obj"},
      {"bake " + path("empty.obj").string() + " -o " + path("l.tpb").string(), "empty.obj"},
      {"bake " + path("bad.scene.json").string() + " -o " + path("l.tpb").string(), "bad.scene.json"},
      {"bake " + path("box.obj").string() + " --probes " + path("coplanar.csv").string() + " -o " +
           path("l.tpb").string(),
       "coplanar"},
      {"inspect " + path("box.obj").string(), "box.obj"},
  };
  for (const auto& c : cases) {
    const CliRun r = run(c.args);
    EXPECT_EQ(r.code, 2) << c.args << "\n" << r.err;
    EXPECT_EQ(lineCount(r.err), 1) << c.args << "\n" << r.err;
    EXPECT_NE(r.err.find(c.mentions), std::string::npos)
        << "error should name '" << c.mentions << "': " << r.err;
    EXPECT_TRUE(onlyInputsLeft(
        {"box.mtl", "box.obj", "broken.obj", "nan.obj", "empty.obj", "coplanar.csv", "bad.scene.json"}))
        << c.args;
  }
}

// A sharded bake (bake --shard I/N, merge) gives the one-process bake's level byte for byte, here with two
// shards run one after the other (tools/distributed/run_local.sh runs three at once on the sample level,
// with refinement; here one hole round and no refinement keep it to seconds). With probe guiding too: the
// merge's path budget goes on with the direction guide each shard's pass 2 learned (the part file carries it);
// and with --share-caps on, where the merge's pass traces half of the capped probes' paths (any thread count:
// the same bytes).
TEST_F(Cli, MergedShardsEqualOneProcessBake) {
  write("box.obj", kBoxObj);
  write("box.mtl", kBoxMtl);
  for (const std::string settings : {"--guide off", "--guide on", "--guide on --share-caps on"}) {
    SCOPED_TRACE(settings);
    const std::string base =
        "bake " + path("box.obj").string() +
        " --samples 32 --max-samples 256 --path-budget 100000 --spacing 0.75 --threads 2 --fill-holes 1 "
        "--probe-budget 0 " +
        settings;
    for (int i = 0; i < 2; ++i) {
      const CliRun r = run(base + " --shard " + std::to_string(i) + "/2 -o " +
                           path("s" + std::to_string(i) + ".part").string());
      ASSERT_EQ(r.code, 0) << r.err;
    }
    const CliRun m = run("merge " + path("s1.part").string() + " " + path("s0.part").string() + " -o " +
                         path("merged.tpb").string());
    ASSERT_EQ(m.code, 0) << m.err;
    ASSERT_EQ(run(base + " -o " + path("one.tpb").string()).code, 0);
    const std::string a = slurp(path("merged.tpb")), b = slurp(path("one.tpb"));
    ASSERT_FALSE(a.empty());
    EXPECT_TRUE(a == b) << "merged level differs from the one-process bake";
    if (settings.find("share-caps") != std::string::npos) {  // and any thread count gives those bytes
      const std::string single = base.substr(0, base.find("--threads 2")) + "--threads 1" +
                                 base.substr(base.find("--threads 2") + std::string("--threads 2").size());
      ASSERT_EQ(run(single + " -o " + path("single.tpb").string()).code, 0);
      EXPECT_TRUE(slurp(path("single.tpb")) == b) << "--threads 1 differs from --threads 2";
    }
  }
}

// The two-round protocol (bake --round 1, merge --floor, bake --round 2, merge), in which no shard traces
// another's pass 1, gives the one-process bake's level too; round 2 refuses another shard's round-1 part.
TEST_F(Cli, TwoRoundShardsEqualOneProcessBake) {
  write("box.obj", kBoxObj);
  write("box.mtl", kBoxMtl);
  const std::string base =
      "bake " + path("box.obj").string() +
      " --samples 32 --max-samples 256 --path-budget 100000 --spacing 0.75 --threads 2 --fill-holes 1 "
      "--probe-budget 0";
  for (int i = 0; i < 2; ++i) {
    const CliRun r = run(base + " --shard " + std::to_string(i) + "/2 --round 1 -o " +
                         path("r1_" + std::to_string(i) + ".part").string());
    ASSERT_EQ(r.code, 0) << r.err;
  }
  const CliRun f = run("merge --floor " + path("r1_0.part").string() + " " + path("r1_1.part").string() +
                       " -o " + path("floor.part").string());
  ASSERT_EQ(f.code, 0) << f.err;
  const CliRun wrong = run(base + " --shard 0/2 --round 2 --floor " + path("floor.part").string() +
                           " --resume " + path("r1_1.part").string() + " -o " + path("x.part").string());
  EXPECT_EQ(wrong.code, 2) << wrong.err;
  EXPECT_EQ(lineCount(wrong.err), 1) << wrong.err;
  for (int i = 0; i < 2; ++i) {
    const std::string k = std::to_string(i);
    const CliRun r =
        run(base + " --shard " + k + "/2 --round 2 --floor " + path("floor.part").string() + " --resume " +
            path("r1_" + k + ".part").string() + " -o " + path("r2_" + k + ".part").string());
    ASSERT_EQ(r.code, 0) << r.err;
  }
  const CliRun m = run("merge " + path("r2_0.part").string() + " " + path("r2_1.part").string() + " -o " +
                       path("merged.tpb").string());
  ASSERT_EQ(m.code, 0) << m.err;
  ASSERT_EQ(run(base + " -o " + path("one.tpb").string()).code, 0);
  const std::string a = slurp(path("merged.tpb")), b = slurp(path("one.tpb"));
  ASSERT_FALSE(a.empty());
  EXPECT_TRUE(a == b) << "two-round merged level differs from the one-process bake";
  // Round-1 parts are not merge input.
  const CliRun early = run("merge " + path("r1_0.part").string() + " " + path("r1_1.part").string() + " -o " +
                           path("early.tpb").string());
  EXPECT_EQ(early.code, 2) << early.err;
  EXPECT_NE(early.err.find("round-1"), std::string::npos) << early.err;
}

// A merge whose tracing goes to a farm of worker processes (merge --farm DIR --workers 2, tetraprobe worker)
// writes the one-process bake's level byte for byte, and says in its summary how long it waited on them; a
// farm directory holding an earlier run's files is refused, and a worker that loaded another scene stops the
// merge with one line naming the problem.
TEST_F(Cli, FarmedMergeEqualsOneProcessBake) {
  write("box.obj", kBoxObj);
  write("box.mtl", kBoxMtl);
  const std::string base =
      "bake " + path("box.obj").string() +
      " --samples 32 --max-samples 256 --path-budget 100000 --spacing 0.75 --threads 2 --fill-holes 1 "
      "--probe-budget 64";
  for (int i = 0; i < 2; ++i)
    ASSERT_EQ(run(base + " --shard " + std::to_string(i) + "/2 -o " +
                  path("s" + std::to_string(i) + ".part").string())
                  .code,
              0);
  const std::string tp = TETRAPROBE_CLI, parts = path("s0.part").string() + " " + path("s1.part").string();
  // The workers and the merge at once, as a scheduler starts them; the shell waits for all three.
  auto farmed = [&](const std::string& farm, const std::string& workerScene, const std::string& out) {
    std::string cmd = "(";
    for (int i = 0; i < 2; ++i)
      cmd += tp + " worker " + workerScene + " --farm " + farm + " --index " + std::to_string(i) +
             "/2 --threads 1 --farm-timeout 30 >" + path("w" + std::to_string(i) + ".log").string() +
             " 2>&1 & ";
    cmd += tp + " merge " + parts + " -o " + out + " --farm " + farm + " --workers 2 --farm-timeout 30 >" +
           path("m.out").string() + " 2>" + path("m.err").string() + "; s=$?; wait; exit $s)";
    const int status = std::system(cmd.c_str());
    return WIFEXITED(status) ? WEXITSTATUS(status) : 128;
  };
  ASSERT_EQ(farmed(path("farm").string(), path("box.obj").string(), path("merged.tpb").string()), 0)
      << slurp(path("m.err")) << slurp(path("w0.log"));
  // Both kinds of work went to the farm: the rounds' probe steps and the refinement's and fit's points.
  const std::string summary = slurp(path("m.out"));
  EXPECT_NE(summary.find("waiting on them"), std::string::npos) << summary;
  EXPECT_EQ(summary.find(" 0 probe steps"), std::string::npos) << summary;
  EXPECT_EQ(summary.find(" 0 reference points"), std::string::npos) << summary;
  EXPECT_NE(slurp(path("w1.log")).find("traced its share"), std::string::npos) << slurp(path("w1.log"));
  ASSERT_EQ(run(base + " -o " + path("one.tpb").string()).code, 0);
  const std::string a = slurp(path("merged.tpb")), b = slurp(path("one.tpb"));
  ASSERT_FALSE(a.empty());
  EXPECT_TRUE(a == b) << "farmed merge differs from the one-process bake";

  // The same directory again: its `done` would stop new workers at once.
  const CliRun stale = run("merge " + parts + " -o " + path("again.tpb").string() + " --farm " +
                           path("farm").string() + " --workers 2");
  EXPECT_EQ(stale.code, 2) << stale.err;
  EXPECT_NE(stale.err.find("earlier run"), std::string::npos) << stale.err;
  EXPECT_FALSE(fs::exists(path("again.tpb")));

  // Workers on another scene (the box moved by a centimetre: same probes, another content hash).
  std::string moved = kBoxObj;
  moved.replace(moved.find("v 0 0 0\n"), 8, "v 0.01 0 0\n");
  write("moved.obj", moved);
  const int code = farmed(path("farm2").string(), path("moved.obj").string(), path("other.tpb").string());
  EXPECT_EQ(code, 2) << slurp(path("m.err"));
  EXPECT_EQ(lineCount(slurp(path("m.err"))), 1) << slurp(path("m.err"));
  EXPECT_NE(slurp(path("m.err")).find("another scene"), std::string::npos) << slurp(path("m.err"));
  EXPECT_FALSE(fs::exists(path("other.tpb")));
}

// merge refuses parts that do not belong together, with one line naming the problem and exit 2, and
// writes nothing: a missing shard, a shard given twice, other options, a damaged part; bake refuses a
// shard index out of range and a sharded bake without adaptive sampling.
TEST_F(Cli, MergeRefusesPartsThatDoNotBelongTogether) {
  write("box.obj", kBoxObj);
  write("box.mtl", kBoxMtl);
  const std::string base = "bake " + path("box.obj").string() + " --samples 32 --spacing 0.75 --threads 2 " +
                           "--probe-budget 0 --fill-holes 0";
  ASSERT_EQ(run(base + " --shard 0/2 -o " + path("s0.part").string()).code, 0);
  ASSERT_EQ(run(base + " --shard 1/2 -o " + path("s1.part").string()).code, 0);
  ASSERT_EQ(run(base + " --seed 7 --shard 1/2 -o " + path("seed7.part").string()).code, 0);
  std::string damaged = slurp(path("s1.part"));
  damaged[damaged.size() / 2] ^= 0x10;
  std::ofstream(path("damaged.part"), std::ios::binary) << damaged;
  std::string older = slurp(path("s1.part"));  // a part of the format before the estimate's batch count
  older[7] = '1';
  std::ofstream(path("older.part"), std::ios::binary) << older;
  const std::string s0 = path("s0.part").string(), s1 = path("s1.part").string();
  const struct {
    std::string args, mentions;
  } cases[] = {
      {"merge " + s0, "missing"},
      {"merge " + s0 + " " + s0 + " " + s1, "twice"},
      {"merge " + s0 + " " + path("seed7.part").string(), "different options"},
      {"merge " + s0 + " " + path("damaged.part").string(), "checksum"},
      {"merge " + path("box.obj").string(), "not a shard part"},
      {"merge " + s0 + " " + path("older.part").string(), "another version"},
      {base + " --shard 2/2 -o " + path("x.part").string(), "--shard"},
      {base + " --noise 0 --shard 0/2 -o " + path("x.part").string(), "adaptive"},
  };
  for (const auto& c : cases) {
    const CliRun r = run(c.args + (c.args.rfind("merge", 0) == 0 ? " -o " + path("out.tpb").string() : ""));
    EXPECT_EQ(r.code, 2) << c.args << ": " << r.err;
    EXPECT_EQ(lineCount(r.err), 1) << c.args << ": " << r.err;
    EXPECT_NE(r.err.find(c.mentions), std::string::npos) << c.args << ": " << r.err;
    EXPECT_FALSE(fs::exists(path("out.tpb")));
    EXPECT_FALSE(fs::exists(path("x.part")));
  }
}

// A level streamed sector by sector (tetraprobe stream, StreamingLevel) answers bit for bit as the fully
// loaded level at every point inside the level's tets in a loaded sector, finitely from the coarse set everywhere
// else, and reports less memory after each unload. The sample's rooms scaled 5x (41 x 15 x 21 m) span
// several 16 m cells (12 sectors); occlusion is on, so its records are streamed too. About 1 s.
TEST_F(Cli, StreamedLevelAnswersLikeTheFullLevel) {
  write("big.scene.json",
        std::string("{\"mesh\": \"") + TETRAPROBE_SOURCE_DIR +
            "/samples/two_rooms/two_rooms.obj\", \"unit_scale\": 5, \"sky\": {\"radiance\": [0.2, "
            "0.2, 0.2]}}");
  const CliRun b = run("bake " + path("big.scene.json").string() + " -o " + path("full.tpb").string() +
                       " --spacing 4 --max-spacing 16 --samples 32 --noise 0 --probe-budget 0 --fill-holes 0 "
                       "--threads 2");
  ASSERT_EQ(b.code, 0) << b.err;
  tetraprobe::StreamingLevel refused;
  EXPECT_EQ(refused.open(path("full.tpb").string()).status, tetraprobe::LevelStatus::kCorrupt)
      << "a level without an index is refused";
  const CliRun s = run("stream " + path("full.tpb").string() + " -o " + path("streamed.tpb").string() +
                       " --coarse-spacing 12");
  ASSERT_EQ(s.code, 0) << s.err;

  tetraprobe::Level full;
  ASSERT_TRUE(tetraprobe::loadLevel(path("streamed.tpb").string(), full));
  ASSERT_FALSE(full.stream.empty());
  ASSERT_FALSE(full.occlusion.empty());
  const tetraprobe::ProbeQuery whole(full);
  tetraprobe::StreamingLevel st;
  const tetraprobe::LevelResult opened = st.open(path("streamed.tpb").string());
  ASSERT_TRUE(opened) << opened.message;
  ASSERT_GE(st.sectors().size(), 4u);

  // Points over the probes' bounds (a little beyond), random unit normals.
  glm::dvec3 lo(full.probes[0]), hi = lo;
  for (const glm::vec3& p : full.probes) {
    lo = glm::min(lo, glm::dvec3(p));
    hi = glm::max(hi, glm::dvec3(p));
  }
  std::mt19937_64 rng(14);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::vector<glm::dvec3> points;
  std::vector<glm::vec3> normals;
  for (int i = 0; i < 3000; ++i) {
    glm::dvec3 t(u(rng), u(rng), u(rng));
    points.push_back(full.origin + lo - 1.0 + t * (hi - lo + 2.0));
    glm::dvec3 n(u(rng) - 0.5, u(rng) - 0.5, u(rng) - 0.5);
    normals.push_back(glm::vec3(glm::normalize(n)));
  }
  auto same = [](const glm::vec3& a, const glm::vec3& b) { return std::memcmp(&a, &b, sizeof a) == 0; };

  // Nothing loaded: the coarse set answers, finite.
  const size_t idle = st.bytesInUse();
  for (size_t i = 0; i < points.size(); ++i) {
    ASSERT_FALSE(st.answersFromLoaded(points[i]));
    const glm::vec3 e = st.query(points[i], normals[i]);
    ASSERT_TRUE(std::isfinite(e.x) && std::isfinite(e.y) && std::isfinite(e.z)) << i;
  }
  // One sector at a time.
  size_t exact = 0;
  for (const tetraprobe::SectorKey& key : st.sectors()) {
    const tetraprobe::LevelResult r = st.load(key);
    ASSERT_TRUE(r) << r.message;
    const size_t inUse = st.bytesInUse();
    EXPECT_GT(inUse, idle);
    for (size_t i = 0; i < points.size(); ++i) {
      const glm::vec3 e = st.query(points[i], normals[i]);
      if (st.answersFromLoaded(points[i])) {
        EXPECT_TRUE(st.sectorOf(points[i]) == key);
        EXPECT_TRUE(same(e, whole.irradiance(points[i], normals[i])))
            << "point " << i << " in a loaded sector answers differently";
        ++exact;
      } else {
        ASSERT_TRUE(std::isfinite(e.x) && std::isfinite(e.y) && std::isfinite(e.z)) << i;
      }
    }
    st.unload(key);
    EXPECT_LT(st.bytesInUse(), inUse) << "unloading frees memory";
    EXPECT_EQ(st.bytesInUse(), idle);
  }
  // Every sector at once: the same answers again, and every point inside a tet of the level among them.
  size_t inside = 0, exactAll = 0;
  for (const tetraprobe::SectorKey& key : st.sectors()) ASSERT_TRUE(st.load(key));
  for (size_t i = 0; i < points.size(); ++i) {
    inside += whole.locate(points[i]).outerCell < 0;
    if (!st.answersFromLoaded(points[i])) continue;
    ++exactAll;
    EXPECT_TRUE(same(st.query(points[i], normals[i]), whole.irradiance(points[i], normals[i]))) << i;
  }
  EXPECT_EQ(exactAll, inside);
  EXPECT_EQ(exact, inside);
  EXPECT_GT(inside, points.size() / 2);

  // The GPU sector pool's CPU answers (no joined level): sized for two sectors, it loads them in pairs,
  // evicting the older, and answers as the full level wherever StreamingLevel with the same two sectors
  // answers from them; elsewhere finitely (the coarse set).
  {
    tetraprobe::StreamingLevel forPool, pair;
    ASSERT_TRUE(forPool.open(path("streamed.tpb").string()));
    ASSERT_TRUE(pair.open(path("streamed.tpb").string()));
    std::vector<tetraprobe::GpuSectorSizes> sizes;
    ASSERT_TRUE(tetraprobe::measureSectors(forPool, sizes));
    tetraprobe::GpuSectorPool pool;
    ASSERT_EQ(pool.init(forPool, tetraprobe::gpuPoolCapacityFor(sizes, 2)), "");
    size_t fromPool = 0;
    const std::vector<tetraprobe::SectorKey>& keys = forPool.sectors();
    for (size_t k = 0; k < keys.size(); ++k) {
      if (k >= 2) {
        pool.evict(keys[k - 2]);
        pair.unload(keys[k - 2]);
      }
      ASSERT_TRUE(pool.load(keys[k]));
      ASSERT_TRUE(pair.load(keys[k]));
      for (size_t i = 0; i < points.size(); ++i) {
        const glm::vec3 e = pool.irradiance(points[i], normals[i]);
        ASSERT_EQ(pool.answersFromLoaded(points[i]), pair.answersFromLoaded(points[i])) << k << " " << i;
        if (pool.answersFromLoaded(points[i])) {
          ++fromPool;
          EXPECT_TRUE(same(e, whole.irradiance(points[i], normals[i]))) << "pool, point " << i;
        } else {
          ASSERT_TRUE(std::isfinite(e.x) && std::isfinite(e.y) && std::isfinite(e.z)) << i;
        }
      }
    }
    EXPECT_GT(fromPool, inside) << "every point inside answered from the pool at least once";
  }

  // render --stream-window: the GPU lookup over a sector pool with the sectors nearest the target, its pixels
  // from loaded sectors equal to the full level's (the command checks and fails otherwise); a level without
  // an index is refused with one line.
  const std::string view = " --eye 10,40,10 --target 20,5,30 --size 64x36 -o " + path("s.png").string();
  const CliRun r = run("render " + path("big.scene.json").string() + " " + path("streamed.tpb").string() +
                       view + " --stream-window 3");
  if (tetraprobe::test::isNoVulkan(r.err)) TETRAPROBE_SKIP_MISSING(r.err);
  ASSERT_EQ(r.code, 0) << r.err;
  size_t loadedSectors = 0, pool = 0, loaded = 0, equal = 0, coarse = 0, total = 0;
  ASSERT_EQ(
      std::sscanf(r.out.c_str(),
                  "tetraprobe render: streamed: %zu of %zu sectors loaded into a %zu-byte GPU pool; %zu "
                  "geometry pixels from loaded sectors (%zu equal to the full level's), %zu from the "
                  "coarse set",
                  &loadedSectors, &total, &pool, &loaded, &equal, &coarse),
      6)
      << r.out;
  EXPECT_EQ(loadedSectors, 3u);
  EXPECT_GT(loaded, 100u);
  EXPECT_EQ(equal, loaded);
  const CliRun unindexed = run("render " + path("big.scene.json").string() + " " + path("full.tpb").string() +
                               view + " --stream-window 3");
  EXPECT_EQ(unindexed.code, 2);
  EXPECT_NE(unindexed.err.find("streaming index"), std::string::npos) << unindexed.err;
}

// A streamed level whose payload was edited and its CRC recomputed (so `open` accepts it) is still refused at
// `load` where `loadLevel` would refuse it: here an all-zero occlusion plane (no plane at all; validateLevel's
// last occlusion check), which only the sectors holding a tet that uses it read. Those sectors fail as
// kCorrupt naming the plane, leave nothing loaded, and the others still load and answer.
TEST_F(Cli, StreamedSectorWithZeroOcclusionPlaneIsCorrupt) {
  write("big.scene.json",
        std::string("{\"mesh\": \"") + TETRAPROBE_SOURCE_DIR +
            "/samples/two_rooms/two_rooms.obj\", \"unit_scale\": 5, \"sky\": {\"radiance\": [0.2, "
            "0.2, 0.2]}}");
  ASSERT_EQ(run("bake " + path("big.scene.json").string() + " -o " + path("full.tpb").string() +
                " --spacing 4 --max-spacing 16 --samples 8 --noise 0 --probe-budget 0 --fill-holes 0 "
                "--occlusion planes --threads 2")
                .code,
            0);
  const CliRun s = run("stream " + path("full.tpb").string() + " -o " + path("streamed.tpb").string());
  ASSERT_EQ(s.code, 0) << s.err;
  const std::string streamed = slurp(path("streamed.tpb"));
  tetraprobe::test::Bytes b(streamed.begin(), streamed.end());
  const size_t occl = tetraprobe::test::section(b, "OCCL");
  ASSERT_NE(occl, 0u);
  const uint64_t tets = tetraprobe::test::getU64(b, occl), planes = tetraprobe::test::getU64(b, occl + 8);
  ASSERT_GT(planes, 0u);
  std::memset(&b[occl + 24 + 8 * tets], 0, 8);  // plane 0: all four coefficients zero
  tetraprobe::test::fixChecksums(b);
  std::ofstream(path("forged.tpb"), std::ios::binary)
      .write(reinterpret_cast<const char*>(b.data()), std::streamsize(b.size()));

  tetraprobe::Level whole;
  EXPECT_EQ(tetraprobe::loadLevel(path("forged.tpb").string(), whole).status,
            tetraprobe::LevelStatus::kCorrupt);
  tetraprobe::StreamingLevel st;
  const tetraprobe::LevelResult opened = st.open(path("forged.tpb").string());
  ASSERT_TRUE(opened) << opened.message;
  const size_t idle = st.bytesInUse();
  size_t refused = 0, loaded = 0;
  for (const tetraprobe::SectorKey& key : st.sectors()) {
    const tetraprobe::LevelResult r = st.load(key);
    if (r) {
      ++loaded;
      st.unload(key);
      continue;
    }
    ++refused;
    EXPECT_EQ(r.status, tetraprobe::LevelStatus::kCorrupt) << r.message;
    EXPECT_NE(r.message.find("is zero (no plane)"), std::string::npos) << r.message;
    EXPECT_EQ(st.bytesInUse(), idle) << "a refused sector leaves nothing loaded";
  }
  EXPECT_GE(refused, 1u);
  EXPECT_GE(loaded, 1u);

  // The bake packed occlusion (OCC2) and tets (TETM); `stream` rewrote them as fixed records (OCCL, TETC),
  // which `load` seeks. A streamed file holding a packed section is refused at `open`, naming it.
  const std::string baked = slurp(path("full.tpb"));
  const auto refusedWhenPacked = [&](const char* fixed, const char* packed) {
    EXPECT_NE(tetraprobe::test::section(tetraprobe::test::Bytes(baked.begin(), baked.end()), packed), 0u);
    tetraprobe::test::Bytes p(streamed.begin(), streamed.end());
    for (uint32_t i = 0; i < tetraprobe::test::getU32(p, 72); ++i)
      if (std::memcmp(&p[80 + 24 * i], fixed, 4) == 0) std::memcpy(&p[80 + 24 * i], packed, 4);
    tetraprobe::test::fixChecksums(p);
    const fs::path file = path(std::string("packed_") + packed + ".tpb");
    std::ofstream(file, std::ios::binary)
        .write(reinterpret_cast<const char*>(p.data()), std::streamsize(p.size()));
    tetraprobe::StreamingLevel level;
    const tetraprobe::LevelResult r = level.open(file.string());
    EXPECT_EQ(r.status, tetraprobe::LevelStatus::kCorrupt) << packed;
    EXPECT_NE(r.message.find(packed), std::string::npos) << r.message;
  };
  refusedWhenPacked("OCCL", "OCC2");
  refusedWhenPacked("TETC", "TETM");
}

// The same input and options give a bit-identical level whatever the thread count, and the report has the
// documented keys.
TEST_F(Cli, BakeIsBitIdenticalAcrossThreadCountsAndReports) {
  write("box.obj", kBoxObj);
  write("box.mtl", kBoxMtl);
  const std::string base =
      "bake " + path("box.obj").string() +
      " --samples 32 --spacing 0.75 --max-samples 512 --path-budget 300000 --refine-points 256";
  const CliRun a =
      run(base + " --threads 1 -o " + path("a.tpb").string() + " --report " + path("a.json").string());
  ASSERT_EQ(a.code, 0) << a.err;
  const CliRun b = run(base + " --threads 2 -o " + path("b.tpb").string());
  ASSERT_EQ(b.code, 0) << b.err;
  const std::string ba = slurp(path("a.tpb")), bb = slurp(path("b.tpb"));
  ASSERT_FALSE(ba.empty());
  EXPECT_TRUE(ba == bb) << "level files differ between 1 and 2 threads";

  const auto j = nlohmann::json::parse(slurp(path("a.json")));
  EXPECT_GE(j.at("probes").at("count").get<int>(), 4);
  EXPECT_GE(j.at("tets").at("count").get<int>(), 1);
  EXPECT_GT(j.at("bytes").at("total").get<int64_t>(), 0);
  for (const char* stage : {"load", "place", "tetrahedralize", "bake", "write", "total"})
    EXPECT_TRUE(j.at("timings_s").contains(stage)) << stage;
  // Point location: a binary tree per cell has one node fewer than leaves; every tet is in a leaf, and a
  // leaf holds at most kDefaultLeafTets tets.
  const auto& loc = j.at("locate");
  EXPECT_EQ(loc.at("leaves").get<int64_t>(),
            loc.at("bsp_nodes").get<int64_t>() + loc.at("cells").get<int64_t>());
  EXPECT_GE(tetraprobe::kDefaultLeafTets * loc.at("leaves").get<int64_t>(),
            j.at("tets").at("count").get<int64_t>());
  EXPECT_EQ(loc.at("bytes").get<int64_t>(),
            16 * loc.at("hash_slots").get<int64_t>() + 24 * loc.at("bsp_nodes").get<int64_t>());

  const CliRun insp = run("inspect --json " + path("a.tpb").string());
  ASSERT_EQ(insp.code, 0) << insp.err;
  const auto ij = nlohmann::json::parse(insp.out);
  EXPECT_EQ(ij.at("probes").at("count"), j.at("probes").at("count"));
  EXPECT_EQ(ij.at("tets").at("count"), j.at("tets").at("count"));
}

// The path budget's pass runs once every probe is placed, so the hole and refinement probes share the budget
// with the probes placed first instead of stopping at the per-probe cap (when the first probes spent it all,
// the refinement probes here averaged 3.6x the surface probes' relative stderr, 0.220 against 0.061); the
// bake's noise figures cover every traced probe, by kind too (report and summary).
TEST_F(Cli, AddedProbesShareThePathBudgetWithTheFirst) {
  const CliRun r = run("bake " + sample() +
                       " --spacing 1 --samples 32 --max-samples 256 --path-budget 400000 --fill-holes 1"
                       " --probe-budget 64 --refine-points 256 --threads 2 -o " +
                       path("b.tpb").string() + " --report " + path("b.json").string());
  ASSERT_EQ(r.code, 0) << r.err;
  const auto j = nlohmann::json::parse(slurp(path("b.json")));
  const auto& noise = j.at("bake").at("noise");
  const auto& kinds = noise.at("by_kind");
  ASSERT_TRUE(kinds.contains("surface") && kinds.contains("refinement")) << kinds.dump();
  int64_t traced = 0;
  double sum = 0.0;
  for (const auto& [name, k] : kinds.items()) {
    traced += k.at("probes").get<int64_t>();
    sum += k.at("probes").get<double>() * k.at("mean_rel_stderr").get<double>();
  }
  const auto& probes = j.at("probes");
  EXPECT_EQ(traced, probes.at("count").get<int64_t>() - probes.at("dilated").get<int64_t>());
  EXPECT_NEAR(noise.at("mean_rel_stderr").get<double>(), sum / double(traced), 1e-9);
  const double surface = kinds.at("surface").at("mean_rel_stderr").get<double>();
  const double refinement = kinds.at("refinement").at("mean_rel_stderr").get<double>();
  EXPECT_LT(refinement, 2.0 * surface) << kinds.dump();
  EXPECT_LE(j.at("bake").at("paths").get<int64_t>(), 400000 + 256 * traced);
  // The summary says the same by kind.
  char line[128];
  std::snprintf(line, sizeof line, "refinement %.4f / %.4f (%lld)", refinement,
                kinds.at("refinement").at("p95_rel_stderr").get<double>(),
                (long long)kinds.at("refinement").at("probes").get<int64_t>());
  EXPECT_NE(r.out.find("by kind, mean / p95 (probes): "), std::string::npos) << r.out;
  EXPECT_NE(r.out.find(line), std::string::npos) << line << "\n" << r.out;
}

// Refinement's surface points grow with its probe budget and with the level's surface (--refine-points auto,
// autoRefinePoints): at least 2048, the budget where that is more, one point per spacing x spacing of surface
// where that is more still, so every part of a larger level is traced as densely as a room; a number given is
// used as is. The report and the generator string say which. The box's surface is 81 m^2 (walls, floor and
// ceiling 80, the light 1); scaled 6x it is 2,916 m^2, so 2,916 points at 1 m.
TEST_F(Cli, RefinePointsGrowWithTheProbeBudgetAndTheSurface) {
  write("box.obj", kBoxObj);
  write("box.mtl", kBoxMtl);
  const std::string base = "bake " + path("box.obj").string() +
                           " --samples 16 --spacing 1 --max-samples 16 --path-budget 100000 --fill-holes 0";
  auto refinePoints = [&](const std::string& extra) {
    const CliRun r =
        run(base + extra + " -o " + path("r.tpb").string() + " --report " + path("r.json").string());
    EXPECT_EQ(r.code, 0) << r.err;
    const auto j = nlohmann::json::parse(slurp(path("r.json")));
    return std::make_pair(j.at("refine").at("points").get<int>(), j.at("options").at("refine_points"));
  };
  const auto small = refinePoints(" --probe-budget 16");
  EXPECT_EQ(small.first, 2048);
  EXPECT_EQ(small.second, "auto");
  const auto large = refinePoints(" --probe-budget 3000");
  EXPECT_EQ(large.first, 3000);
  const auto given = refinePoints(" --probe-budget 3000 --refine-points 300");
  EXPECT_EQ(given.first, 300);
  EXPECT_EQ(given.second, 300);
  const CliRun insp = run("inspect " + path("r.tpb").string());
  EXPECT_NE(insp.out.find("--refine-points=300"), std::string::npos) << insp.out;
  EXPECT_EQ(run(base + " --refine-points 0 -o " + path("z.tpb").string()).code, 2);
  EXPECT_NEAR(nlohmann::json::parse(slurp(path("r.json"))).at("scene").at("surface_area_m2").get<double>(),
              81.0, 1e-9);

  write("big.scene.json", R"({"mesh": "box.obj", "unit_scale": 6})");
  const CliRun big = run("bake " + path("big.scene.json").string() +
                         " --samples 16 --spacing 1 --max-samples 16 --path-budget 100000 --fill-holes 0"
                         " --probe-budget 16 -o " +
                         path("big.tpb").string() + " --report " + path("big.json").string());
  ASSERT_EQ(big.code, 0) << big.err;
  const auto j = nlohmann::json::parse(slurp(path("big.json")));
  EXPECT_NEAR(j.at("scene").at("surface_area_m2").get<double>(), 36.0 * 81.0, 1e-6);
  EXPECT_EQ(j.at("refine").at("points").get<int>(), 2916);
}

// Query: below a ceiling light, a surface facing up (toward the light) receives much more than one facing
// down, the batch form agrees with the single form line by line, and --explain's probes give the answer.
// The late sliver pass (tetra/final_slivers.h) runs after the last probe is added: on the sample, the hole and
// refinement probes make tets flatter than any the filler left (--late-slivers keep shows it); with the bound
// at auto the shipped mesh's worst min dihedral is at least the worst before those probes (by default at least
// the smaller of that and 2 degrees), the report says what the pass did, and the level stays bit-identical
// across thread counts. The pass is off unless asked (--late-slivers fix).
TEST_F(Cli, FinalMeshIsNoWorseThanBeforeHoleAndRefinementProbes) {
  const std::string base = "bake " + sample() +
                           " --spacing 1 --samples 16 --noise 0 --fill-holes 1 --probe-budget 64"
                           " --refine-points 256";
  const auto bake = [&](const std::string& name, const std::string& extra) {
    const CliRun r = run(base + extra + " -o " + path(name + ".tpb").string() + " --report " +
                         path(name + ".json").string());
    EXPECT_EQ(r.code, 0) << r.err;
    return nlohmann::json::parse(slurp(path(name + ".json"))).at("tets");
  };
  const auto keep = bake("keep", " --threads 2");  // keep is the default
  const auto fix = bake("fix", " --late-slivers fix --late-min-dihedral auto --threads 1");
  const auto fix2 = bake("fix2", " --late-slivers fix --late-min-dihedral auto --threads 2");
  const auto byDefault = bake("default", " --late-slivers fix --threads 2");  // the bound's default
  if (HasFailure()) return;
  const double bound = fix.at("min_dihedral_deg_before_holes").get<double>();
  EXPECT_EQ(keep.at("min_dihedral_deg_before_holes").get<double>(), bound);
  ASSERT_LT(keep.at("min_dihedral_deg").get<double>(), bound)
      << "the late probes made no sliver here: the case tests nothing";
  EXPECT_FALSE(keep.at("late_pass").at("ran").get<bool>());
  const auto& late = fix.at("late_pass");
  EXPECT_TRUE(late.at("ran").get<bool>());
  EXPECT_EQ(late.at("min_dihedral_deg_before").get<double>(), keep.at("min_dihedral_deg").get<double>());
  EXPECT_EQ(late.at("bound_deg").get<double>(), bound);
  EXPECT_GE(fix.at("min_dihedral_deg").get<double>(), bound) << fix.dump();
  EXPECT_EQ(byDefault.at("late_pass").at("bound_deg").get<double>(), std::min(2.0, bound));
  EXPECT_GE(byDefault.at("min_dihedral_deg").get<double>(), std::min(2.0, bound)) << byDefault.dump();
  EXPECT_GT(late.at("probes_removed").get<int64_t>() + late.at("fillers_added").get<int64_t>(), 0);
  uint64_t tets = 0;
  for (const auto& c : fix.at("quality_histogram").at("min_dihedral")) tets += c.get<uint64_t>();
  EXPECT_EQ(tets, fix.at("count").get<uint64_t>()) << "the histogram is the final mesh's";
  EXPECT_TRUE(slurp(path("fix.tpb")) == slurp(path("fix2.tpb"))) << "1 and 2 threads differ";
}

TEST_F(Cli, QueryFacesTheLightAndBatchMatchesSingle) {
  write("box.obj", kBoxObj);
  write("box.mtl", kBoxMtl);
  ASSERT_EQ(
      run("bake " + path("box.obj").string() + " --samples 64 --noise 0 -o " + path("l.tpb").string()).code,
      0);
  const CliRun up = run("query " + path("l.tpb").string() + " 2 1.5 2 0 1 0");
  const CliRun down = run("query " + path("l.tpb").string() + " 2 1.5 2 0 -1 0");
  ASSERT_EQ(up.code, 0) << up.err;
  ASSERT_EQ(down.code, 0) << down.err;
  float ur, ug, ub, dr, dg, db;
  ASSERT_EQ(std::sscanf(up.out.c_str(), "%f,%f,%f", &ur, &ug, &ub), 3);
  ASSERT_EQ(std::sscanf(down.out.c_str(), "%f,%f,%f", &dr, &dg, &db), 3);
  EXPECT_GT(ug, 2.0f * dg) << "facing the ceiling light should see much more light";

  write("pts.csv", "2,1.5,2,0,1,0\n# comment\n2,1.5,2,0,-1,0\n");
  const CliRun batch = run("query " + path("l.tpb").string() + " --points " + path("pts.csv").string());
  ASSERT_EQ(batch.code, 0) << batch.err;
  EXPECT_EQ(batch.out, up.out + down.out);

  // --explain: the first line is the same answer; four probe rows whose weights (after occlusion) sum to
  // 1 and whose weighted irradiance is the answer (no fallback inside a closed box). Printed to 4 digits:
  // 1 % tolerance.
  const CliRun ex = run("query " + path("l.tpb").string() + " 2 1.5 2 0 1 0 --explain");
  ASSERT_EQ(ex.code, 0) << ex.err;
  EXPECT_EQ(ex.out.substr(0, up.out.size()), up.out);
  std::istringstream lines(ex.out);
  std::string line;
  int rows = 0;
  double weightSum = 0.0, blendG = 0.0;
  while (std::getline(lines, line)) {
    int probe;
    char pos[3][32];
    float dist, w, vis, after, er, eg, eb;
    if (std::sscanf(line.c_str(), " %d %31[^,], %31[^,], %31s %f %f %f %f %f, %f, %f", &probe, pos[0], pos[1],
                    pos[2], &dist, &w, &vis, &after, &er, &eg, &eb) == 11) {
      ++rows;
      weightSum += after;
      blendG += double(after) * eg;
    }
  }
  EXPECT_EQ(rows, 4) << ex.out;
  EXPECT_NEAR(weightSum, 1.0, 1e-3) << ex.out;
  EXPECT_NEAR(blendG, ug, 0.01 * ug) << ex.out;

  // --explain --scene: each probe row also says what rays from the point say. Inside the empty box every probe
  // is in the open, so each is "clear" or "back" (behind the floor-facing surface), never "hit".
  const CliRun rays =
      run("query " + path("l.tpb").string() + " 2 1.5 2 0 1 0 --explain --scene " + path("box.obj").string());
  ASSERT_EQ(rays.code, 0) << rays.err;
  EXPECT_NE(rays.out.find(" rays "), std::string::npos) << rays.out;
  size_t said = 0;
  for (const char* word : {" clear ", " back "})
    for (size_t at = rays.out.find(word); at != std::string::npos; at = rays.out.find(word, at + 1)) ++said;
  EXPECT_EQ(said, 4u) << rays.out;
  EXPECT_EQ(rays.out.find(" hit "), std::string::npos) << rays.out;

  write("bad.csv", "2,1.5,2,0,1\n");
  const CliRun bad = run("query " + path("l.tpb").string() + " --points " + path("bad.csv").string());
  EXPECT_EQ(bad.code, 2);
  EXPECT_NE(bad.err.find("bad.csv:1"), std::string::npos) << bad.err;
}

// The bundled sample: the lit room is much brighter than the room lit only through the doorway, and the
// room behind the doorway still gets some light.
TEST_F(Cli, SampleLitRoomBrighterThanDarkRoom) {
  ASSERT_EQ(run("bake " + sample() + " --samples 64 --noise 0 -o " + path("s.tpb").string()).code, 0);
  // Probe heights 1.5 m, facing up; room A is x in [0,4], room B x in [4.2,8.2], z in [0,4].
  const CliRun a = run("query " + path("s.tpb").string() + " 2 1.5 2 0 1 0");
  const CliRun b = run("query " + path("s.tpb").string() + " 7 1.5 2 0 1 0");
  ASSERT_EQ(a.code, 0) << a.err;
  float ar, ag, ab, br, bg, bb;
  ASSERT_EQ(std::sscanf(a.out.c_str(), "%f,%f,%f", &ar, &ag, &ab), 3);
  ASSERT_EQ(std::sscanf(b.out.c_str(), "%f,%f,%f", &br, &bg, &bb), 3);
  EXPECT_GT(ag, 3.0f * bg) << "lit room " << ag << " vs dark room " << bg;
  EXPECT_GT(bg, 0.0f) << "light reaches the dark room through the doorway";
}

// Shell probes: the bundled sample is closed under a black sky, so every shell probe sees the backs of its
// walls or nothing lit and is dilated; --shell-spacing 0 leaves them out. Either way the two faces of the
// partition wall, 0.2 m apart, do not share light: the dark room's face (x = 4.2, facing +x) gets a small
// fraction of the lit room's face (x = 4.0, facing -x) at the same height, away from the doorway (z 1.5-2.5).
// The dark face's light comes from one probe in the dark room, lit only through the doorway: with a fixed 64
// paths its noise alone can pass a quarter of the lit face (0.36 against 0.98 at z 3.4, where 1024 give 0.09),
// so the probes sample adaptively up to 1024 paths (the default's 8192 and path budget take seconds more).
TEST_F(Cli, ShellProbesAreDilatedAndThePartitionDoesNotLeak) {
  for (const std::string shell : {"auto", "0"}) {
    const std::string level = path("s" + shell + ".tpb").string(), report = path(shell + ".json").string();
    const CliRun bake =
        run("bake " + sample() +
            " --spacing 0.5 --samples 64 --max-samples 1024 --path-budget 0 --shell-spacing " + shell +
            " -o " + level + " --report " + report);
    ASSERT_EQ(bake.code, 0) << bake.err;
    const auto j = nlohmann::json::parse(slurp(report));
    const int shellProbes = j.at("probes").at("shell").get<int>();
    if (shell == "0") {
      EXPECT_EQ(shellProbes, 0);
    } else {
      EXPECT_GT(shellProbes, 100);
      EXPECT_EQ(j.at("probes").at("dilated").get<int>(), shellProbes);
    }
    for (const char* z : {"0.6", "3.4"}) {
      const CliRun lit = run("query " + level + " 4.0 1.2 " + z + " -1 0 0");
      const CliRun dark = run("query " + level + " 4.2 1.2 " + z + " 1 0 0");
      ASSERT_EQ(lit.code, 0) << lit.err;
      ASSERT_EQ(dark.code, 0) << dark.err;
      float lr, lg, lb, dr, dg, db;
      ASSERT_EQ(std::sscanf(lit.out.c_str(), "%f,%f,%f", &lr, &lg, &lb), 3);
      ASSERT_EQ(std::sscanf(dark.out.c_str(), "%f,%f,%f", &dr, &dg, &db), 3);
      EXPECT_LT(dg, 0.25f * lg) << "shell " << shell << " z " << z << ": dark face " << dg << ", lit face "
                                << lg;
    }
  }
}

// bench locate on a level with occlusion: every method (grid + BSP batch and single, cached and plain walks,
// CGAL's locate, brute force) gives the same answers, the BSP leaves name the answer's tet with one tet a leaf
// (--leaf-tets 1) and often with the default's small leaves, and the JSON has the documented keys with
// consistent values.
TEST_F(Cli, BenchLocateMethodsAgreeOnAnOccludedLevel) {
  const std::string level = path("b.tpb").string();
  const CliRun bake = run("bake " + sample() + " --spacing 0.5 --samples 16 --noise 0 -o " + level);
  ASSERT_EQ(bake.code, 0) << bake.err;
  for (const char* order : {"random", "coherent"}) {
    const CliRun b =
        run(std::string("bench locate ") + level + " --queries 20000 --threads 2 --json --order " + order +
            (std::string(order) == "random" ? " --leaf-tets 1" : ""));
    ASSERT_EQ(b.code, 0) << b.err;
    const auto j = nlohmann::json::parse(b.out);
    std::set<std::string> names;
    for (const auto& m : j.at("methods")) {
      names.insert(m.at("name").get<std::string>());
      EXPECT_EQ(m.at("mismatches").get<int64_t>(), 0) << order << ": " << m.at("name");
      EXPECT_GT(m.at("queries_per_s").get<double>(), 0.0);
    }
    for (const char* name :
         {"grid_bsp", "grid_bsp_single", "walk_cached", "walk", "cgal_fast_location", "cgal_hint", "brute"})
      EXPECT_TRUE(names.count(name)) << name;
    const auto& bsp = j.at("bsp");
    EXPECT_GE(bsp.at("leaf_tet_is_answer").get<double>(), std::string(order) == "random" ? 0.999 : 0.3);
    EXPECT_EQ(bsp.at("node_bytes").get<int>(), 24);
    EXPECT_GE(bsp.at("max_depth").get<double>(), bsp.at("mean_depth").get<double>());
    const double bytes = 16.0 * bsp.at("hash_slots").get<double>() + 24.0 * bsp.at("nodes").get<double>();
    EXPECT_NEAR(j.at("bytes_per_tet").get<double>(), bytes / j.at("tets").get<double>(), 1e-9);
  }
}

// SH exchange with an engine's own baker: export a level's probes, import them into a new bake with deringing
// off, and the new level's probes and SH are the same bytes (positions and coefficients survive the CSV
// exactly).
TEST_F(Cli, ExportThenImportShRoundTripsTheProbes) {
  write("box.obj", kBoxObj);
  write("box.mtl", kBoxMtl);
  ASSERT_EQ(run("bake " + path("box.obj").string() + " --samples 32 --noise 0 --dering none -o " +
                path("a.tpb").string())
                .code,
            0);
  const CliRun ex = run("export-sh " + path("a.tpb").string() + " -o " + path("sh.csv").string());
  ASSERT_EQ(ex.code, 0) << ex.err;
  const CliRun im = run("bake " + path("box.obj").string() + " --import-sh " + path("sh.csv").string() +
                        " --dering none -o " + path("b.tpb").string());
  ASSERT_EQ(im.code, 0) << im.err;
  const CliRun ex2 = run("export-sh " + path("b.tpb").string() + " -o " + path("sh2.csv").string());
  ASSERT_EQ(ex2.code, 0) << ex2.err;
  EXPECT_EQ(slurp(path("sh.csv")), slurp(path("sh2.csv")));
}

// The reference oracle is reproducible whatever the thread count, prints r,g,b plus standard errors per
// line, and below a ceiling light sees more light facing up than facing down.
TEST_F(Cli, ReferenceIsDeterministicAcrossThreadCounts) {
  write("box.obj", kBoxObj);
  write("box.mtl", kBoxMtl);
  write("pts.csv", "2,0.001,2,0,1,0\n2,2.9,2,0,-1,0\n0.001,1.5,2,1,0,0\n");
  const std::string base = "reference " + path("box.obj").string() + " --points " + path("pts.csv").string() +
                           " --rel-error 0.05 --max-samples 4096";
  const CliRun a = run(base + " --threads 1");
  const CliRun b = run(base + " --threads 2");
  ASSERT_EQ(a.code, 0) << a.err;
  EXPECT_EQ(a.out, b.out);
  EXPECT_EQ(lineCount(a.out), 3);
  float v[2][6];
  std::istringstream in(a.out);
  std::string line;
  for (int i = 0; i < 2 && std::getline(in, line); ++i)
    ASSERT_EQ(std::sscanf(line.c_str(), "%f,%f,%f,%f,%f,%f", &v[i][0], &v[i][1], &v[i][2], &v[i][3], &v[i][4],
                          &v[i][5]),
              6)
        << line;
  EXPECT_GT(v[0][1], v[1][1]) << "floor facing the light vs ceiling facing down";
}

namespace {

// Two sealed rooms split by a 0.1 m wall at x = 0: a bright ceiling panel on the left (x < 0), a dim one on
// the right, and on the right a free-standing panel at x = 1.5 (|z| < 1) in front of the wall. Faces point
// into the rooms; every box is closed. `safe`: also a sealed 1 m box on the left room's floor whose faces
// point into it, so that no light reaches its inside (a closed cavity: no path leaves).
std::string wallSceneObj(bool safe = false) {
  std::ostringstream o;
  int base = 0;
  // A box [lo, hi] with faces pointing out of it (solid) or into it (room).
  auto box = [&](double x0, double y0, double z0, double x1, double y1, double z1, const char* mtl,
                 bool room) {
    const double v[8][3] = {{x0, y0, z0}, {x1, y0, z0}, {x1, y1, z0}, {x0, y1, z0},
                            {x0, y0, z1}, {x1, y0, z1}, {x1, y1, z1}, {x0, y1, z1}};
    o << "usemtl " << mtl << "\n";
    for (const auto& p : v) o << "v " << p[0] << " " << p[1] << " " << p[2] << "\n";
    const int f[6][4] = {{0, 3, 2, 1}, {4, 5, 6, 7}, {0, 1, 5, 4}, {3, 7, 6, 2}, {0, 4, 7, 3}, {1, 2, 6, 5}};
    for (const auto& q : f) {
      if (room)
        o << "f " << base + q[3] + 1 << " " << base + q[2] + 1 << " " << base + q[1] + 1 << " "
          << base + q[0] + 1 << "\n";
      else
        o << "f " << base + q[0] + 1 << " " << base + q[1] + 1 << " " << base + q[2] + 1 << " "
          << base + q[3] + 1 << "\n";
    }
    base += 8;
  };
  o << "mtllib wall.mtl\n";
  box(-4, 0, -4, 4, 4, 4, "white", true);                // the room
  box(-0.05, 0, -4, 0.05, 4, 4, "white", false);         // the wall
  box(1.5, 0, -1, 1.55, 4, 1, "white", false);           // the panel in front of the wall, right side
  box(-3, 3.9, -1, -2, 3.95, 1, "bright", false);        // left light (its underside glows)
  box(2, 3.9, -1, 3, 3.95, 1, "dim", false);             // right light
  if (safe) box(-3, 0.5, 2, -2, 1.5, 3, "white", true);  // the sealed box, its faces inward
  return o.str();
}

}  // namespace

// The bake's final check counts apart the fallback points no path leaves: inside a sealed box (faces inward,
// no light inside) every point falls back, as its tet's probes are all outside, and 4,096 reference paths find
// no light there; the report's final_closed_fallback_points holds them and final_lookup_fallback_points the
// others. The same level without the box has no such point.
TEST_F(Cli, BakeCountsFallbackPointsNoPathLeavesApart) {
  write("wall.mtl",
        "newmtl white\nKd 0.7 0.7 0.7\nnewmtl bright\nKd 0 0 0\nKe 200 200 200\nnewmtl dim\nKd 0 0 0\nKe 5 5 "
        "5\n");
  std::ostringstream probes;
  for (double x : {-3.5, -0.6, 0.6, 3.5})
    for (double y : {0.25, 3.75})
      for (double z : {-3.5, 3.5}) probes << x << "," << y << "," << z << "\n";
  write("probes.csv", probes.str());
  int64_t closed[2] = {0, 0}, open[2] = {0, 0};
  for (const bool safe : {false, true}) {
    write("wall.obj", wallSceneObj(safe));
    const std::string report = path(safe ? "safe.json" : "nosafe.json").string();
    const CliRun bake = run(
        "bake " + path("wall.obj").string() + " --placement none --probes " + path("probes.csv").string() +
        " --samples 64 --noise 0 --fill-holes 0 --probe-budget 0 --fit off --threads 2 -o " +
        path("l.tpb").string() + " --report " + report);
    ASSERT_EQ(bake.code, 0) << bake.err;
    EXPECT_NE(bake.out.find("where no path leaves"), std::string::npos) << bake.out;
    const auto holes = nlohmann::json::parse(slurp(report)).at("holes");
    closed[safe] = holes.at("final_closed_fallback_points").get<int64_t>();
    open[safe] = holes.at("final_lookup_fallback_points").get<int64_t>();
  }
  EXPECT_EQ(closed[0], 0) << "no cavity, nothing closed";
  EXPECT_GT(closed[1], 20) << "the sealed box's inside: about 6 m^2 of some 300 m^2 of checked surface";
  EXPECT_LE(open[1], open[0] + 20) << "its points are not counted as open fallbacks";
}

// A point that sees none of its probes: the point on the wall's right face at (0.05, 2, 0) lies in a tet of
// three left-room probes and one right-room probe hidden behind the panel, so it sees none of its four probes.
// Two guards give it its own (dim) side's light. Without hole filling, the run-time fallback takes the nearest
// probe in front of the surface (occludedIrradiance; the nearest of all is a far-side probe): the right room's
// probe beyond the panel, so the dim room's light (below a third of the far side's) though not the gap's own
// (the gap behind the panel is darker still). With filling (occlusion_holes.h, the bake's --fill-holes) the bake
// adds a probe in the gap in front of the point: within 2x of the path-traced reference there.
TEST_F(Cli, PointSeeingNoneOfItsProbesGetsLightFromItsOwnSide) {
  write("wall.obj", wallSceneObj());
  write("wall.mtl",
        "newmtl white\nKd 0.7 0.7 0.7\nnewmtl bright\nKd 0 0 0\nKe 200 200 200\nnewmtl dim\nKd 0 0 0\nKe 5 5 "
        "5\n");
  write("probes.csv", "-1,1,-1\n-1,3,-1\n-1,2,1.5\n3,2,0\n");
  write("point.csv", "0.05,2,0,1,0,0\n-0.05,2,0,-1,0,0\n");
  const std::string common = path("wall.obj").string() + " --placement none --probes " +
                             path("probes.csv").string() +
                             " --occlusion shadow-maps --samples 512 --noise 0 --probe-budget 0 --threads 2";
  ASSERT_EQ(run("bake " + common + " --fill-holes 0 -o " + path("before.tpb").string() + " --report " +
                path("before.json").string())
                .code,
            0);
  const CliRun after = run("bake " + common + " --fill-holes 3 -o " + path("after.tpb").string() +
                           " --report " + path("after.json").string());
  ASSERT_EQ(after.code, 0) << after.err;
  const size_t plus = after.out.find('+', after.out.find("holes"));
  ASSERT_NE(plus, std::string::npos) << after.out;
  EXPECT_NE(after.out[plus + 1], '0') << "the first round must add probes: " << after.out;
  // The report's check of the finished level (a draw of surface points of its own): without filling some
  // surfaces fall back, and filling leaves fewer of them.
  const auto holesBefore = nlohmann::json::parse(slurp(path("before.json"))).at("holes");
  const auto holesAfter = nlohmann::json::parse(slurp(path("after.json"))).at("holes");
  const auto left = [](const nlohmann::json& h) { return h.at("final_hole_points").get<int64_t>(); };
  EXPECT_GT(holesBefore.at("final_points_checked").get<int64_t>(), 0);
  EXPECT_EQ(holesAfter.at("final_points_checked"), holesBefore.at("final_points_checked"));
  EXPECT_GT(left(holesBefore), 0);
  EXPECT_LT(left(holesAfter), left(holesBefore))
      << "hole filling leaves fewer surfaces falling back: " << holesBefore << " -> " << holesAfter;
  EXPECT_NE(after.out.find("fallback "), std::string::npos) << after.out;
  // The lookup's own count (after the face blend, which gives a point its neighbours' sight): on this wall
  // level it only ever takes points out of the fallback.
  const auto lookupLeft = [](const nlohmann::json& h) {
    return h.at("final_lookup_fallback_points").get<int64_t>();
  };
  EXPECT_LE(lookupLeft(holesBefore), left(holesBefore));
  EXPECT_LE(lookupLeft(holesAfter), left(holesAfter));

  auto lum = [](const std::string& line) {
    double r = 0, g = 0, b = 0;
    std::sscanf(line.c_str(), "%lf,%lf,%lf", &r, &g, &b);
    return tetraprobe::luminance(glm::dvec3(r, g, b));
  };
  const CliRun ref = run("reference " + path("wall.obj").string() + " --points " +
                         path("point.csv").string() + " --rel-error 0.02");
  ASSERT_EQ(ref.code, 0) << ref.err;
  std::istringstream lines(ref.out);
  std::string own, far;
  std::getline(lines, own);
  std::getline(lines, far);
  const double ownRef = lum(own), farRef = lum(far);
  ASSERT_GT(farRef, 5.0 * ownRef) << "the far side must be much brighter for the test to tell them apart";
  ASSERT_GT(ownRef, 0.0);

  const CliRun before = run("query " + path("before.tpb").string() + " 0.05 2 0 1 0 0");
  const CliRun filled = run("query " + path("after.tpb").string() + " 0.05 2 0 1 0 0");
  ASSERT_EQ(before.code, 0);
  ASSERT_EQ(filled.code, 0);
  EXPECT_GT(lum(before.out), 0.5 * ownRef) << before.out;
  EXPECT_LT(lum(before.out), farRef / 3.0) << "the fallback took far-side light: " << before.out;
  EXPECT_GT(lum(filled.out), 0.5 * ownRef) << filled.out;
  EXPECT_LT(lum(filled.out), 2.0 * ownRef) << filled.out;
  EXPECT_LT(lum(filled.out), farRef / 3.0) << filled.out;

  // --hole-rule unseen leaves alone only hole points whose fallback probe a ray reaches; this point's (the
  // right room's probe beyond the panel) is hidden, so it still gets its probe and its own side's light.
  ASSERT_EQ(run("bake " + common + " --fill-holes 3 --hole-rule unseen -o " + path("unseen.tpb").string() +
                " --report " + path("unseen.json").string())
                .code,
            0);
  const auto rounds = nlohmann::json::parse(slurp(path("unseen.json"))).at("holes").at("rounds");
  ASSERT_FALSE(rounds.empty());
  EXPECT_GT(rounds[0].at("probes_added").get<int64_t>(), 0);
  EXPECT_LT(rounds[0].at("fallback_probe_seen").get<int64_t>(), rounds[0].at("hole_points").get<int64_t>());
  const CliRun unseen = run("query " + path("unseen.tpb").string() + " 0.05 2 0 1 0 0");
  ASSERT_EQ(unseen.code, 0);
  EXPECT_GT(lum(unseen.out), 0.5 * ownRef) << unseen.out;
  EXPECT_LT(lum(unseen.out), 2.0 * ownRef) << unseen.out;
  EXPECT_NE(run("bake " + common + " --hole-rule some -o " + path("x.tpb").string()).code, 0);
}

// render --mode reference / error: traced on the CPU (no Vulkan needed), the error mode prints the gross
// and dark-hole fractions on one line and writes them as JSON; .exr holds the values. The traced-only
// options are refused in the Vulkan modes, and --exposure in the error mode (its scale is fixed).
TEST_F(Cli, RenderReferenceAndErrorModesWriteImagesAndFigures) {
  write("box.obj", kBoxObj);
  write("box.mtl", kBoxMtl);
  const std::string level = path("box.tpb").string();
  ASSERT_EQ(run("bake " + path("box.obj").string() + " --samples 32 --noise 0 -o " + level).code, 0);
  const std::string base = "render " + path("box.obj").string() + " " + level +
                           " --eye 3.5,1.5,3.5 --target 1,1,1 --size 32x24 --samples 8 --threads 2";
  const CliRun ref = run(base + " --mode reference -o " + path("ref.png").string());
  ASSERT_EQ(ref.code, 0) << ref.err;
  EXPECT_TRUE(fs::file_size(path("ref.png")) > 0);
  EXPECT_NE(ref.out.find("8 paths per pixel"), std::string::npos) << ref.out;

  const CliRun err =
      run(base + " --mode error -o " + path("err.png").string() + " --json " + path("err.json").string());
  ASSERT_EQ(err.code, 0) << err.err;
  EXPECT_TRUE(fs::file_size(path("err.png")) > 0);
  EXPECT_NE(err.out.find("gross (off by > 2x)"), std::string::npos) << err.out;
  EXPECT_NE(err.out.find("dark holes (< 0.25x)"), std::string::npos) << err.out;
  const auto j = nlohmann::json::parse(slurp(path("err.json")));
  EXPECT_EQ(j.at("samples_per_pixel").get<int>(), 8);
  EXPECT_EQ(j.at("bounces").get<std::string>(), "unbounded");
  EXPECT_EQ(j.at("hit_pixels").get<int>(), 32 * 24) << "the camera is inside the closed box";
  for (const char* key : {"gross_fraction", "dark_hole_fraction", "too_bright_fraction", "too_dark_fraction",
                          "mean_log2_ratio"}) {
    const double v = j.at("error").at(key).get<double>();
    EXPECT_TRUE(std::isfinite(v)) << key;
  }
  EXPECT_GE(j.at("error").at("gross_fraction").get<double>(),
            j.at("error").at("dark_hole_fraction").get<double>());

  ASSERT_EQ(run(base + " --mode error -o " + path("err.exr").string()).code, 0);
  EXPECT_TRUE(fs::file_size(path("err.exr")) > 0);

  const std::string vk = "render " + path("box.obj").string() + " " + level + " -o " + path("x.png").string();
  for (const std::string& bad :
       {vk + " --mode irradiance --samples 8", vk + " --mode error --frames 3",
        vk + " --mode error --exposure 2", vk + " --mode error --bounces two",
        vk + " --mode error --samples 0", vk + " --mode probes --exposure 2",
        vk + " --mode indirect --shadow-map-size 256", vk + " --mode full --shadow-map-size 8",
        vk + " --mode full --frames 0", vk + " --mode wireframe"}) {
    const CliRun r = run(bad);
    EXPECT_EQ(r.code, 2) << bad << "\n" << r.err;
    EXPECT_EQ(lineCount(r.err), 1) << bad << "\n" << r.err;
  }
}

// The Vulkan modes: full (the scene JSON adds a point light to the box), the three debug views, and --json
// with the GPU time of every pass (median of --frames frames after 2 warm-up frames). The bake records probe
// kinds, which inspect counts.
TEST_F(Cli, RenderFullAndDebugModesWriteImagesAndPassTimings) {
  write("box.obj", kBoxObj);
  write("box.mtl", kBoxMtl);
  write("lit.scene.json", R"({"mesh": "box.obj", "lights": [{"type": "point", "position": [1, 2, 1],
                               "intensity": [5, 5, 5]}]})");
  const std::string level = path("box.tpb").string();
  ASSERT_EQ(run("bake " + path("lit.scene.json").string() + " --samples 32 --noise 0 -o " + level).code, 0);
  const CliRun inspect = run("inspect " + level + " --json");
  ASSERT_EQ(inspect.code, 0) << inspect.err;
  const auto kinds = nlohmann::json::parse(inspect.out).at("probes").at("kinds");
  EXPECT_GT(kinds.value("surface", 0), 0) << kinds.dump();
  EXPECT_GT(kinds.value("shell", 0) + kinds.value("dilated", 0), 0) << kinds.dump();

  const std::string base = "render " + path("lit.scene.json").string() + " " + level +
                           " --eye 3.5,1.5,3.5 --target 1,1,1 --size 32x24";
  const CliRun full = run(base + " --mode full -o " + path("full.png").string() + " --frames 3 --json " +
                          path("full.json").string() + " --shadow-map-size 256");
  if (tetraprobe::test::isNoVulkan(full.err)) TETRAPROBE_SKIP_MISSING(full.err);
  ASSERT_EQ(full.code, 0) << full.err;
  EXPECT_TRUE(fs::file_size(path("full.png")) > 0);
  const auto j = nlohmann::json::parse(slurp(path("full.json")));
  EXPECT_EQ(j.at("mode").get<std::string>(), "full");
  EXPECT_EQ(j.at("lights").get<int>(), 1);
  EXPECT_EQ(j.at("timed_frames").get<int>(), 3);
  EXPECT_EQ(j.at("warmup_frames").get<int>(), 2);
  for (const char* pass : {"shadow_maps", "gbuffer", "lighting", "direct"})
    EXPECT_GE(j.at("gpu_ms").at(pass).get<double>(), 0.0) << pass << "\n" << j.dump(2);
  for (const char* mode : {"probes", "tets", "occlusion"}) {
    const std::string png = path(std::string(mode) + ".png").string();
    const CliRun r = run(base + " --mode " + mode + " -o " + png);
    EXPECT_EQ(r.code, 0) << mode << "\n" << r.err;
    EXPECT_TRUE(fs::exists(png)) << mode;
  }
}

// bench render on the box (bakes in about a second without refinement) at 32x24: one JSON object with the documented keys, a
// lookup time for every variant that covers the level (its own, reported as `variant`, first), and the same
// variant in inspect --json and render --json.
TEST_F(Cli, BenchRenderPrintsLookupAmbientAndGridTimes) {
  write("box.obj", kBoxObj);
  write("box.mtl", kBoxMtl);
  const std::string level = path("box.tpb").string();
  ASSERT_EQ(
      run("bake " + path("box.obj").string() + " --spacing 1 --samples 16 --probe-budget 0 -o " + level).code,
      0);
  const std::string view = " --eye 3.5,1.5,3.5 --target 1,1,1 --size 32x24";
  const CliRun b =
      run("bench render " + path("box.obj").string() + " " + level + view + " --frames 2 --json");
  if (tetraprobe::test::isNoVulkan(b.err)) TETRAPROBE_SKIP_MISSING(b.err);
  ASSERT_EQ(b.code, 0) << b.err;
  const auto j = nlohmann::json::parse(b.out);
  EXPECT_EQ(j.at("width").get<int>(), 32);
  EXPECT_EQ(j.at("height").get<int>(), 24);
  EXPECT_FALSE(j.at("device").get<std::string>().empty());
  const std::string variant = j.at("variant").get<std::string>();
  const auto& lookup = j.at("lookup_ms");
  EXPECT_GE(lookup.at("chosen").get<double>(), 0.0);
  EXPECT_EQ(lookup.at("chosen").get<double>(), lookup.at(variant).get<double>());
  EXPECT_GE(lookup.at("l2+planes+shadow_maps+outer+cells").get<double>(), 0.0) << "the generic variant";
  EXPECT_GE(j.at("ambient_ms").get<double>(), 0.0);
  EXPECT_GE(j.at("grid_ms").get<double>(), 0.0);
  EXPECT_GT(j.at("grid").at("texture_bytes").get<double>(), 0.0);
  EXPECT_LE(j.at("grid").at("bytes").get<double>(), j.at("tet_lookup_bytes").get<double>());
  EXPECT_TRUE(j.at("goal_met").is_boolean());
  // The half-resolution lookup: its three passes, pixel shares that add up to every geometry pixel, and its
  // difference from the full pass.
  const auto& half = j.at("half_resolution");
  EXPECT_NEAR(half.at("total_ms").get<double>(),
              half.at("lookup_half_ms").get<double>() + half.at("upsample_ms").get<double>() +
                  half.at("lookup_edges_ms").get<double>(),
              1e-9);
  EXPECT_NEAR(half.at("pixels_interpolated").get<double>() + half.at("pixels_own_lookup").get<double>() +
                  half.at("pixels_full_lookup").get<double>(),
              1.0, 1e-9);
  EXPECT_GE(half.at("pixels_own_lookup").get<double>(), 0.25)
      << "a block's representative: 1 pixel in 4 or more";
  EXPECT_GE(half.at("error_vs_full").at("mean_rel").get<double>(), 0.0);
  EXPECT_LT(half.at("error_vs_full").at("mean_rel").get<double>(), 0.05);
  // The temporal start over the default path: the cold lookup's answer, most pixels' last tets still right.
  const auto& temporal = j.at("temporal");
  EXPECT_EQ(temporal.at("frames").get<int>(), 4);
  EXPECT_LE(temporal.at("max_rel_difference_to_cold").get<double>(), 1e-4);
  EXPECT_GT(temporal.at("pixels_held_by_previous_tet").get<double>(), 0.5);
  EXPECT_GT(temporal.at("temporal_ms").get<double>(), 0.0);

  const CliRun inspect = run("inspect " + level + " --json");
  ASSERT_EQ(inspect.code, 0) << inspect.err;
  EXPECT_EQ(nlohmann::json::parse(inspect.out).at("shader_variant").get<std::string>(), variant);
  const CliRun render =
      run("render " + path("box.obj").string() + " " + level + view + " --mode irradiance -o " +
          path("r.png").string() + " --frames 1 --json " + path("r.json").string());
  ASSERT_EQ(render.code, 0) << render.err;
  EXPECT_EQ(nlohmann::json::parse(slurp(path("r.json"))).at("variant").get<std::string>(), variant);
  EXPECT_EQ(run("bench render " + path("box.obj").string() + " " + level + " --also l3").code, 2);
  // render --half-res writes the upsampled image; it has no meaning for the debug views.
  const CliRun halfRender = run("render " + path("box.obj").string() + " " + level + view +
                                " --mode indirect --half-res -o " + path("h.png").string());
  ASSERT_EQ(halfRender.code, 0) << halfRender.err;
  EXPECT_NE(halfRender.out.find("upsample"), std::string::npos) << halfRender.out;
  EXPECT_TRUE(fs::exists(path("h.png")));
  EXPECT_EQ(run("render " + path("box.obj").string() + " " + level + view + " --mode tets --half-res -o " +
                path("t.png").string())
                .code,
            2);
}

// eval scores every method on the same points, the grid included, and writes the Markdown table, the SVG plot
// and the JSON keys the docs name (the box bakes in well under a second; the grid at the probe count is
// small, and --samples 16 keeps the bake and the reference cheap).
TEST_F(Cli, EvalWritesGridMethodsMarkdownPlotAndTimingKeys) {
  bakeBox();
  if (HasFatalFailure()) return;
  const CliRun r = run("eval " + path("box.obj").string() + " " + path("l.tpb").string() +
                       " --points 32 --samples 16 --grid both --grid-offsets 2 --gpu none --timing-size "
                       "32x18 --markdown --plot " +
                       path("p.svg").string() + " --report " + path("e.json").string());
  ASSERT_EQ(r.code, 0) << r.err;
  for (const char* name : {"| tet |", "| nearest |", "| grid (equal bytes) |", "| grid (probe count) |",
                           "| grid (equal bytes, offset 1/2) |"})
    EXPECT_NE(r.out.find(name), std::string::npos) << "no row " << name << " in\n" << r.out;
  // The offset lattice has the equal-bytes grid's spacing and one node more per axis (the notes name both).
  int dims[2][3] = {};
  double step[2] = {0.0, 0.0};
  const auto report = nlohmann::json::parse(slurp(path("e.json")));
  const std::string prefixes[2] = {"grid (equal bytes): ", "grid (equal bytes, offset 1/2): "};
  for (const auto& note : report.at("grid_notes")) {
    const std::string s = note.get<std::string>();
    for (int k = 0; k < 2; ++k)
      if (s.rfind(prefixes[k], 0) == 0) {
        EXPECT_EQ(std::sscanf(s.c_str() + prefixes[k].size(), "%dx%dx%d nodes of %lf", &dims[k][0],
                              &dims[k][1], &dims[k][2], &step[k]),
                  4)
            << s;
      }
  }
  for (int a = 0; a < 3; ++a) EXPECT_EQ(dims[1][a], dims[0][a] + 1) << a;
  EXPECT_GT(step[0], 0.0);
  EXPECT_EQ(step[1], step[0]);
  const std::string svg = slurp(path("p.svg"));
  EXPECT_EQ(svg.rfind("<?xml", 0), 0u);
  EXPECT_NE(svg.find("<svg "), std::string::npos);
  EXPECT_NE(svg.find("</svg>"), std::string::npos);
  // The grid's series is drawn: its colour 0xe7298a as cairo writes a fill (the text is glyph outlines).
  EXPECT_NE(svg.find("fill:rgb(90.588235%,16.078431%,54.117647%)"), std::string::npos);
  const std::string json = slurp(path("e.json"));
  for (const char* key :
       {"\"cpu_ns_per_query\"", "\"cpu_ns_per_query_coherent\"", "\"cpu_ns_per_query_random\"", "\"threads\"",
        "\"gpu_ms\"", "\"bytes_sections\"", "\"start_bricks\"", "\"outer_cells\"", "\"bytes_per_probe\""})
    EXPECT_NE(json.find(key), std::string::npos) << "no key " << key;
  // The fallback share (a number for the tet lookup, null for methods without one), the former relative
  // errors and the points no path leaves, reported apart (docs/evaluation.md).
  const auto& methods = report.at("methods");
  ASSERT_EQ(methods.at(0).at("name"), "tet");
  EXPECT_TRUE(methods.at(0).at("fallback").is_number());
  for (const auto& m : methods) {
    for (const char* key : {"mean_rel_abs_floor", "relmse_abs_floor", "p95_rel_abs_floor"})
      EXPECT_TRUE(m.at(key).is_number()) << key;
    EXPECT_EQ(m.at("closed_mean_irradiance").size(), 3u);
    if (m.at("name") == "nearest") {
      EXPECT_TRUE(m.at("fallback").is_null());
    }
  }
  EXPECT_TRUE(report.at("reference").at("closed_points").is_number_unsigned());
  EXPECT_GT(report.at("reference").at("rel_floor").get<double>(), 0.0);
  EXPECT_NE(r.out.find("| fallback |"), std::string::npos) << "no fallback column in\n" << r.out;
}

// --plot FILE.png writes the same chart as a PNG (1840 pixels wide: 2 per SVG unit) that reads back; a name
// ending in neither .svg nor .png is refused before any work (exit 2, naming the file), writing nothing.
TEST_F(Cli, EvalPlotsPngByTheNamesEndingAndRefusesOtherNames) {
  bakeBox();
  if (HasFatalFailure()) return;
  const std::string base = "eval " + path("box.obj").string() + " " + path("l.tpb").string() +
                           " --points 16 --samples 8 --grid none --gpu none --timing-size 16x9 --plot ";
  const CliRun png = run(base + path("p.PNG").string());
  ASSERT_EQ(png.code, 0) << png.err;
  const tetraprobe::cli::Rgb8Image im = tetraprobe::cli::readImage8(path("p.PNG").string());
  EXPECT_EQ(im.width, 1840);
  EXPECT_GT(im.height, 600);
  const CliRun bad = run(base + path("p.txt").string());
  EXPECT_EQ(bad.code, 2);
  EXPECT_NE(bad.err.find("p.txt"), std::string::npos) << bad.err;
  EXPECT_FALSE(fs::exists(path("p.txt")));
}

// --reference-in scores against the references an earlier --points-out wrote: the same figures as the run that
// traced them (the CSV's 7 digits change no reported digit here), and a file drawn with another seed is
// refused (exit 2, naming the mismatch) rather than scored against the wrong points.
TEST_F(Cli, EvalReferenceInReproducesTheTracedRunAndRefusesOtherPoints) {
  bakeBox();
  if (HasFatalFailure()) return;
  const std::string base = "eval " + path("box.obj").string() + " " + path("l.tpb").string() +
                           " --points 32 --samples 16 --grid none --gpu none --timing-size 16x9";
  const CliRun traced = run(base + " --points-out " + path("pts.csv").string());
  ASSERT_EQ(traced.code, 0) << traced.err;
  const CliRun reused = run(base + " --reference-in " + path("pts.csv").string());
  ASSERT_EQ(reused.code, 0) << reused.err;
  // The method rows (name + the error columns) must agree; the timing columns differ run to run.
  auto errorColumns = [](const std::string& out, const std::string& method) {
    const size_t at = out.find("\n  " + method + " ");
    return at == std::string::npos ? std::string() : out.substr(at, 70);
  };
  for (const char* m : {"tet", "nearest"}) {
    EXPECT_FALSE(errorColumns(traced.out, m).empty()) << m << "\n" << traced.out;
    EXPECT_EQ(errorColumns(traced.out, m), errorColumns(reused.out, m)) << m;
  }
  const CliRun other = run(base + " --seed 7 --reference-in " + path("pts.csv").string());
  EXPECT_EQ(other.code, 2);
  EXPECT_NE(other.err.find("reference point"), std::string::npos) << other.err;
}

// ---- One source of truth for the bake's options: the generator string, --options-from, --probes, --seed ----

namespace {

std::string generatorOf(const CliRun& inspectJson) {
  return nlohmann::json::parse(inspectJson.out).at("generator").get<std::string>();
}

}  // namespace

// A placed, traced, one-machine level records every option that changes it in its generator string (no path,
// no thread count), and baking the same scene from that string alone gives the same file byte for byte, for
// any thread count; options given next to --options-from override the recorded ones.
TEST_F(Cli, LevelRebakesFromItsOwnGeneratorByteForByte) {
  write("box.obj", kBoxObj);
  write("box.mtl", kBoxMtl);
  // The defaults but for cheaper sampling (every stage runs: holes, refinement at an automatic budget), and
  // numbers whose text must come back exactly.
  const CliRun a =
      run("bake " + path("box.obj").string() + " -o " + path("a.tpb").string() +
          " --samples 32 --max-samples 512 --path-budget 300000 --refine-points 256 --spacing 0.7"
          " --dering 0.3 --min-agreement 0.97 --seed 18446744073709551615 --threads 2");
  ASSERT_EQ(a.code, 0) << a.err;
  const CliRun info = run("inspect --json " + path("a.tpb").string());
  ASSERT_EQ(info.code, 0) << info.err;
  const std::string generator = generatorOf(info);
  for (const char* item :
       {"--spacing=0.7 ", "--samples=32 ", "--noise=0.02 ", "--path-budget=300000 ",
        "--seed=18446744073709551615 ", "--dering=0.3 ", "--min-agreement=0.97 ", "--fill-holes=3 ",
        "--probe-budget=auto ", "--refine-points=256 ", "--max-spacing=10 ", "--filler-spacing=4 ",
        "--shell-spacing=auto ", "--refine-offset=auto ", "--fit=auto ", "--fit-lambda=0.3 ",
        "--fit-max-move=0.3 ", "--fit-points=auto "})
    EXPECT_NE(generator.find(item), std::string::npos) << item << " missing from: " << generator;
  EXPECT_EQ(generator.find("thread"), std::string::npos) << generator;
  EXPECT_EQ(generator.find(dir_.string()), std::string::npos) << "a path in the generator: " << generator;
  EXPECT_EQ(generator.find("box.obj"), std::string::npos) << generator;

  const CliRun b = run("bake " + path("box.obj").string() + " --options-from " + path("a.tpb").string() +
                       " -o " + path("b.tpb").string() + " --threads 1");
  ASSERT_EQ(b.code, 0) << b.err;
  const std::string ba = slurp(path("a.tpb")), bb = slurp(path("b.tpb"));
  ASSERT_FALSE(ba.empty());
  EXPECT_TRUE(ba == bb) << "the re-bake from the generator differs from the level";

  const CliRun c = run("bake " + path("box.obj").string() + " --options-from " + path("a.tpb").string() +
                       " --seed 5 --fill-holes 0 --probe-budget 0 -o " + path("c.tpb").string());
  ASSERT_EQ(c.code, 0) << c.err;
  const std::string overridden = generatorOf(run("inspect --json " + path("c.tpb").string()));
  EXPECT_NE(overridden.find("--seed=5 "), std::string::npos) << overridden;
  EXPECT_NE(overridden.find("--samples=32 "), std::string::npos) << overridden;
  EXPECT_NE(slurp(path("c.tpb")), ba);
}

// A level whose generator string predates the option list (";"-separated items under other names) reads as
// the options it records, the rest at today's defaults but for the path budget, which such levels did not
// have: --options-from bakes what the same options given by hand bake.
TEST_F(Cli, EarlierGeneratorStringReadsAsTheOptionsItRecords) {
  bakeBox();
  if (HasFatalFailure()) return;
  tetraprobe::Level level;
  ASSERT_TRUE(tetraprobe::loadLevel(path("l.tpb").string(), level));
  level.generator =
      "tetraprobe 0.1.0 bake; placement=voxel; tetra=cgal; spacing=0.75; shell_spacing=0.75; "
      "bounces=1048576; "
      "samples=16; target_error=0; max_samples=8192; content=default; seed=7; sh_order=2; dering=auto; "
      "occlusion=auto; hole_rounds=1; min_agreement=0.98";
  ASSERT_TRUE(tetraprobe::saveLevel(path("old.tpb").string(), level));
  const CliRun from = run("bake " + path("box.obj").string() + " --options-from " + path("old.tpb").string() +
                          " --refine-points 256 -o " + path("from.tpb").string());
  ASSERT_EQ(from.code, 0) << from.err;
  const CliRun byHand = run("bake " + path("box.obj").string() +
                            " --spacing 0.75 --samples 16 --noise 0 --seed 7 --fill-holes 1 --path-budget 0"
                            " --refine-points 256 -o " +
                            path("hand.tpb").string());
  ASSERT_EQ(byHand.code, 0) << byHand.err;
  EXPECT_TRUE(slurp(path("from.tpb")) == slurp(path("hand.tpb")))
      << generatorOf(run("inspect --json " + path("from.tpb").string())) << "\nvs\n"
      << generatorOf(run("inspect --json " + path("hand.tpb").string()));
  // A level that records no option cannot give them.
  level.generator = "imported by hand";
  ASSERT_TRUE(tetraprobe::saveLevel(path("bare.tpb").string(), level));
  const CliRun bare = run("bake " + path("box.obj").string() + " --options-from " +
                          path("bare.tpb").string() + " -o " + path("x.tpb").string());
  EXPECT_EQ(bare.code, 2);
  EXPECT_EQ(lineCount(bare.err), 1) << bare.err;
  EXPECT_FALSE(fs::exists(path("x.tpb")));
}

// `bake --probes FILE` alone: the file's probes are the level's probes. 60 probes in a room split by a wall,
// 56 of them on the left: the wall's right face sees none of its tets' probes, yet no hole probe or
// refinement probe is added unless asked; --fill-holes 3 and --probe-budget N opt in and add probes. A level
// baked from a probe file records the file's name and --options-from wants the file again.
TEST_F(Cli, UserProbesAloneAreTheLevelsOnlyProbesUnlessFillingIsAsked) {
  write("wall.obj", wallSceneObj());
  write("wall.mtl",
        "newmtl white\nKd 0.7 0.7 0.7\nnewmtl bright\nKd 0 0 0\nKe 200 200 200\nnewmtl dim\nKd 0 0 0\nKe 5 5 "
        "5\n");
  std::ostringstream csv;
  csv << "-1,1,-1\n-1,3,-1\n-1,2,1.5\n3,2,0\n";  // PointSeeingNoneOfItsProbes...'s four probes
  int count = 4;
  for (int i = 0; i < 4; ++i)
    for (int j = 0; j < 2; ++j)
      for (int k = 0; k < 7; ++k, ++count)
        csv << -3.5 + 0.8 * i << "," << 0.7 + 2.6 * j << "," << -3.3 + k << "\n";
  ASSERT_EQ(count, 60);
  write("probes.csv", csv.str());
  const std::string common = "bake " + path("wall.obj").string() + " --probes " +
                             path("probes.csv").string() +
                             " --samples 64 --noise 0 --refine-points 256 --threads 2";
  auto probes = [&](const std::string& level) {
    const CliRun info = run("inspect --json " + path(level).string());
    EXPECT_EQ(info.code, 0) << info.err;
    return nlohmann::json::parse(info.out).at("probes").at("count").get<int>();
  };

  const CliRun alone = run(common + " -o " + path("alone.tpb").string());
  ASSERT_EQ(alone.code, 0) << alone.err;
  EXPECT_EQ(probes("alone.tpb"), 60) << alone.out;
  const std::string generator = generatorOf(run("inspect --json " + path("alone.tpb").string()));
  EXPECT_NE(generator.find("--probes=probes.csv --placement=none "), std::string::npos) << generator;
  EXPECT_NE(generator.find("--fill-holes=0 "), std::string::npos) << generator;
  EXPECT_NE(generator.find("--probe-budget=0 "), std::string::npos) << generator;

  const CliRun holes = run(common + " --fill-holes 3 -o " + path("holes.tpb").string());
  ASSERT_EQ(holes.code, 0) << holes.err;
  EXPECT_GT(probes("holes.tpb"), 60) << holes.out;
  const CliRun refined = run(common + " --probe-budget 16 -o " + path("refined.tpb").string());
  ASSERT_EQ(refined.code, 0) << refined.err;
  EXPECT_GT(probes("refined.tpb"), 60) << refined.out;
  EXPECT_LE(probes("refined.tpb"), 60 + 16) << refined.out;

  // --options-from: the probe file is given again (any path), or the bake refuses.
  const CliRun missing = run("bake " + path("wall.obj").string() + " --options-from " +
                             path("alone.tpb").string() + " -o " + path("x.tpb").string());
  EXPECT_EQ(missing.code, 2);
  EXPECT_NE(missing.err.find("--probes"), std::string::npos) << missing.err;
  EXPECT_FALSE(fs::exists(path("x.tpb")));
  const CliRun again =
      run("bake " + path("wall.obj").string() + " --options-from " + path("alone.tpb").string() +
          " --probes " + path("probes.csv").string() + " -o " + path("again.tpb").string());
  ASSERT_EQ(again.code, 0) << again.err;
  EXPECT_TRUE(slurp(path("again.tpb")) == slurp(path("alone.tpb")));
}

// --seed is an unsigned 64-bit integer: a sign, a fraction or a value past 2^64-1 is bad usage (exit 2, one
// line naming the option, no file), and 2^64-1 itself is a seed like any other.
TEST_F(Cli, SeedIsAnUnsigned64BitInteger) {
  write("box.obj", kBoxObj);
  write("box.mtl", kBoxMtl);
  const std::string base = "bake " + path("box.obj").string() +
                           " --samples 16 --noise 0 --fill-holes 0 --probe-budget 0 --threads 2 -o " +
                           path("l.tpb").string() + " --seed ";
  for (const char* bad : {"-1", "1.5", "18446744073709551616", "1e3", "+1", "0x10", ""}) {
    const CliRun r = run(base + "'" + bad + "'");
    EXPECT_EQ(r.code, 2) << bad << ": " << r.err;
    EXPECT_EQ(lineCount(r.err), 1) << r.err;
    EXPECT_NE(r.err.find("--seed"), std::string::npos) << r.err;
    EXPECT_FALSE(fs::exists(path("l.tpb"))) << bad;
  }
  const CliRun top = run(base + "18446744073709551615");
  ASSERT_EQ(top.code, 0) << top.err;
  EXPECT_NE(generatorOf(run("inspect --json " + path("l.tpb").string())).find("--seed=18446744073709551615 "),
            std::string::npos);
}

// `eval --sweep` re-bakes with the options the level records (pipelineOptionsFromGenerator), not with a
// library set of its own: at the level's own spacing the swept level is the level under test, so its tet
// row matches the level's to the byte and the last digit (here with a filler lattice, a max spacing and a
// path budget other than the defaults, none of which the sweep read before).
TEST_F(Cli, EvalSweepAtTheLevelsSpacingRebakesTheLevel) {
  write("box.obj", kBoxObj);
  write("box.mtl", kBoxMtl);
  const CliRun bake = run("bake " + path("box.obj").string() + " -o " + path("l.tpb").string() +
                          " --spacing 0.75 --max-spacing 1.5 --filler-spacing 1.5 --samples 16 --noise 0.05"
                          " --max-samples 256 --path-budget 50000 --refine-points 256 --seed 3 --threads 2");
  ASSERT_EQ(bake.code, 0) << bake.err;
  const CliRun eval =
      run("eval " + path("box.obj").string() + " " + path("l.tpb").string() +
          " --points 32 --samples 16 --grid none --gpu none --timing-size 16x9 --sweep spacing=0.75"
          " --threads 2 --report " +
          path("eval.json").string());
  ASSERT_EQ(eval.code, 0) << eval.err;
  const auto j = nlohmann::json::parse(slurp(path("eval.json")));
  const auto& tet = j.at("methods").at(0);
  ASSERT_EQ(j.at("sweep").size(), 1u);
  const auto& swept = j.at("sweep").at(0).at("methods").at(0);
  ASSERT_EQ(tet.at("name"), "tet");
  ASSERT_EQ(swept.at("name"), "tet");
  EXPECT_EQ(j.at("sweep").at(0).at("probes"), tet.at("probes"));
  for (const char* key : {"probes", "bytes", "gross_error", "mean_rel_error", "p95_rel_error", "relmse"})
    EXPECT_EQ(swept.at(key), tet.at(key)) << key;
}
