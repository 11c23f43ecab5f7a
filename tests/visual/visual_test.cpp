// Visual regression tests: bake the bundled two-room sample with fixed settings (no path budget: every test
// process bakes again, and what is compared is the renderer, not the bake's noise), render each of its cameras
// headless (Vulkan; lavapipe in CI) at a fixed exposure, and compare with the reference images in
// tests/visual/reference/ using `tetraprobe diff`. A fixed exposure (not auto) makes a global brightness
// regression visible. On a mismatch the rendered image and a diff image are left in <build>/visual/ for
// people.
//
// Tolerance (`tetraprobe diff`'s defaults, DiffThresholds in tools/cli/image_compare.h): a pixel differs when
// a channel is off by more than 2/255; at most 0.1 % of pixels may differ, at most 1/8 of any 16x16 window,
// and at most 0.5 % may change at all. The bake is bit-identical across runs and thread counts, and the
// renderer's GPU lookup matches the CPU to 1e-6 relative, so on one driver the images are identical; the
// slack absorbs rasterization differences between Mesa versions along silhouette edges (scattered single
// pixels). ComparisonRejectsBrokenRenders shows the same comparison rejects broken levels, and
// docs/evaluation.md#visual-regression gives the figures and the reasons for each threshold.
//
// Set TETRAPROBE_UPDATE_REFERENCES=1 to overwrite the references with the current renders (make
// update-references) after an intended change, and look at them before committing. Such a run compares
// nothing, so under TETRAPROBE_REQUIRE_ALL (CI) it fails like a run without a Vulkan device.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <functional>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include <glm/geometric.hpp>

#include "missing_capability.h"
#include "tetraprobe/runtime/level.h"
#include "tetraprobe/runtime/query.h"

namespace fs = std::filesystem;

namespace {

const fs::path kOut = TETRAPROBE_VISUAL_OUT;
const fs::path kRef = fs::path(TETRAPROBE_SOURCE_DIR) / "tests/visual/reference";
const std::string kScene = std::string(TETRAPROBE_SOURCE_DIR) + "/samples/two_rooms/two_rooms.scene.json";

std::string slurp(const fs::path& p) {
  std::ifstream in(p);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

int sh(const std::string& cmd) {
  const int status = std::system(cmd.c_str());
  return WIFEXITED(status) ? WEXITSTATUS(status) : 128;
}

class Visual : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    fs::create_directories(kOut);
    bakeStatus_ = sh(std::string(TETRAPROBE_CLI) + " bake " + kScene +
                     " --spacing 0.5 --samples 128 --path-budget 0 --threads 0 -o " +
                     (kOut / "two_rooms.tpb").string() + " > " + (kOut / "bake.log").string() + " 2>&1");
  }
  static int bakeStatus_;

  // Renders `level` (default: the bake) as the reference `camera`/`mode` into <out>/<name>.png. Returns false
  // when there is no Vulkan driver (the caller skips); fails the test on any other render failure.
  static bool renderTo(const std::string& camera, const std::string& mode, const std::string& name,
                       const fs::path& level, std::string* skip) {
    const fs::path img = kOut / (name + ".png");
    const int r = sh(std::string(TETRAPROBE_CLI) + " render " + kScene + " " + level.string() + " -o " +
                     img.string() + " --camera " + camera + " --mode " + mode +
                     " --size 480x270 --exposure 0.35 > " + (kOut / (name + ".log")).string() + " 2>&1");
    if (r != 0) {
      const std::string log = slurp(kOut / (name + ".log"));
      // Only a machine without any Vulkan driver skips; every other render failure fails the test.
      if (tetraprobe::test::isNoVulkan(log)) {
        *skip = log;
        return false;
      }
      ADD_FAILURE() << "render failed: " << log;
    }
    return true;
  }

  void check(const std::string& camera, const std::string& mode) {
    ASSERT_EQ(bakeStatus_, 0) << "bake failed, see " << (kOut / "bake.log");
    const std::string name = "two_rooms_" + camera + "_" + mode;
    const fs::path img = kOut / (name + ".png");
    std::string skip;
    if (!renderTo(camera, mode, name, kOut / "two_rooms.tpb", &skip)) TETRAPROBE_SKIP_MISSING(skip);
    if (HasFailure()) return;
    const fs::path ref = kRef / (name + ".png");
    if (std::getenv("TETRAPROBE_UPDATE_REFERENCES")) {
      fs::create_directories(kRef);
      fs::copy_file(img, ref, fs::copy_options::overwrite_existing);
      TETRAPROBE_SKIP_MISSING("reference updated, nothing compared: " << ref);
    }
    ASSERT_TRUE(fs::exists(ref)) << "no reference image " << ref << " (make update-references)";
    const fs::path diff = kOut / (name + ".diff.png");
    const int d = sh(std::string(TETRAPROBE_CLI) + " diff " + img.string() + " " + ref.string() + " --out " +
                     diff.string() + " > " + (kOut / (name + ".diff.txt")).string() + " 2>&1");
    EXPECT_EQ(d, 0) << name << " differs from its reference; see " << img << ", " << diff << " and "
                    << (kOut / (name + ".diff.txt"));
  }
};
int Visual::bakeStatus_ = -1;

}  // namespace

