// Dilation of invalid probes (dilateInvalidProbes): each invalid probe takes its nearest valid probe's SH.
#include <gtest/gtest.h>

#include <limits>
#include <random>
#include <stdexcept>

#include <glm/geometric.hpp>

#include "tetraprobe/bake/bake.h"

namespace tetraprobe {
namespace {

ShRgb tagged(float v) {
  ShRgb s{};
  s.c[0] = glm::vec3(v, -v, 2.0f * v);
  return s;
}

// Against brute force on clustered points (an interior cloud and a far shell, the case the pipeline has),
// including queries far off the valid probes' grid; ties go to the lower index.
TEST(Dilate, InvalidProbesTakeTheNearestValidProbesSh) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::vector<glm::dvec3> pos;
  std::vector<uint8_t> invalid;
  for (int i = 0; i < 600; ++i) {  // interior cloud, mostly valid
    pos.push_back({u(rng) * 10.0, u(rng) * 3.0, u(rng) * 4.0});
    invalid.push_back(u(rng) < 0.1 ? 1 : 0);
  }
  for (int i = 0; i < 200; ++i) {  // far invalid shell
    pos.push_back({u(rng) * 40.0 - 15.0, 25.0 + u(rng), u(rng) * 40.0 - 15.0});
    invalid.push_back(1);
  }
  pos.push_back(pos[3]);  // at distance 0 from probe 3: copies it when 3 is valid
  invalid.push_back(1);
  std::vector<ShRgb> sh;
  for (size_t i = 0; i < pos.size(); ++i) sh.push_back(tagged(float(i)));
  const std::vector<ShRgb> before = sh;

  const size_t replaced = dilateInvalidProbes(pos, invalid, sh);
  size_t expected = 0;
  for (size_t i = 0; i < pos.size(); ++i) {
    if (!invalid[i]) {
      EXPECT_EQ(sh[i].c[0], before[i].c[0]) << "valid probe " << i << " changed";
      continue;
    }
    ++expected;
    size_t best = 0;
    double bestD = std::numeric_limits<double>::infinity();
    for (size_t j = 0; j < pos.size(); ++j) {
      if (invalid[j]) continue;
      const glm::dvec3 d = pos[j] - pos[i];
      const double d2 = glm::dot(d, d);
      if (d2 < bestD) {
        bestD = d2;
        best = j;
      }
    }
    EXPECT_EQ(sh[i].c[0], before[best].c[0]) << "probe " << i << " should copy " << best;
  }
  EXPECT_EQ(replaced, expected);
}

// Nothing to copy from, or nothing to replace: unchanged. Mismatched sizes are a programming error.
TEST(Dilate, AllValidOrAllInvalidLeavesShUnchanged) {
  std::vector<glm::dvec3> pos = {{0, 0, 0}, {1, 0, 0}};
  std::vector<ShRgb> sh = {tagged(1.0f), tagged(2.0f)};
  EXPECT_EQ(dilateInvalidProbes(pos, {1, 1}, sh), 0u);
  EXPECT_EQ(dilateInvalidProbes(pos, {0, 0}, sh), 0u);
  EXPECT_EQ(sh[0].c[0], tagged(1.0f).c[0]);
  EXPECT_EQ(sh[1].c[0], tagged(2.0f).c[0]);
  EXPECT_THROW(dilateInvalidProbes(pos, {0}, sh), std::invalid_argument);
}

}  // namespace
}  // namespace tetraprobe
