// Run-time SH updates (probe_update.h, vulkan_upload.h's writeLevelSh / cmdUpdateLevelSh) relight a level on
// the CPU and on the GPU exactly as a level freshly built with the new SH: the test uploads a level once,
// replaces all or part of its SH in place, and compares the GPU lookup (shaders/tetraprobe.glsl through
// point_lookup.comp, on lavapipe) and the CPU query with those of a level built from scratch with the same
// probes and the new SH.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <functional>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

#include <glm/geometric.hpp>

#include "missing_capability.h"
#include "point_lookup.h"
#include "tetraprobe/runtime/probe_update.h"
#include "tetraprobe/runtime/query.h"
#include "tetraprobe/runtime/sh_half.h"
#include "tetraprobe/runtime/vulkan_upload.h"
#include "tetraprobe/tetra/tetrahedralize.h"

namespace tetraprobe {
namespace {

using test::countDifferent;
using test::cpuIrradiance;
using test::PointLookup;
using test::PointNormal;
using test::worstRelative;

const glm::dvec3 kOrigin(1000.0, -20.0, 500.0);  // far from the world origin, as a real level may be

// The probes: 5x3x5 on a 1 m grid over local [0,4]x[0,2]x[0,4], jittered so no four are cospherical, in
// z-major order (probes [15 z, 15 z + 15) form the layer z).
std::vector<glm::dvec3> probePositions() {
  std::vector<glm::dvec3> world;
  for (int z = 0; z < 5; ++z)
    for (int y = 0; y < 3; ++y)
      for (int x = 0; x < 5; ++x)
        world.push_back(kOrigin + glm::dvec3(x + 0.07 * std::sin(1.3 * x + 2.1 * y + 0.7 * z),
                                             y + 0.05 * std::cos(0.9 * x + 1.7 * z),
                                             z + 0.06 * std::sin(2.3 * y + 0.4 * x)));
  return world;
}

// "Daylight": a smooth field, L00 dominant so E stays positive (relative errors are meaningful).
ShRgb daylight(const glm::vec3& p) {
  ShRgb sh;
  sh.c[0] = glm::vec3(2.0f + 0.4f * p.x, 1.5f + 0.3f * p.y, 1.0f + 0.2f * p.z);
  sh.c[1] = glm::vec3(0.2f * p.y, -0.1f, 0.05f * p.x);
  sh.c[2] = glm::vec3(-0.15f, 0.1f * p.z, 0.2f);
  sh.c[3] = glm::vec3(0.1f * p.x, 0.05f, -0.1f * p.z);
  for (int i = 4; i < 9; ++i)
    sh.c[size_t(i)] = glm::vec3(0.03f * float(i - 6) + 0.01f * p.x, 0.02f * p.y, -0.02f * float(i - 5));
  return sh;
}

// "A lamp switched on": warmer, brighter towards +x, the L1 direction turned 90 degrees about y, L2 flipped.
ShRgb lamp(const glm::vec3& p) {
  const ShRgb d = daylight(p);
  ShRgb sh;
  const glm::vec3 tint(1.6f, 0.9f, 0.4f);
  sh.c[0] = d.c[0] * tint * (1.0f + 0.3f * p.x);
  sh.c[1] = d.c[1] * tint;
  sh.c[2] = -d.c[3] * tint;  // (x, z) -> (z, -x)
  sh.c[3] = d.c[2] * tint;
  for (int i = 4; i < 9; ++i) sh.c[size_t(i)] = -0.5f * d.c[size_t(i)];
  return sh;
}

// Plane occlusion on three tets in four (random planes and visible sets), so the update is checked with the
// occluded blend too. It depends on the tets only, as real occlusion depends on tets and geometry.
LevelOcclusion planeOcclusion(size_t tets) {
  LevelOcclusion occ;
  std::mt19937 rng(11);
  std::uniform_real_distribution<float> u(-1.0f, 1.0f);
  for (size_t t = 0; t < tets; ++t) {
    if (t % 4 == 3) {
      occ.tets.push_back(makeTetOcclusion(kOcclusionNone, 0, 0, 0));
      continue;
    }
    const uint32_t count = uint32_t(t % 3) + 1;
    uint32_t cells = 0;
    for (uint32_t c = 0; c < (1u << count); ++c) cells |= (1u + uint32_t(rng()) % 15u) << (4 * c);
    occ.tets.push_back(makeTetOcclusion(kOcclusionPlanes, count, uint32_t(occ.planes.size()), cells));
    for (uint32_t k = 0; k < count; ++k) {
      const double a = u(rng), b = u(rng), c = u(rng), d = u(rng);
      occ.planes.push_back(makeOcclusionPlane(a, b, c, d));
    }
  }
  return occ;
}

// A level built from scratch: tetrahedralized, occluded, with probe p's SH = sh(p).
Level buildLevel(const std::function<ShRgb(size_t, const glm::vec3&)>& sh) {
  const std::vector<glm::dvec3> world = probePositions();
  Level level;
  level.origin = kOrigin;
  for (size_t p = 0; p < world.size(); ++p) {
    level.probes.emplace_back(world[p] - kOrigin);
    level.sh.push_back(quantizeSh(sh(p, level.probes.back())));  // as setProbeSh and a level file store them
  }
  level.tets = buildTetRecords(world, tetrahedralizeDelaunay(world), kOrigin);
  level.occlusion = planeOcclusion(level.tets.size());
  return level;
}

// Points in and around the probe hull (local [-1,5]x[-1,3]x[-1,5]) with random unit normals.
std::vector<PointNormal> makePoints(size_t n) {
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<float> u(0.0f, 1.0f), s(-1.0f, 1.0f);
  std::vector<PointNormal> pts(n);
  for (PointNormal& q : pts) {
    const glm::vec3 x(-1.0f + 6.0f * u(rng), -1.0f + 4.0f * u(rng), -1.0f + 6.0f * u(rng));
    const glm::vec3 nrm = glm::normalize(glm::vec3(s(rng), s(rng), s(rng)) + glm::vec3(1e-3f));
    for (int a = 0; a < 3; ++a) q.position[a] = x[a], q.normal[a] = nrm[a];
    q.position[3] = q.normal[3] = 0.0f;
  }
  return pts;
}

// The whole relight, in the order an engine does it: upload a level lit by daylight; switch the lamp on for
// every probe (setProbeSh + writeLevelSh, a staged copy waited for); then relight one layer of probes in a
// command buffer that also renders (cmdUpdateLevelSh before the lookup). After each step the CPU query of the
// updated level equals, bit for bit, that of a level built from scratch with the same SH (same tets: the
// tetrahedralization does not look at the SH), and the GPU lookup of the updated buffers equals, bit for bit,
// the lookup of a fresh upload of that level, and the CPU within 1e-4 relative (the tolerance of
// GpuLookup.MatchesCpuQueryPerPixel, which explains it). Each update must change the answers (the test can
// fail), and the partial one only near the relit layer.
TEST(ShUpdate, RelitLevelMatchesFreshLevelOnCpuAndGpu) {
  const std::vector<PointNormal> pts = makePoints(4096);
  Level level = buildLevel([](size_t, const glm::vec3& p) { return daylight(p); });
  const ProbeQuery query(level);
  std::vector<glm::vec3> before;
  try {
    PointLookup gpu(pts);
    const size_t live = gpu.upload(level, query);
    before = gpu.run(live);
    EXPECT_LT(worstRelative(before, cpuIrradiance(query, pts)), 1e-4) << "GPU against CPU before any update";

    // 1. Every probe, through a staged copy (writeLevelSh).
    const Level lampLevel = buildLevel([](size_t, const glm::vec3& p) { return lamp(p); });
    ASSERT_EQ(lampLevel.tets.size(), level.tets.size());
    ASSERT_EQ(std::memcmp(lampLevel.tets.data(), level.tets.data(), sizeof(Tet) * level.tets.size()), 0)
        << "a fresh build of the same probes must give the same tets";
    const ProbeQuery lampQuery(lampLevel);
    ASSERT_TRUE(setProbeSh(level, 0, lampLevel.sh));
    std::string error;
    ASSERT_EQ(gpu.writeSh(live, level, 0, level.sh.size(), &error), VK_SUCCESS) << error;
    const std::vector<glm::vec3> cpuLamp = cpuIrradiance(lampQuery, pts);
    EXPECT_EQ(countDifferent(cpuIrradiance(query, pts), cpuLamp), 0u) << "CPU: relit level against fresh";
    const std::vector<glm::vec3> relit = gpu.run(live);
    const std::vector<glm::vec3> freshLamp = gpu.run(gpu.upload(lampLevel, lampQuery));
    EXPECT_EQ(countDifferent(relit, freshLamp), 0u) << "GPU: updated buffers against a fresh upload";
    EXPECT_LT(worstRelative(relit, cpuLamp), 1e-4) << "GPU against CPU after the update";
    EXPECT_GT(countDifferent(relit, before), pts.size() * 99 / 100) << "the lamp must change the answers";

    // 2. The layer z = 2 (probes [30, 45)) back to daylight, recorded in the command buffer of the lookup.
    const size_t first = 30, count = 15;
    const auto mixed = [&](size_t p, const glm::vec3& x) {
      return p >= first && p < first + count ? daylight(x) : lamp(x);
    };
    const Level mixedLevel = buildLevel(mixed);
    const ProbeQuery mixedQuery(mixedLevel);
    ASSERT_TRUE(setProbeSh(level, first, {mixedLevel.sh.data() + first, count}));
    bool recorded = false;
    const std::vector<glm::vec3> partial = gpu.run(live, [&](VkCommandBuffer cmd) {
      recorded = cmdUpdateLevelSh(cmd, gpu.buffers(live), level, first, count,
                                  VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT, &error);
    });
    ASSERT_TRUE(recorded) << error;
    const std::vector<glm::vec3> cpuMixed = cpuIrradiance(mixedQuery, pts);
    EXPECT_EQ(countDifferent(cpuIrradiance(query, pts), cpuMixed), 0u) << "CPU: partly relit against fresh";
    EXPECT_EQ(countDifferent(partial, gpu.run(gpu.upload(mixedLevel, mixedQuery))), 0u)
        << "GPU: partly updated buffers against a fresh upload";
    EXPECT_LT(worstRelative(partial, cpuMixed), 1e-4);
    const size_t changed = countDifferent(partial, relit);
    EXPECT_GT(changed, pts.size() / 10) << "points near layer z = 2 must change";
    EXPECT_LT(changed, pts.size() * 9 / 10) << "points far from layer z = 2 must not";
    std::printf("partial update of %zu probes changed %zu of %zu points\n", count, changed, pts.size());

    // 3. Out-of-range and mismatched requests are refused and leave the buffers as they were.
    EXPECT_EQ(gpu.writeSh(live, level, level.sh.size(), 1, &error), VK_ERROR_INITIALIZATION_FAILED);
    EXPECT_NE(error.find("outside"), std::string::npos) << error;
    EXPECT_EQ(gpu.writeSh(live, level, 1, level.sh.size(), &error), VK_ERROR_INITIALIZATION_FAILED);
    Level bigger = level;
    for (int k = 0; k < 200; ++k) {
      bigger.probes.push_back(glm::vec3(0.0f));
      bigger.sh.push_back(ShRgb{});
    }
    EXPECT_EQ(gpu.writeSh(live, bigger, 0, 1, &error), VK_ERROR_INITIALIZATION_FAILED)
        << "a level with more probes than the buffer was uploaded with";
    EXPECT_NE(error.find("cannot hold"), std::string::npos) << error;
    recorded = true;
    EXPECT_EQ(countDifferent(gpu.run(live,
                                     [&](VkCommandBuffer cmd) {
                                       recorded = cmdUpdateLevelSh(
                                           cmd, gpu.buffers(live), level, level.sh.size() - 1, 2,
                                           VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT, &error);
                                     }),
                             partial),
              0u);
    EXPECT_FALSE(recorded);
  } catch (const std::runtime_error& e) {
    if (test::isNoVulkan(e.what())) TETRAPROBE_SKIP_MISSING(e.what());
    throw;
  }
}

}  // namespace
}  // namespace tetraprobe