TEST_F(Visual, OverviewIndirectMatchesReference) {
  check("overview", "indirect");
}
TEST_F(Visual, DoorwayIndirectMatchesReference) {
  check("doorway", "indirect");
}
TEST_F(Visual, RoomBIrradianceMatchesReference) {
  check("room_b", "irradiance");
}

namespace {

// Runs `tetraprobe diff IMAGE REFERENCE` with the thresholds every reference test uses; returns its exit code
// (0 match, 1 differ) and its one-line verdict in `line`.
int diffAgainstReference(const fs::path& image, const fs::path& ref, std::string* line) {
  const fs::path txt = kOut / (image.stem().string() + ".diff.txt");
  const int d = sh(std::string(TETRAPROBE_CLI) + " diff " + image.string() + " " + ref.string() + " --out " +
                   (kOut / (image.stem().string() + ".diff.png")).string() + " > " + txt.string() + " 2>&1");
  *line = slurp(txt);
  while (!line->empty() && line->back() == '\n') line->pop_back();
  return d;
}

// Mean length of the tet edges at each probe (metres).
std::vector<double> meanEdgeLength(const tetraprobe::Level& level) {
  std::vector<double> sum(level.probes.size(), 0.0), count(level.probes.size(), 0.0);
  for (const tetraprobe::Tet& t : level.tets)
    for (int i = 0; i < 4; ++i)
      for (int j = 0; j < 4; ++j)
        if (i != j) {
          sum[size_t(t.v[i])] += glm::distance(glm::dvec3(level.probes[size_t(t.v[i])]),
                                               glm::dvec3(level.probes[size_t(t.v[j])]));
          count[size_t(t.v[i])] += 1.0;
        }
  for (size_t p = 0; p < sum.size(); ++p) sum[p] = count[p] > 0 ? sum[p] / count[p] : 0.0;
  return sum;
}

}  // namespace

