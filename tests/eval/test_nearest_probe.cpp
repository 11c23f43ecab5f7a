// The nearest-probe competitor (eval/nearest_probe.h): the bucket search finds the probe a brute-force scan
// finds, inside and far outside the probes' box, and its GPU pass (shaders/lighting_nearest.comp) lights each
// pixel with that probe's SH.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>
#include <vector>

#include <glm/geometric.hpp>

#include "missing_capability.h"
#include "test_levels.h"
#include "tetraprobe/eval/nearest_probe.h"
#include "tetraprobe/render/render.h"

namespace tetraprobe {
namespace {

// Probes scattered unevenly (a dense cluster and sparse rest, so buckets hold 0..many) with SH varying per
// probe.
Level scatteredLevel(size_t n, uint32_t seed) {
  Level level;
  level.origin = glm::dvec3(1.0, 0.0, -2.0);
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  for (size_t i = 0; i < n; ++i) {
    const bool cluster = i % 3 == 0;
    const glm::vec3 p = cluster
                            ? glm::vec3(-1.0f + 0.5f * u(rng), 0.2f + 0.3f * u(rng), 0.5f + 0.5f * u(rng))
                            : glm::vec3(-4.0f + 8.0f * u(rng), -0.5f + 2.5f * u(rng), -4.0f + 8.0f * u(rng));
    level.probes.push_back(p);
    ShRgb s;
    for (int c = 0; c < kShCoeffCount; ++c)
      s.c[size_t(c)] = glm::vec3(1.0f + 0.1f * float(c) + u(rng), 0.5f + u(rng), 0.2f * float(c) * u(rng));
    level.sh.push_back(s);
  }
  return level;
}

int32_t bruteNearest(const Level& level, const glm::vec3& q) {
  float best = std::numeric_limits<float>::infinity();
  int32_t idx = -1;
  for (size_t i = 0; i < level.probes.size(); ++i) {
    const glm::vec3 d = level.probes[i] - q;
    const float d2 = glm::dot(d, d);
    if (d2 < best) {
      best = d2;
      idx = int32_t(i);
    }
  }
  return idx;
}

TEST(NearestProbe, AgreesWithBruteForceInsideAndFarOutside) {
  const Level level = scatteredLevel(500, 7);
  const NearestProbe nearest(level);
  std::mt19937 rng(11);
  std::uniform_real_distribution<float> u(-1.0f, 1.0f);
  for (int k = 0; k < 4000; ++k) {
    const float reach = k < 3000 ? 5.0f : 500.0f;  // the last quarter far outside the box
    const glm::vec3 q(reach * u(rng), reach * u(rng), reach * u(rng));
    ASSERT_EQ(nearest.nearest(q), bruteNearest(level, q)) << q.x << " " << q.y << " " << q.z;
  }
}

// Per pixel, the GPU's answer is the SH irradiance of the probe NearestProbe finds for the pixel's position
// (1e-4 relative: float SH sums in another order); where two probes are within float rounding of equally
// near, either probe's answer is accepted.
TEST(NearestRender, GpuPassLightsEachPixelWithTheNearestProbe) {
  const Level level = scatteredLevel(300, 3);
  const NearestProbe buckets(level);
  const RenderMesh mesh = test::floorMesh();
  RenderView view = test::floorView(48, 32);
  view.mode = RenderMode::kIrradiance;
  RenderResult r;
  try {
    r = renderNearestProbe(mesh, buckets.gpuBuckets(), view);
  } catch (const std::runtime_error& e) {
    if (!test::isNoVulkan(e.what())) throw;
    TETRAPROBE_SKIP_MISSING(e.what());
  }
  size_t checked = 0, ties = 0;
  for (size_t i = 0; i < size_t(view.width * view.height); ++i) {
    if (r.position.rgba[4 * i + 3] == 0.0f) continue;
    const glm::vec3 q(r.position.rgba[4 * i], r.position.rgba[4 * i + 1], r.position.rgba[4 * i + 2]);
    const glm::vec3 n(r.normal.rgba[4 * i], r.normal.rgba[4 * i + 1], r.normal.rgba[4 * i + 2]);
    const glm::vec3 got(r.color.rgba[4 * i], r.color.rgba[4 * i + 1], r.color.rgba[4 * i + 2]);
    auto matches = [&](int32_t p) {
      const glm::vec3 want = shIrradiance(level.sh[size_t(p)], n);
      for (int c = 0; c < 3; ++c)
        if (std::abs(got[c] - want[c]) > 1e-4f * (1.0f + std::abs(want[c]))) return false;
      return true;
    };
    const int32_t p = buckets.nearest(q);
    ++checked;
    if (matches(p)) continue;
    const glm::vec3 dp = level.probes[size_t(p)] - q;
    const float best = glm::dot(dp, dp);
    bool tie = false;
    for (size_t k = 0; k < level.probes.size() && !tie; ++k) {
      const glm::vec3 d = level.probes[k] - q;
      tie = glm::dot(d, d) <= best * (1.0f + 1e-5f) + 1e-12f && matches(int32_t(k));
    }
    ASSERT_TRUE(tie) << "pixel " << i << ": GPU " << got.x << " " << got.y << " " << got.z
                     << ", nearest probe " << p;
    ++ties;
  }
  EXPECT_GT(checked, size_t(view.width * view.height / 2));
  EXPECT_LE(ties, checked / 100);
}

}  // namespace
}  // namespace tetraprobe
