// Shader variants (runtime/shader_variant.h, the specialization constants of shaders/tetraprobe.glsl): which
// variant a level gets, that each variant's GPU output is the CPU query's on levels that use its features,
// that leaving out a feature a level uses is visible (the constants take effect), and that no shipping
// shader holds the O(tets) scan.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <optional>
#include <string>
#include <vector>

#include "debug_occlusion.comp.h"
#include "debug_tets.comp.h"
#include "lighting.comp.h"
#include "lighting_debug_scan.comp.h"
#include "lookup_scene.h"
#include "tetraprobe/runtime/gpu_tets.h"
#include "tetraprobe/runtime/shader_variant.h"
#include "tetraprobe/runtime/vulkan_upload.h"

namespace tetraprobe {
namespace {

using namespace tetraprobe::test;

// The synthetic occlusion with only the records of `keep` (the others become kOcclusionNone).
LevelOcclusion occlusionOfKind(const Level& level, OcclusionKind keep) {
  LevelOcclusion occ = syntheticOcclusion(level);
  for (TetOcclusion& t : occ.tets)
    if (t.kind() != keep) t = makeTetOcclusion(kOcclusionNone, 0, 0, 0);
  return occ;
}

// An L1 level: the lattice's SH with coefficients 4..8 zeroed.
Level makeL1Level() {
  Level level = makeLevel();
  level.shOrder = 1;
  for (ShRgb& sh : level.sh)
    for (int i = 4; i < kShCoeffCount; ++i) sh.c[size_t(i)] = glm::vec3(0.0f);
  return level;
}

ShaderVariant variantOf(const Level& level) {
  const ProbeQuery query(level);
  return shaderVariantFor(level, query.outerCells(), query.cellGrid());
}

// A level without occlusion gets a variant with both occlusion kinds off, and its VkSpecializationInfo says
// so: constants 1 and 2 are 0 (the shader's occlusion code is then dead and compiled out).
TEST(ShaderVariant, LevelWithoutOcclusionDisablesIt) {
  const ShaderVariant v = variantOf(makeLevel());
  EXPECT_FALSE(v.planes);
  EXPECT_FALSE(v.shadowMaps);
  EXPECT_EQ(v.shOrder, 2u);
  EXPECT_TRUE(v.outerCells);
  EXPECT_TRUE(v.cellGrid);
  EXPECT_EQ(v.name(), "l2+outer+cells");
  ShaderSpecialization spec;
  shaderSpecialization(v, 0, spec);
  ASSERT_EQ(spec.info.mapEntryCount, uint32_t(kShaderSpecConstantCount));
  ASSERT_EQ(spec.info.dataSize, kShaderSpecConstantCount * sizeof(uint32_t));
  const auto* data = static_cast<const uint32_t*>(spec.info.pData);
  for (uint32_t i = 0; i < kShaderSpecConstantCount; ++i) {
    EXPECT_EQ(spec.info.pMapEntries[i].constantID, i);
    EXPECT_EQ(spec.info.pMapEntries[i].offset, 4 * i);
    EXPECT_EQ(spec.info.pMapEntries[i].size, 4u);
  }
  EXPECT_EQ(data[kSpecShOrder], 2u);
  EXPECT_EQ(data[kSpecPlanes], 0u);
  EXPECT_EQ(data[kSpecShadowMaps], 0u);
  EXPECT_EQ(data[kSpecOuterCells], 1u);
  EXPECT_EQ(data[kSpecCellGrid], 1u);
}

// Each occlusion kind the level stores is on, the other off.
TEST(ShaderVariant, OcclusionKindsPresentAreOn) {
  Level level = makeLevel();
  level.occlusion = occlusionOfKind(level, kOcclusionPlanes);
  ShaderVariant v = variantOf(level);
  EXPECT_TRUE(v.planes);
  EXPECT_FALSE(v.shadowMaps);
  level.occlusion = occlusionOfKind(level, kOcclusionShadowMaps);
  v = variantOf(level);
  EXPECT_FALSE(v.planes);
  EXPECT_TRUE(v.shadowMaps);
  level.occlusion = syntheticOcclusion(level);
  v = variantOf(level);
  EXPECT_TRUE(v.planes && v.shadowMaps);
  EXPECT_EQ(v.name(), kGenericShaderVariant.name());
  // Every feature on, and the level's tet packing, which the generic variant reads at run time.
  const GpuTetPacking packing = gpuTetPacking(level.probes.size(), level.tets.size());
  EXPECT_EQ(v.tetVertexBits, packing.vertexBits);
  EXPECT_EQ(v.tetNeighbourBits, packing.neighbourBits);
  EXPECT_EQ(v.tetStride, packing.strideUints);
  EXPECT_TRUE(shaderVariantCovers(kGenericShaderVariant, v));
  ShaderVariant other = v;
  other.tetStride += 1;
  EXPECT_FALSE(shaderVariantCovers(other, v)) << "another level's packing reads the wrong words";
}

// L1 only when the level says so and band 2 really is zero (an L2 coefficient left in would be dropped).
TEST(ShaderVariant, L1OnlyWhenBandTwoIsZero) {
  Level level = makeL1Level();
  EXPECT_EQ(variantOf(level).shOrder, 1u);
  level.sh[3].c[7] = glm::vec3(0.0f, 1e-6f, 0.0f);
  EXPECT_EQ(variantOf(level).shOrder, 2u);
}

TEST(ShaderVariant, CoveringVariantsCoverTheLevelsOwnFirst) {
  for (const ShaderVariant needed : {ShaderVariant{1, false, false, true, true},
                                     ShaderVariant{2, true, false, true, true}, kGenericShaderVariant}) {
    const std::vector<ShaderVariant> all = coveringShaderVariants(needed);
    ASSERT_FALSE(all.empty());
    EXPECT_EQ(all.front(), needed);
    EXPECT_EQ(all.back(), kGenericShaderVariant);
    for (size_t i = 0; i < all.size(); ++i) {
      EXPECT_TRUE(shaderVariantCovers(all[i], needed)) << all[i].name();
      for (size_t j = 0; j < i; ++j) EXPECT_NE(all[i], all[j]);
    }
  }
  // itself, + order 2, + planes, + shadow maps, generic
  EXPECT_EQ(coveringShaderVariants(ShaderVariant{1, false, false, true, true}).size(), 5u);
  EXPECT_FALSE(shaderVariantCovers(ShaderVariant{1, true, true, true, true}, kGenericShaderVariant));
}

TEST(ShaderVariant, SpecializationTakesTheFirstConstantId) {
  ShaderSpecialization spec;
  shaderSpecialization(ShaderVariant{1, true, false, false, true}, 10, spec);
  for (uint32_t i = 0; i < kShaderSpecConstantCount; ++i) EXPECT_EQ(spec.entries[i].constantID, 10 + i);
  EXPECT_EQ(spec.data[kSpecShOrder], 1u);
  EXPECT_EQ(spec.data[kSpecPlanes], 1u);
  EXPECT_EQ(spec.data[kSpecShadowMaps], 0u);
  EXPECT_EQ(spec.data[kSpecOuterCells], 0u);
}

// --- SPIR-V ----------------------------------------------------------------------------------------------

bool spirvHasString(const uint32_t* code, size_t bytes, const char* text) {
  const auto* p = reinterpret_cast<const char*>(code);
  const size_t n = std::strlen(text);
  for (size_t i = 0; i + n <= bytes; ++i)
    if (std::memcmp(p + i, text, n) == 0) return true;
  return false;
}

// The SpecId decorations (OpDecorate %x SpecId N: opcode 71, decoration 1) of a module.
std::vector<uint32_t> specIds(const uint32_t* code, size_t bytes) {
  std::vector<uint32_t> ids;
  for (size_t i = 5; i < bytes / 4;) {
    const uint32_t count = code[i] >> 16, op = code[i] & 0xFFFFu;
    if (count == 0) break;
    if (op == 71 && count >= 4 && code[i + 2] == 1) ids.push_back(code[i + 3]);
    i += count;
  }
  return ids;
}

// No shipping shader that includes tetraprobe.glsl holds the O(tets) or O(outer cells) scan: their functions
// are not in the SPIR-V (glslang keeps function names, OpName, as the debug build shows), so no pipeline made
// from it can run one. The shipping lookup declares the eight specialization constants.
TEST(ShaderVariant, ShippingShadersHaveNoScanLoop) {
  struct Module {
    const char* name;
    const uint32_t* code;
    size_t bytes;
  };
  const Module shipping[] = {
      {"lighting.comp", kSpirv_lighting_comp, sizeof(kSpirv_lighting_comp)},
      {"debug_tets.comp", kSpirv_debug_tets_comp, sizeof(kSpirv_debug_tets_comp)},
      {"debug_occlusion.comp", kSpirv_debug_occlusion_comp, sizeof(kSpirv_debug_occlusion_comp)}};
  for (const Module& m : shipping) {
    EXPECT_TRUE(spirvHasString(m.code, m.bytes, "tetraprobeWalk")) << m.name << ": names must be kept";
    EXPECT_FALSE(spirvHasString(m.code, m.bytes, "tetraprobeScanAll")) << m.name;
    EXPECT_FALSE(spirvHasString(m.code, m.bytes, "tetraprobeOuterScan")) << m.name;
  }
  // The check finds the scan where the debug macro compiles it in.
  EXPECT_TRUE(spirvHasString(kSpirv_lighting_debug_scan_comp, sizeof(kSpirv_lighting_debug_scan_comp),
                             "tetraprobeScanAll"));
  EXPECT_TRUE(spirvHasString(kSpirv_lighting_debug_scan_comp, sizeof(kSpirv_lighting_debug_scan_comp),
                             "tetraprobeOuterScan"));
  std::vector<uint32_t> ids = specIds(kSpirv_lighting_comp, sizeof(kSpirv_lighting_comp));
  std::sort(ids.begin(), ids.end());
  EXPECT_EQ(ids, (std::vector<uint32_t>{0, 1, 2, 3, 4, 5, 6, 7}));
}

// --- GPU against CPU per variant ----------------------------------------------------------------------------

struct Comparison {
  int pixels = 0, bad = 0;  // bad: relative error >= 1e-4 in some channel
  double worst = 0.0;
  bool skipped = false;  // no Vulkan driver or device: `why` says which
  std::string why;
};

// Renders the lookup scene's irradiance with `options` and compares every geometry pixel with
// ProbeQuery::irradiance (the tolerance of GpuLookup.MatchesCpuQueryPerPixel: relative 1e-4 per channel).
Comparison compareWithCpu(const Level& level, const RenderOptions& options, RenderResult* out = nullptr,
                          float cellSize = 16.0f) {
  Comparison c;
  const ProbeQuery query(level, cellSize);
  const RenderView view = makeView(RenderMode::kIrradiance, 480, 270);
  RenderResult r;
  std::string skip;
  if (!render(makeMesh(), level, query, view, r, skip, options)) {
    c.skipped = true;
    c.why = skip;
    return c;
  }
  for (size_t i = 0; i < size_t(view.width) * view.height; ++i) {
    if (r.position.rgba[4 * i + 3] == 0.0f) continue;
    const glm::dvec3 world = level.origin + glm::dvec3(px3(r.position, i));
    const glm::vec3 cpu = query.irradiance(world, px3(r.normal, i)), gpu = px3(r.color, i);
    double rel = 0.0;
    for (int ch = 0; ch < 3; ++ch)
      rel = std::max(rel, std::abs(double(gpu[ch]) - cpu[ch]) / std::max(std::abs(double(cpu[ch])), 1e-6));
    c.worst = std::max(c.worst, rel);
    c.bad += rel >= 1e-4;
    ++c.pixels;
  }
  if (out) *out = std::move(r);
  return c;
}

struct NamedLevel {
  const char* name;
  Level level;
};

std::vector<NamedLevel> variantLevels() {
  std::vector<NamedLevel> out;
  out.push_back({"no occlusion", makeLevel()});
  out.push_back({"planes", makeLevel()});
  out.back().level.occlusion = occlusionOfKind(out.back().level, kOcclusionPlanes);
  out.push_back({"shadow maps", makeLevel()});
  out.back().level.occlusion = occlusionOfKind(out.back().level, kOcclusionShadowMaps);
  out.push_back({"both", makeLevel()});
  out.back().level.occlusion = syntheticOcclusion(out.back().level);
  out.push_back({"L1", makeL1Level()});
  out.push_back({"L1 + both", makeL1Level()});
  out.back().level.occlusion = syntheticOcclusion(out.back().level);
  return out;
}

// Every level gets its own variant (reported in RenderResult::variant) and that variant's output equals the
// CPU query per pixel: six levels, six variants, exercising L1 and L2, no occlusion, planes only, shadow maps
// only and both (the last is the generic variant; the L1 levels' own variants skip band 2).
TEST(GpuVariants, EachVariantMatchesCpuOnTheLevelsThatUseIt) {
  std::vector<ShaderVariant> seen;
  for (const NamedLevel& nl : variantLevels()) {
    const ShaderVariant own = variantOf(nl.level);
    for (const ShaderVariant& s : seen)
      EXPECT_NE(s, own) << nl.name << ": each level exercises a new variant";
    seen.push_back(own);
    RenderResult r;
    const Comparison c = compareWithCpu(nl.level, RenderOptions{}, &r);
    if (c.skipped) TETRAPROBE_SKIP_MISSING(c.why);
    EXPECT_EQ(r.variant, own) << "the renderer specializes with the level's own variant";
    std::printf("%-12s variant %-38s %d pixels, worst relative error %.3g\n", nl.name, own.name().c_str(),
                c.pixels, c.worst);
    EXPECT_GT(c.pixels, 10000);
    EXPECT_EQ(c.bad, 0) << nl.name << " with variant " << own.name();
  }
}

// The constants take effect: a variant without a feature the level uses answers differently on many pixels
// (so the variants above were really different programs).
TEST(GpuVariants, VariantWithoutAFeatureTheLevelUsesDiffers) {
  Level level = makeLevel();
  level.occlusion = syntheticOcclusion(level);
  const ShaderVariant cases[] = {{2, false, true, true, true},
                                 {2, true, false, true, true},
                                 {1, true, true, true, true},
                                 {2, true, true, false, true}};
  for (const ShaderVariant& v : cases) {
    RenderOptions options;
    options.variant = v;
    const Comparison c = compareWithCpu(level, options);
    if (c.skipped) TETRAPROBE_SKIP_MISSING(c.why);
    std::printf("variant %-28s on a level using everything: %d of %d pixels off by 1e-4 or more\n",
                v.name().c_str(), c.bad, c.pixels);
    EXPECT_GT(c.bad, 500) << v.name();
  }
}

// The tet packing read from the buffer at run time (the generic variant) and folded from the level's
// specialization constants give the same pixels, bit for bit; a wrong packing in the constants is read (many
// pixels off), so the constants are what the specialized lookup uses.
TEST(GpuVariants, TetPackingFromConstantsEqualsPackingReadAtRunTime) {
  Level level = makeLevel();
  level.occlusion = syntheticOcclusion(level);
  RenderResult own, generic;
  const Comparison a = compareWithCpu(level, RenderOptions{}, &own);
  if (a.skipped) TETRAPROBE_SKIP_MISSING(a.why);
  EXPECT_NE(own.variant.tetStride, 0u) << "the renderer specializes with the level's packing";
  RenderOptions options;
  options.variant = kGenericShaderVariant;
  const Comparison b = compareWithCpu(level, options, &generic);
  EXPECT_EQ(a.bad, 0);
  EXPECT_EQ(b.bad, 0);
  ASSERT_EQ(own.color.rgba.size(), generic.color.rgba.size());
  size_t differ = 0;
  for (size_t i = 0; i < own.color.rgba.size(); ++i) differ += own.color.rgba[i] != generic.color.rgba[i];
  EXPECT_EQ(differ, 0u);
  ShaderVariant wrong = own.variant;
  wrong.tetVertexBits += 1;
  options.variant = wrong;
  const Comparison c = compareWithCpu(level, options);
  std::printf("tet packing %u/%u bits, stride %u: a vertex width one bit off puts %d of %d pixels off\n",
              own.variant.tetVertexBits, own.variant.tetNeighbourBits, own.variant.tetStride, c.bad,
              c.pixels);
  EXPECT_GT(c.bad, 500);
}

// The shipping lookup (no scan) and the debug build that scans every tet and outer cell after a failed walk
// give the same pixels, bit for bit: on these levels no walk fails, so the scan guards nothing the shipping
// path needs (docs/rendering.md#shader-variants). Small cells too: cell borders and absent cells in view.
TEST(GpuVariants, ShippingLookupEqualsDebugScanBuild) {
  for (float cellSize : {16.0f, 0.5f}) {
    Level level = makeLevel();
    level.occlusion = syntheticOcclusion(level);
    RenderResult shipping, debug;
    const Comparison a = compareWithCpu(level, RenderOptions{}, &shipping, cellSize);
    if (a.skipped) TETRAPROBE_SKIP_MISSING(a.why);
    RenderOptions options;
    options.lightingSpirv = kSpirv_lighting_debug_scan_comp;
    options.lightingSpirvBytes = sizeof(kSpirv_lighting_debug_scan_comp);
    const Comparison b = compareWithCpu(level, options, &debug, cellSize);
    EXPECT_EQ(a.bad, 0);
    EXPECT_EQ(b.bad, 0);
    ASSERT_EQ(shipping.color.rgba.size(), debug.color.rgba.size());
    size_t differ = 0;
    for (size_t i = 0; i < shipping.color.rgba.size(); ++i)
      differ += shipping.color.rgba[i] != debug.color.rgba[i];
    EXPECT_EQ(differ, 0u) << "cell size " << cellSize;
  }
}

}  // namespace
}  // namespace tetraprobe