// The references can fail: four deliberately broken levels, each a data mutation of the same bake (no shader
// change), rendered like OverviewIndirectMatchesReference, must each be rejected by the comparison that
// accepts the unbroken level (saved and rendered through the same path, so a difference cannot come from the
// load/save round trip). The metric and thresholds, and why each variant must be caught: docs/evaluation.md
// (#visual-regression). The broken variants:
// - occlusion off: the level's occlusion section dropped (light leaks through the partition);
// - SH L1: coefficients 4..8 of every probe zeroed (Level::shOrder 1);
// - weights shifted: every probe moved by 1 % of the mean length of its tet edges in a random direction, tets
//   kept, so every barycentric weight moves by about 1 % (measured below, mean max |dw| over points);
// - one probe zeroed: all SH of one probe in view (two cases: the middle of the lit room's floor, and the
//   doorway, the camera's target, where probes are densest and a probe's blob the smallest).
TEST_F(Visual, ComparisonRejectsBrokenRenders) {
  ASSERT_EQ(bakeStatus_, 0) << "bake failed, see " << (kOut / "bake.log");
  tetraprobe::Level baked;
  const auto loaded = tetraprobe::loadLevel((kOut / "two_rooms.tpb").string(), baked);
  ASSERT_TRUE(loaded) << loaded.message;
  const fs::path ref = kRef / "two_rooms_overview_indirect.png";
  ASSERT_TRUE(fs::exists(ref)) << ref;

  // The probes to zero: the one with the largest weight 5 cm above the floor at the middle of the lit room A
  // (2, 0, 2), and at the overview camera's target (4.1, 0, 2), the doorway, where the fine volume's probes
  // are close together, so the smallest blob of the two.
  const tetraprobe::ProbeQuery bakedQuery(baked);
  const auto heaviestProbe = [&](const glm::dvec3& x) {
    const tetraprobe::Location loc = bakedQuery.locate(x);
    int best = 0;
    for (int k = 1; k < 4; ++k)
      if (loc.weights[k] > loc.weights[best]) best = k;
    return loc.tet >= 0 ? baked.tets[size_t(loc.tet)].v[best] : -1;
  };
  const int32_t roomProbe = heaviestProbe(glm::dvec3(2.0, 0.05, 2.0));
  const int32_t doorwayProbe = heaviestProbe(glm::dvec3(4.1, 0.05, 2.0));
  ASSERT_GE(roomProbe, 0);
  ASSERT_GE(doorwayProbe, 0);

  struct Variant {
    std::string name;
    std::function<void(tetraprobe::Level&)> mutate;
    bool broken;
  };
  const std::vector<Variant> variants = {
      {"unbroken", [](tetraprobe::Level&) {}, false},
      {"occlusion_off", [](tetraprobe::Level& l) { l.occlusion = tetraprobe::LevelOcclusion{}; }, true},
      {"sh_l1",
       [](tetraprobe::Level& l) {
         for (tetraprobe::ShRgb& s : l.sh)
           for (int c = 4; c < tetraprobe::kShCoeffCount; ++c) s.c[size_t(c)] = glm::vec3(0.0f);
         l.shOrder = 1;
       },
       true},
      {"weights_shifted_1pct",
       [](tetraprobe::Level& l) {
         const std::vector<double> edge = meanEdgeLength(l);
         std::mt19937 rng(1);
         const auto u = [&] { return double(rng()) / 4294967296.0 * 2.0 - 1.0; };
         for (size_t p = 0; p < l.probes.size(); ++p) {
           glm::dvec3 d;
           do d = glm::dvec3(u(), u(), u());
           while (glm::dot(d, d) > 1.0 || glm::dot(d, d) < 1e-4);
           l.probes[p] = glm::vec3(glm::dvec3(l.probes[p]) + 0.01 * edge[p] * glm::normalize(d));
         }
       },
       true},
      {"one_probe_zeroed_room_a",
       [&](tetraprobe::Level& l) { l.sh[size_t(roomProbe)] = tetraprobe::ShRgb{}; }, true},
      {"one_probe_zeroed_doorway",
       [&](tetraprobe::Level& l) { l.sh[size_t(doorwayProbe)] = tetraprobe::ShRgb{}; }, true},
  };

  for (const Variant& v : variants) {
    tetraprobe::Level level = baked;
    v.mutate(level);
    const fs::path path = kOut / ("broken_" + v.name + ".tpb");
    const auto saved = tetraprobe::saveLevel(path.string(), level);
    ASSERT_TRUE(saved) << v.name << ": " << saved.message;
    if (v.name == "weights_shifted_1pct") {
      // How far the weights moved: at 4000 points in the rooms, the largest |dw| of the four, where the
      // point stays in the same tet (mean and 90th percentile).
      const tetraprobe::ProbeQuery moved(level);
      std::mt19937 rng(2);
      std::vector<double> dw;
      for (int i = 0; i < 4000; ++i) {
        const glm::dvec3 x(0.1 + 8.0 * (rng() / 4294967296.0), 0.1 + 2.8 * (rng() / 4294967296.0),
                           0.1 + 3.8 * (rng() / 4294967296.0));
        const tetraprobe::Location a = bakedQuery.locate(x), b = moved.locate(x, a.tet);
        if (!a.inside || a.tet != b.tet) continue;
        float m = 0.0f;
        for (int k = 0; k < 4; ++k) m = std::max(m, std::abs(a.weights[k] - b.weights[k]));
        dw.push_back(m);
      }
      ASSERT_GT(dw.size(), 1000u);
      std::sort(dw.begin(), dw.end());
      double mean = 0.0;
      for (double d : dw) mean += d / double(dw.size());
      std::printf("weights_shifted_1pct: max |dw| per point: mean %.4f, 90th percentile %.4f (%zu points)\n",
                  mean, dw[dw.size() * 9 / 10], dw.size());
      EXPECT_GT(mean, 0.005) << "the perturbation must shift weights by about 1 %";
      EXPECT_LT(mean, 0.02) << "the perturbation must shift weights by about 1 %, not more";
    }
    std::string skip;
    if (!renderTo("overview", "indirect", "broken_" + v.name, path, &skip)) TETRAPROBE_SKIP_MISSING(skip);
    if (!fs::exists(kOut / ("broken_" + v.name + ".png"))) return;  // the render failed (reported)
    std::string line;
    const int d = diffAgainstReference(kOut / ("broken_" + v.name + ".png"), ref, &line);
    std::printf("%-22s %s\n", v.name.c_str(), line.c_str());
    if (v.broken) {
      EXPECT_EQ(d, 1) << v.name << " must be rejected: " << line;
    } else {
      EXPECT_EQ(d, 0) << "the unbroken level must be accepted: " << line;
    }
  }
}
