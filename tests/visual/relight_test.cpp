// Run-time relighting of a real baked level against a fresh bake of the same SH: the bundled two_rooms
// sample, baked and exported (`export-sh`), re-baked twice with `bake --import-sh` (no path tracing: the
// same probes, so the same tets, cell grid, outer cells and occlusion) with the original SH and with the
// probes of room A relit (tinted: the lamp changes colour). The first, relit in place with setProbeSh and
// writeLevelSh, must answer as the second on the CPU and on the GPU bit for bit.
#include <gtest/gtest.h>

#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include <glm/geometric.hpp>

#include "missing_capability.h"
#include "point_lookup.h"
#include "tetraprobe/runtime/level.h"
#include "tetraprobe/runtime/probe_update.h"
#include "tetraprobe/runtime/query.h"

namespace fs = std::filesystem;

namespace tetraprobe {
namespace {

const fs::path kOut = fs::path(TETRAPROBE_VISUAL_OUT) / "relight";
const std::string kScene = std::string(TETRAPROBE_SOURCE_DIR) + "/samples/two_rooms/two_rooms.scene.json";

int run(const std::string& cmd, const fs::path& log) {
  const int status = std::system((cmd + " > " + log.string() + " 2>&1").c_str());
  return WIFEXITED(status) ? WEXITSTATUS(status) : 128;
}

std::string slurp(const fs::path& p) {
  std::ifstream in(p);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

// Copies an export-sh CSV, multiplying the 27 SH values of every probe with x < 4.1 (room A) by `tint` per
// channel. Comment and header lines are copied as they are.
void tintRoomA(const fs::path& in, const fs::path& out, const glm::vec3& tint) {
  std::ifstream src(in);
  std::ofstream dst(out);
  std::string line;
  while (std::getline(src, line)) {
    if (line.empty() || line[0] == '#' || line[0] == 'x') {
      dst << line << '\n';
      continue;
    }
    std::vector<std::string> cells;
    std::stringstream ss(line);
    for (std::string cell; std::getline(ss, cell, ',');) cells.push_back(cell);
    ASSERT_EQ(cells.size(), 30u) << line;
    const bool roomA = std::stod(cells[0]) < 4.1;
    char buf[64];
    for (size_t i = 0; i < cells.size(); ++i) {
      // Positions and untouched values are copied as text (export-sh writes positions with 17 digits).
      if (i >= 3 && roomA) {
        std::snprintf(buf, sizeof buf, "%.9g", std::stod(cells[i]) * double(tint[int((i - 3) % 3)]));
        cells[i] = buf;
      }
      dst << (i ? "," : "") << cells[i];
    }
    dst << '\n';
  }
}

Level load(const fs::path& p) {
  Level level;
  const LevelResult r = loadLevel(p.string(), level);
  EXPECT_TRUE(r) << r.message;
  return level;
}

// Points in both rooms (x in [0.1, 8.1], y in [0.1, 2.9], z in [0.1, 3.9]) with random unit normals, local
// frame.
std::vector<test::PointNormal> roomPoints(const Level& level, size_t n) {
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> u(0.0, 1.0), s(-1.0, 1.0);
  std::vector<test::PointNormal> pts(n);
  for (test::PointNormal& q : pts) {
    const glm::dvec3 world(0.1 + 8.0 * u(rng), 0.1 + 2.8 * u(rng), 0.1 + 3.8 * u(rng));
    const glm::vec3 local(world - level.origin);
    const glm::vec3 nrm = glm::normalize(glm::vec3(float(s(rng)), float(s(rng)), float(s(rng))) + 1e-3f);
    for (int a = 0; a < 3; ++a) q.position[a] = local[a], q.normal[a] = nrm[a];
    q.position[3] = q.normal[3] = 0.0f;
  }
  return pts;
}

TEST(Relight, BakedLevelRelitInPlaceMatchesFreshBakeOnCpuAndGpu) {
  fs::create_directories(kOut);
  const std::string cli = TETRAPROBE_CLI;
  // A quick bake (a few seconds): the test is about the update, not the light.
  ASSERT_EQ(
      run(cli + " bake " + kScene + " --spacing 1 --samples 64 --max-samples 256 --path-budget 200000 " +
              "--probe-budget 0 -o " + (kOut / "baked.tpb").string(),
          kOut / "bake.log"),
      0)
      << slurp(kOut / "bake.log");
  ASSERT_EQ(run(cli + " export-sh " + (kOut / "baked.tpb").string() + " -o " + (kOut / "day.csv").string(),
                kOut / "export.log"),
            0)
      << slurp(kOut / "export.log");
  tintRoomA(kOut / "day.csv", kOut / "lamp.csv", glm::vec3(1.5f, 1.0f, 0.6f));
  for (const char* name : {"day", "lamp"}) {
    const fs::path csv = kOut / (std::string(name) + ".csv"), level = kOut / (std::string(name) + ".tpb");
    ASSERT_EQ(
        run(cli + " bake " + kScene + " --import-sh " + csv.string() + " --dering none -o " + level.string(),
            kOut / (std::string(name) + ".log")),
        0)
        << slurp(kOut / (std::string(name) + ".log"));
  }
  Level day = load(kOut / "day.tpb");
  const Level lamp = load(kOut / "lamp.tpb");
  ASSERT_EQ(day.probes.size(), lamp.probes.size());
  ASSERT_EQ(std::memcmp(day.probes.data(), lamp.probes.data(), sizeof(glm::vec3) * day.probes.size()), 0)
      << "the CSV round trip must keep the probe positions bit for bit";
  ASSERT_EQ(day.tets.size(), lamp.tets.size());
  ASSERT_EQ(std::memcmp(day.tets.data(), lamp.tets.data(), sizeof(Tet) * day.tets.size()), 0)
      << "the same probes must give the same tets";
  ASSERT_EQ(day.occlusion.planes.size(), lamp.occlusion.planes.size()) << "and the same occlusion";
  ASSERT_FALSE(day.occlusion.empty()) << "the baked level has occlusion: the relight is checked with it";

  const std::vector<test::PointNormal> pts = roomPoints(day, 4000);
  const ProbeQuery dayQuery(day), lampQuery(lamp);
  const std::vector<glm::vec3> cpuDay = test::cpuIrradiance(dayQuery, pts);
  const std::vector<glm::vec3> cpuLamp = test::cpuIrradiance(lampQuery, pts);
  const size_t relitPoints = test::countDifferent(cpuDay, cpuLamp);
  std::printf("the lamp changes %zu of %zu points (%zu probes)\n", relitPoints, pts.size(),
              day.probes.size());
  EXPECT_GT(relitPoints, pts.size() / 4) << "the relight must change room A's light for the test to bite";

  try {
    test::PointLookup gpu(pts);
    const size_t live = gpu.upload(day, dayQuery);
    const std::vector<glm::vec3> gpuDay = gpu.run(live);
    ASSERT_TRUE(setProbeSh(day, 0, lamp.sh));
    std::string error;
    ASSERT_EQ(gpu.writeSh(live, day, 0, day.sh.size(), &error), VK_SUCCESS) << error;
    EXPECT_EQ(test::countDifferent(test::cpuIrradiance(dayQuery, pts), cpuLamp), 0u)
        << "CPU: the relit level against the fresh bake";
    const std::vector<glm::vec3> gpuRelit = gpu.run(live);
    const std::vector<glm::vec3> gpuLamp = gpu.run(gpu.upload(lamp, lampQuery));
    EXPECT_EQ(test::countDifferent(gpuRelit, gpuLamp), 0u) << "GPU: the relit buffers against a fresh upload";
    EXPECT_GT(test::countDifferent(gpuRelit, gpuDay), pts.size() / 4);
    const double worst = test::worstRelative(gpuRelit, cpuLamp);
    std::printf("GPU against CPU on the relit level: worst relative difference %.2e\n", worst);
    EXPECT_LT(worst, 1e-4);
  } catch (const std::runtime_error& e) {
    if (test::isNoVulkan(e.what())) TETRAPROBE_SKIP_MISSING(e.what());
    throw;
  }
}

}  // namespace
}  // namespace tetraprobe
