// The regular SH grid competitor (eval/grid_volume.h): its lattice fits the byte budget and is the finest
// that does, trilinear interpolation reproduces linear fields, nodes inside geometry carry their nearest
// valid node's light instead of zeros, and the GPU pass agrees with the CPU lookup.
#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <vector>

#include <glm/common.hpp>
#include <glm/geometric.hpp>

#include "missing_capability.h"
#include "test_levels.h"
#include "tetraprobe/eval/evaluate.h"
#include "tetraprobe/eval/grid_volume.h"
#include "tetraprobe/render/render.h"

namespace tetraprobe {
namespace {

// A field linear in position in every coefficient: c_i(p) = a_i + b_i . p (per channel).
ShRgb linearSh(const glm::dvec3& p) {
  ShRgb s;
  for (int i = 0; i < kShCoeffCount; ++i)
    for (int ch = 0; ch < 3; ++ch)
      s.c[size_t(i)][ch] =
          float(0.1 * (i + 1) + 0.3 * ch + (0.5 + 0.1 * i) * p.x - 0.2 * ch * p.y + 0.05 * i * p.z);
  return s;
}

// Trilinear weights are exact for linear functions: the blend equals the field at any point of the lattice's
// box, whatever the cell; outside it, the nearest face's value (clamped).
TEST(GridVolume, TrilinearReproducesLinearFieldExactly) {
  const GridLayout layout = gridLayoutForNodes({-1.0, 0.0, 2.0}, {3.0, 2.0, 3.5}, 300);
  std::vector<ShRgb> sh(layout.nodes());
  for (size_t i = 0; i < sh.size(); ++i) sh[i] = linearSh(layout.node(i));
  const GridVolume grid(layout, sh, std::vector<uint8_t>(sh.size(), 0));
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  const glm::dvec3 hi = layout.min + glm::dvec3(layout.dims - 1) * layout.step;
  for (int k = 0; k < 200; ++k) {
    const glm::dvec3 p = layout.min + glm::dvec3(u(rng), u(rng), u(rng)) * (hi - layout.min);
    const ShRgb got = grid.blend(p), want = linearSh(p);
    for (int i = 0; i < kShCoeffCount; ++i)
      for (int ch = 0; ch < 3; ++ch)
        ASSERT_NEAR(got.c[size_t(i)][ch], want.c[size_t(i)][ch],
                    2e-5 * (1.0 + std::abs(want.c[size_t(i)][ch])))
            << "coefficient " << i << " channel " << ch << " at " << p.x << "," << p.y << "," << p.z;
  }
  // Outside: clamped to the box.
  const glm::dvec3 outside = hi + glm::dvec3(5.0, 0.0, -0.5 * (hi.z - layout.min.z));
  const glm::dvec3 clamped = glm::clamp(outside, layout.min, hi);
  EXPECT_NEAR(grid.blend(outside).c[0].r, linearSh(clamped).c[0].r, 1e-4);
  // Irradiance is the blended SH's (linear in the coefficients).
  const glm::vec3 n = glm::normalize(glm::vec3(0.3f, 0.8f, -0.2f));
  const glm::dvec3 p = (layout.min + hi) * 0.5;
  const glm::vec3 e = grid.irradiance(p, n), want = shIrradiance(linearSh(p), n);
  for (int ch = 0; ch < 3; ++ch) EXPECT_NEAR(e[ch], want[ch], 1e-4 * (1.0 + std::abs(want[ch])));
}

// Invalid nodes are not left at zero: each takes its nearest valid node's SH.
TEST(GridVolume, InvalidNodesTakeTheNearestValidNode) {
  const GridLayout layout = gridLayoutForNodes({0.0, 0.0, 0.0}, {4.0, 4.0, 4.0}, 125);
  ASSERT_EQ(layout.dims, glm::ivec3(5));
  std::vector<ShRgb> sh(layout.nodes());
  std::vector<uint8_t> invalid(layout.nodes(), 0);
  for (size_t i = 0; i < sh.size(); ++i) {
    const glm::dvec3 p = layout.node(i);
    if (p.x < 1.5) {
      invalid[i] = 1;  // a wall of invalid nodes, left at zero as an unbaked node would be
    } else {
      sh[i].c[0] = glm::vec3(float(p.x + 10.0 * p.y + 100.0 * p.z));
    }
  }
  const GridVolume grid(layout, sh, invalid);
  EXPECT_EQ(grid.invalidNodes(), 50u);
  for (size_t i = 0; i < sh.size(); ++i) {
    if (!invalid[i]) continue;
    const glm::dvec3 p = layout.node(i);
    // The nearest valid node is the one at x = 2 on the same (y, z).
    const float want = float(2.0 + 10.0 * p.y + 100.0 * p.z);
    EXPECT_EQ(grid.sh()[i].c[0].r, want) << "node " << i;
    EXPECT_GT(grid.sh()[i].c[0].r, 0.0f);
  }
}

// The equal-bytes grid fits its budget (header + 56 bytes a node: ShHalf), covers the box, and is the finest that
// fits: 1 % less spacing goes over.
TEST(GridLayout, BytesFitTheBudgetAndAreTheFinestThatDo) {
  const glm::dvec3 lo(-7.5, 0.0, -3.0), hi(12.0, 6.5, 9.0);
  for (const uint64_t budget : {uint64_t(5000), uint64_t(123457), uint64_t(820000), uint64_t(6000000)}) {
    const GridLayout l = gridLayoutForBytes(lo, hi, budget);
    EXPECT_LE(l.bytes(), budget);
    EXPECT_EQ(l.bytes(), kGridHeaderBytes + 56 * l.nodes());
    const glm::dvec3 top = l.min + glm::dvec3(l.dims - 1) * l.step;
    for (int a = 0; a < 3; ++a) {
      EXPECT_LE(l.min[a], lo[a] + 1e-6 * l.step);  // covers the box up to rounding
      EXPECT_GE(top[a], hi[a] - 1e-6 * l.step);
      EXPECT_GE(l.dims[a], 2);
    }
    uint64_t finer = 1;
    for (int a = 0; a < 3; ++a)
      finer *=
          uint64_t(std::max<int64_t>(2, int64_t(std::ceil((hi[a] - lo[a]) / (0.99 * l.step) - 1e-9)) + 1));
    EXPECT_GT(kGridHeaderBytes + 56 * finer, budget) << "budget " << budget << ": a finer lattice also fits";
  }
  // At the probe count: at most that many nodes.
  EXPECT_LE(gridLayoutForNodes(lo, hi, 1025).nodes(), 1025u);
}

// A solid crate under the sky: nodes inside it are found invalid, not traced, and dilated from the nodes
// outside, so no node holds zero light (a zero node would darken every lookup near the crate).
TEST(GridBake, NodesInsideGeometryAreDilatedNotZero) {
  Scene s = test::floorUnderSky(glm::vec3(0.5f), glm::vec3(1.0f));
  const uint32_t m = test::addMaterial(s, glm::vec3(0.5f));
  test::addBox(s, {-1.0f, 0.0f, -1.0f}, {1.0f, 2.0f, 1.0f}, false, m);
  const SceneTracer tracer(s);
  const GridLayout layout = gridLayoutForNodes({-2.0, 0.5, -2.0}, {2.0, 3.0, 2.0}, 400);
  BakeOptions bake;
  bake.samplesPerProbe = 64;
  bake.progress = false;
  DeringOptions dering;
  GridBakeStats stats;
  const GridVolume grid = bakeGridVolume(tracer, layout, bake, dering, &stats);
  EXPECT_EQ(stats.nodes, layout.nodes());
  EXPECT_GT(stats.invalidNodes, 0u) << "some nodes lie inside the crate";
  size_t inside = 0;
  for (size_t i = 0; i < layout.nodes(); ++i) {
    const glm::dvec3 p = layout.node(i);
    const bool inCrate = std::abs(p.x) < 0.95 && std::abs(p.z) < 0.95 && p.y < 1.95;
    if (inCrate) {
      ++inside;
      EXPECT_TRUE(grid.invalid()[i]) << "node " << i << " inside the crate";
    }
    EXPECT_GT(grid.sh()[i].c[0].g, 0.05f) << "node " << i << " holds no light";
  }
  EXPECT_GT(inside, 0u);
}

// Both forms of the generator string split into their items, in order, keys trimmed; words without '='
// (the tool and its version) are not items.
TEST(GeneratorFields, SplitsTheOptionListAndTheEarlierItems) {
  using Fields = std::vector<std::pair<std::string, std::string>>;
  EXPECT_EQ(generatorFields("tetraprobe 0.1.0 bake --spacing=0.25 --dering=auto --seed=9"),
            (Fields{{"--spacing", "0.25"}, {"--dering", "auto"}, {"--seed", "9"}}));
  EXPECT_EQ(generatorFields("tetraprobe 0.1.0 bake; placement=voxel; samples=128; dering=0.5"),
            (Fields{{"placement", "voxel"}, {"samples", "128"}, {"dering", "0.5"}}));
  EXPECT_EQ(generatorFields("tetraprobe 0.1.0 bake --probes=a;b.csv --seed=1"),
            (Fields{{"--probes", "a;b.csv"}, {"--seed", "1"}}))
      << "a ';' in a file name does not make the option list the earlier form";
  EXPECT_TRUE(generatorFields("imported by hand").empty());
}

// The GPU pass (shaders/lighting_grid.comp) reads the same grid the same way as GridVolume::irradiance:
// per pixel within float rounding.
TEST(GridRender, GpuPassMatchesCpuLookup) {
  const GridLayout layout = gridLayoutForNodes({-3.0, -0.5, -3.0}, {3.0, 2.0, 3.0}, 500);
  std::vector<ShRgb> sh(layout.nodes());
  for (size_t i = 0; i < sh.size(); ++i) {
    const glm::dvec3 p = layout.node(i);
    for (int c = 0; c < kShCoeffCount; ++c)
      sh[i].c[size_t(c)] = glm::vec3(float(1.0 + 0.1 * c + 0.2 * std::sin(p.x + c)), float(0.5 + 0.1 * p.z),
                                     float(0.7 + 0.05 * c * std::cos(p.y * 2.0)));
  }
  const GridVolume grid(layout, sh, std::vector<uint8_t>(sh.size(), 0));
  const RenderMesh mesh = test::floorMesh();
  RenderView view = test::floorView(48, 32);
  view.mode = RenderMode::kIrradiance;
  RenderGrid g;
  g.min = layout.min;
  g.step = layout.step;
  g.dims = layout.dims;
  g.sh = grid.sh().data();
  RenderResult r;
  try {
    r = renderGridVolume(mesh, g, view);
  } catch (const std::runtime_error& e) {
    if (!test::isNoVulkan(e.what())) throw;
    TETRAPROBE_SKIP_MISSING(e.what());
  }
  const glm::dvec3 origin = glm::round(layout.min + glm::dvec3(layout.dims - 1) * layout.step * 0.5);
  size_t checked = 0;
  for (size_t i = 0; i < size_t(view.width * view.height); ++i) {
    if (r.position.rgba[4 * i + 3] == 0.0f) continue;
    const glm::dvec3 world =
        origin + glm::dvec3(r.position.rgba[4 * i], r.position.rgba[4 * i + 1], r.position.rgba[4 * i + 2]);
    const glm::vec3 n(r.normal.rgba[4 * i], r.normal.rgba[4 * i + 1], r.normal.rgba[4 * i + 2]);
    const glm::vec3 want = grid.irradiance(world, n);
    for (int c = 0; c < 3; ++c)
      ASSERT_NEAR(r.color.rgba[4 * i + size_t(c)], want[c], 1e-4 * (1.0 + std::abs(want[c])))
          << "pixel " << i;
    ++checked;
  }
  EXPECT_GT(checked, size_t(view.width * view.height / 2));
}

}  // namespace
}  // namespace tetraprobe
