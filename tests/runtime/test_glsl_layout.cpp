// The GLSL lookup's records and constants (shaders/tetraprobe_layout.glsl, tetraprobe.glsl, tetraprobe_sh.glsl)
// against the C++ that writes the buffers (runtime/gpu_layout.h and the headers it names), without a Vulkan
// device. Records: glslang compiles a shader that reads every block of tetraprobe_layout.glsl and reports the
// std430 offset, array stride and binding of every member (`-q --reflect-all-block-variables`), compared with
// offsetof / sizeof of the C++ struct; a member on either side that the other lacks fails. Constants: every
// TETRAPROBE_* macro with a value, every `const float` and every specialization constant of the three files is
// read from the source text and compared with its C++ twin (integers exactly, floats after rounding both to
// float, as the shader sees them); a GLSL constant without a twin here fails, so a new one must be named.
// GLSLANG_VALIDATOR (the glslang binary the build compiles the shaders with) comes from CMake.
// GCC 12 at -O1 with the sanitizers (make test-sanitize) reports -Wmaybe-uninitialized inside libstdc++'s
// <regex> (std::function members of its NFA states): a known false positive in the library's code, not here.
#if defined(__GNUC__) && !defined(__clang__)
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"
#endif
#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <optional>
#include <regex>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "tetraprobe/runtime/cell_grid.h"
#include "tetraprobe/runtime/face_blend.h"
#include "tetraprobe/runtime/gpu_layout.h"
#include "tetraprobe/runtime/lookup_constants.h"
#include "tetraprobe/runtime/occlusion.h"
#include "tetraprobe/runtime/occlusion_data.h"
#include "tetraprobe/runtime/sh.h"
#include "tetraprobe/runtime/shader_variant.h"

namespace tetraprobe {
namespace {

namespace fs = std::filesystem;

const fs::path kShaders = fs::path(TETRAPROBE_SOURCE_DIR) / "shaders";

std::string readText(const fs::path& path) {
  std::ifstream in(path);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

// One line of glslang's reflection: a block member (offset, strides) or a block (size, binding).
struct Reflected {
  long offset = -1, size = -1, binding = -1, arrayStride = -1, topLevelArrayStride = -1;
};
struct Reflection {
  std::map<std::string, Reflected> members;  // "tetraprobeGridMin", "tetraprobeOuterCells[0].n", ...
  std::map<std::string, Reflected> blocks;   // "TetraprobeGrid", ...
  std::string log;
};

long field(const std::string& line, const std::string& key) {
  const std::regex re(key + " (-?[0-9]+)");
  std::smatch m;
  return std::regex_search(line, m, re) ? std::stol(m[1]) : -1;
}

// Compiles `source` (a compute shader) with glslang and parses its reflection.
Reflection reflect(const std::string& source) {
  const fs::path dir = fs::path(testing::TempDir()) / "glsl_layout";
  fs::create_directories(dir);
  const fs::path shader = dir / "layout_probe.comp", spv = dir / "layout_probe.spv", log = dir / "log.txt";
  std::ofstream(shader) << source;
  const std::string cmd = std::string("\"") + GLSLANG_VALIDATOR +
                          "\" -V -q -l --reflect-all-block-variables -I\"" + kShaders.string() + "\" \"" +
                          shader.string() + "\" -o \"" + spv.string() + "\" > \"" + log.string() + "\" 2>&1";
  const int rc = std::system(cmd.c_str());
  Reflection r;
  r.log = readText(log);
  EXPECT_EQ(rc, 0) << r.log;
  std::istringstream in(r.log);
  std::string line, section;
  while (std::getline(in, line)) {
    if (!line.empty() && line.back() == ':') {
      section = line;
      continue;
    }
    const size_t colon = line.find(':');
    if (colon == std::string::npos) continue;
    const std::string name = line.substr(0, colon);
    Reflected e{field(line, "offset"), field(line, "size"), field(line, "binding"),
                field(line, "arrayStride"), field(line, "topLevelArrayStride")};
    if (section == "Uniform reflection:")
      r.members[name] = e;
    else if (section == "Uniform block reflection:")
      r.blocks[name] = e;
  }
  return r;
}

// A compute shader that reads one element of every block of tetraprobe_layout.glsl (glslang drops the blocks
// a shader does not use; --reflect-all-block-variables then lists all of each used block's members).
const char* kLayoutProbe = R"(#version 450
#extension GL_GOOGLE_include_directive : require
#include "tetraprobe_layout.glsl"
layout(local_size_x = 1) in;
layout(std430, set = 1, binding = 0) writeonly buffer Out { uint outValue; };
void main() {
  outValue = tetraprobeTetData[0] + tetraprobeTetStride + tetraprobeProbeData[0] + uint(tetraprobeGridMin.x) +
             uint(tetraprobeStartTet[0]) + uint(tetraprobeOuterCellCount) + uint(tetraprobeOuterCells[0].n[2]) +
             uint(tetraprobeCellData[0]) + tetraprobeOccData[0];
}
)";

struct ExpectedMember {
  const char* name;
  long offset;
  long arrayStride = -1;          // arrays of scalars: the element stride
  long topLevelArrayStride = -1;  // members of an array of structs: the struct's stride
};

struct ExpectedBlock {
  const char* name;
  GpuBinding binding;
  std::vector<ExpectedMember> members;
};

std::vector<ExpectedBlock> expectedBlocks() {
  const long outer = long(kGpuOuterCellsOffset), cellStride = long(sizeof(GpuOuterCell));
  return {
      {"TetraprobeTets",
       kGpuBindingTets,
       {{"tetraprobeTetVertexBits", long(offsetof(GpuTetHeader, vertexBits))},
        {"tetraprobeTetNeighbourBits", long(offsetof(GpuTetHeader, neighbourBits))},
        {"tetraprobeTetStride", long(offsetof(GpuTetHeader, strideUints))},
        {"tetraprobeTetRecords", long(offsetof(GpuTetHeader, count))},
        {"tetraprobeTetData", long(sizeof(GpuTetHeader)), long(sizeof(uint32_t))}}},
      {"TetraprobeProbes", kGpuBindingProbes, {{"tetraprobeProbeData", 0, long(sizeof(uint32_t))}}},
      {"TetraprobeGrid",
       kGpuBindingGrid,
       {{"tetraprobeGridMin", long(offsetof(GpuGridHeader, min))},
        {"tetraprobeTetCount", long(offsetof(GpuGridHeader, tetCount))},
        {"tetraprobeGridCellSize", long(offsetof(GpuGridHeader, cellSize))},
        {"tetraprobeProbeCount", long(offsetof(GpuGridHeader, probeCount))},
        {"tetraprobeGridDims", long(offsetof(GpuGridHeader, dims))},
        {"tetraprobeMaxWalkSteps", long(offsetof(GpuGridHeader, maxWalkSteps))},
        {"tetraprobeStartTet", long(kGpuGridStartTetOffset), long(sizeof(int32_t))}}},
      {"TetraprobeOuterCells",
       kGpuBindingOuterCells,
       {{"tetraprobeOuterCellCount", long(offsetof(GpuOuterHeader, count))},
        {"tetraprobeOuterCells[0].v", outer + long(offsetof(GpuOuterCell, v)), -1, cellStride},
        {"tetraprobeOuterCells[0].link", outer + long(offsetof(GpuOuterCell, link)), -1, cellStride},
        {"tetraprobeOuterCells[0].n", outer + long(offsetof(GpuOuterCell, n)), -1, cellStride}}},
      {"TetraprobeCells",
       kGpuBindingCells,
       {{"tetraprobeCellMin", long(offsetof(GpuCellGridHeader, min))},
        {"tetraprobeCellSize", long(offsetof(GpuCellGridHeader, cellSize))},
        {"tetraprobeCellSlotMask", long(offsetof(GpuCellGridHeader, slotMask))},
        {"tetraprobeCellMaxProbe", long(offsetof(GpuCellGridHeader, maxProbe))},
        {"tetraprobeCellBrickOffset", long(offsetof(GpuCellGridHeader, brickOffset))},
        {"tetraprobeCellBrickDim", long(offsetof(GpuCellGridHeader, brickDim))},
        {"tetraprobeCellData", long(sizeof(GpuCellGridHeader)), long(sizeof(int32_t))}}},
      {"TetraprobeOcclusion",
       kGpuBindingOcclusion,
       {{"tetraprobeOccTetCount", long(offsetof(GpuOcclusionHeader, tetCount))},
        {"tetraprobeOccPlaneOffset", long(offsetof(GpuOcclusionHeader, planeOffset))},
        {"tetraprobeOccShadowOffset", long(offsetof(GpuOcclusionHeader, shadowOffset))},
        {"tetraprobeOccPad", long(offsetof(GpuOcclusionHeader, pad))},
        {"tetraprobeOccData", long(sizeof(GpuOcclusionHeader)), long(sizeof(uint32_t))}}},
  };
}

// Every block of tetraprobe_layout.glsl has the binding of GpuBinding, and every member the offset (and
// strides) of its C++ field; no member on either side is unmatched.
TEST(GlslLayout, EveryBlockMemberHasTheCppOffsetAndBinding) {
  const Reflection r = reflect(kLayoutProbe);
  ASSERT_FALSE(r.members.empty()) << r.log;
  std::set<std::string> known;
  int blocks = 0;
  for (const ExpectedBlock& b : expectedBlocks()) {
    ++blocks;
    const auto block = r.blocks.find(b.name);
    ASSERT_NE(block, r.blocks.end()) << "block " << b.name << " missing from the GLSL\n" << r.log;
    EXPECT_EQ(block->second.binding, long(b.binding)) << b.name << ": binding (GpuBinding)";
    for (const ExpectedMember& m : b.members) {
      known.insert(m.name);
      const auto it = r.members.find(m.name);
      ASSERT_NE(it, r.members.end()) << b.name << "." << m.name << " missing from the GLSL\n" << r.log;
      EXPECT_EQ(it->second.offset, m.offset) << m.name << ": std430 offset in GLSL vs offsetof in C++";
      if (m.arrayStride >= 0) {
        EXPECT_EQ(it->second.arrayStride, m.arrayStride) << m.name << ": array stride";
      }
      if (m.topLevelArrayStride >= 0) {
        EXPECT_EQ(it->second.topLevelArrayStride, m.topLevelArrayStride) << m.name << ": struct array stride";
      }
    }
  }
  EXPECT_EQ(blocks, int(kGpuBindingCount));
  // Members the GLSL has and this table lacks (the shorter, unindexed names glslang also lists for members
  // the shader read, "tetraprobeOuterCells.n", are the same members).
  for (const auto& [name, e] : r.members) {
    if (name.find('.') != std::string::npos && name.find('[') == std::string::npos) continue;
    if (name == "outValue") continue;
    EXPECT_TRUE(known.count(name)) << "GLSL member " << name << " (offset " << e.offset
                                   << ") has no C++ twin in this test's table";
  }
}

// A GLSL constant's value as written: a decimal or hex literal (u suffix allowed), optionally in int(...).
std::optional<double> parseGlslValue(std::string v) {
  v = std::regex_replace(v, std::regex("^\\s+|\\s+$"), "");
  std::smatch m;
  if (std::regex_match(v, m, std::regex("int\\((0x[0-9A-Fa-f]+)u\\)")))
    return double(int32_t(uint32_t(std::stoul(m[1], nullptr, 16))));
  if (std::regex_match(v, m, std::regex("(0x[0-9A-Fa-f]+)u?"))) return double(std::stoul(m[1], nullptr, 16));
  if (std::regex_match(v, m, std::regex("([-+]?[0-9.]+(e[-+]?[0-9]+)?)u?"))) return std::stod(m[1]);
  if (v == "true") return 1.0;
  if (v == "false") return 0.0;
  return std::nullopt;
}

struct GlslConstant {
  std::string file, name, text;
};

// Every `#define TETRAPROBE_NAME value`, `const float NAME = value[, NAME = value]...;` and
// `layout(constant_id = TETRAPROBE_SPEC_ID + k) const T name = value;` of the lookup's GLSL files. Include
// guards and function-like macros have no value and are left out.
std::vector<GlslConstant> glslConstants(std::map<std::string, int>* specIds) {
  std::vector<GlslConstant> out;
  // Every file of the lookup (tetraprobe*.glsl), in name order: a file split off later is read too.
  std::vector<std::string> files;
  for (const fs::directory_entry& e : fs::directory_iterator(kShaders)) {
    const std::string name = e.path().filename().string();
    if (name.rfind("tetraprobe", 0) == 0 && e.path().extension() == ".glsl") files.push_back(name);
  }
  std::sort(files.begin(), files.end());
  EXPECT_GE(files.size(), 3u);
  for (const std::string& file : files) {
    // Macro continuation lines joined, so a value clang-format moved to the next line is read.
    const std::string text = std::regex_replace(readText(kShaders / file), std::regex("\\\\\n\\s*"), " ");
    EXPECT_FALSE(text.empty()) << file;
    const std::regex define(R"(#define\s+(TETRAPROBE_[A-Z0-9_]+)[ \t]+([^/\n]+))");
    for (auto it = std::sregex_iterator(text.begin(), text.end(), define); it != std::sregex_iterator(); ++it)
      out.push_back({file, (*it)[1], (*it)[2]});
    const std::regex constDecl(R"(\bconst\s+(float|int|uint)\s+([^;]+);)");
    for (auto it = std::sregex_iterator(text.begin(), text.end(), constDecl); it != std::sregex_iterator();
         ++it) {
      const std::string list = (*it)[2];
      const std::regex item(R"(([A-Za-z_][A-Za-z0-9_]*)\s*=\s*([^,]+))");
      for (auto j = std::sregex_iterator(list.begin(), list.end(), item); j != std::sregex_iterator(); ++j)
        out.push_back({file, (*j)[1], (*j)[2]});
    }
    const std::regex spec(
        R"(layout\(constant_id = TETRAPROBE_SPEC_ID \+ ([0-9]+)\) const \w+ (\w+) = (\w+);)");
    for (auto it = std::sregex_iterator(text.begin(), text.end(), spec); it != std::sregex_iterator(); ++it) {
      if (specIds) (*specIds)[(*it)[2]] = std::stoi((*it)[1]);
      out.push_back({file, (*it)[2], (*it)[3]});
    }
  }
  return out;
}

// The C++ twin of each GLSL constant, as the C++ uses it.
struct Twin {
  double value;
  bool isFloat;  // compared after rounding both sides to float (the shader's precision)
};

std::map<std::string, Twin> cppTwins() {
  const auto i = [](double v) { return Twin{v, false}; };
  const auto f = [](double v) { return Twin{v, true}; };
  return {
      // Configuration macros an engine may define before including (their defaults).
      {"TETRAPROBE_SET", i(0)},
      {"TETRAPROBE_BINDING", i(0)},
      {"TETRAPROBE_SPEC_ID", i(0)},
      // Records (gpu_layout.h, cell_grid.h, occlusion_data.h, sh_half.h).
      {"TETRAPROBE_POSITION_UINTS", i(kGpuPositionFloatsPerProbe)},
      {"TETRAPROBE_SH_UINTS", i(kGpuShUintsPerProbe)},
      // ShHalf::h[27] (after the 27 coefficients) is the high half of uint 27 / 2.
      {"TETRAPROBE_SH_SCALE_UINT", i((3 * kShCoeffCount) / 2)},
      {"TETRAPROBE_CELL_SLOT_INTS", i(sizeof(CellSlot) / sizeof(int32_t))},
      {"TETRAPROBE_EMPTY_LEAF", i(kEmptyLeaf)},
      {"TETRAPROBE_OCC_RECORD_UINTS", i(kGpuOccRecordUints)},
      {"TETRAPROBE_OCC_KIND_PLANES", i(kOcclusionPlanes)},
      {"TETRAPROBE_OCC_KIND_SHADOW_MAPS", i(kOcclusionShadowMaps)},
      {"TETRAPROBE_OCC_PROBE_MASK_SHIFT", i(kGpuOccProbeMaskShift)},
      {"TETRAPROBE_OCC_OFFSET_SHIFT", i(kGpuOccOffsetShift)},
      {"TETRAPROBE_OCC_PLANE_UINTS", i(sizeof(OcclusionPlane) / sizeof(uint32_t))},
      {"TETRAPROBE_OCC_PLANE_UNIT", f(OcclusionPlane::kOcclusionPlaneUnit)},
      {"TETRAPROBE_SHADOW_BLOCK_UINTS", i(kShadowMapBlockBytes / sizeof(uint32_t))},
      {"TETRAPROBE_SHADOW_PROBE_UINTS", i(kShadowMapTexels / sizeof(uint32_t))},
      {"TETRAPROBE_SHADOW_NO_HIT", i(kShadowMapNoHit)},
      {"TETRAPROBE_SHADOW_SCALE", f(kShadowMapScale)},
      // Point location (lookup_constants.h).
      {"TETRAPROBE_INSIDE_EPS", f(kLookupInsideEps)},
      {"TETRAPROBE_CYCLE_ACCEPT_EPS", f(kLookupCycleAcceptEps)},
      {"TETRAPROBE_MAX_HINT_STEPS", i(kLookupMaxHintSteps)},
      {"TETRAPROBE_MAX_OUTER_STEPS", i(kLookupMaxOuterSteps)},
      {"TETRAPROBE_OUTER_NEGLIGIBLE", f(kGpuOuterNegligible)},
      {"TETRAPROBE_OUTER_ZERO_ROOT", f(kGpuOuterZeroRoot)},
      {"TETRAPROBE_OUTER_MAX_T", f(kLookupOuterMaxT)},
      // Occlusion (occlusion.h) and the face blend (face_blend.h).
      {"TETRAPROBE_OCC_BIAS", f(kOcclusionBias)},
      {"TETRAPROBE_OCC_PLANE_HALF", f(kOcclusionPlaneFalloff)},
      {"TETRAPROBE_OCC_SHADOW_HALF", f(kOcclusionShadowFalloff)},
      {"TETRAPROBE_OCC_FALLBACK", f(kOcclusionFallbackSum)},
      {"TETRAPROBE_OCC_FRONT_SINE", f(kOcclusionFrontSine)},
      {"TETRAPROBE_OCC_BEHIND", f(kOcclusionBehindShare)},
      {"TETRAPROBE_FACE_BAND", f(kFaceBlendBand)},
      {"TETRAPROBE_FACE_TRUST", f(kFaceBlendFallbackTrust)},
      {"TETRAPROBE_FACE_FALLBACK_BAND", f(kFaceBlendFallbackBand)},
      {"TETRAPROBE_FACE_BLIND_SUM", f(kFaceBlendBlindSum)},
      {"TETRAPROBE_FACE_MAX_TETS", i(kFaceBlendMaxTets)},
      // SH (sh.h), rounded to float as the CPU's float(k).
      {"kTetraprobeY00", f(sh_const::kY00)},
      {"kTetraprobeY1", f(sh_const::kY1)},
      {"kTetraprobeY2n2", f(sh_const::kY2n2)},
      {"kTetraprobeY20", f(sh_const::kY20)},
      {"kTetraprobeY22", f(sh_const::kY22)},
      {"kTetraprobeA0", f(sh_const::kA0)},
      {"kTetraprobeA1", f(sh_const::kA1)},
      {"kTetraprobeA2", f(sh_const::kA2)},
      // Specialization constants: the generic variant's values (shader_variant.h).
      {"tetraprobeShOrder", i(kGenericShaderVariant.shOrder)},
      {"tetraprobeUsePlanes", i(kGenericShaderVariant.planes)},
      {"tetraprobeUseShadowMaps", i(kGenericShaderVariant.shadowMaps)},
      {"tetraprobeUseOuterCells", i(kGenericShaderVariant.outerCells)},
      {"tetraprobeUseCellGrid", i(kGenericShaderVariant.cellGrid)},
      {"tetraprobeSpecTetVertexBits", i(kGenericShaderVariant.tetVertexBits)},
      {"tetraprobeSpecTetNeighbourBits", i(kGenericShaderVariant.tetNeighbourBits)},
      {"tetraprobeSpecTetStride", i(kGenericShaderVariant.tetStride)},
  };
}

// Constants derived in GLSL from others (no literal to compare): named so that the test knows them.
const std::set<std::string> kDerived = {"tetraprobeShCount"};

// Constants of GPU-only code with no CPU mirror to drift from: the half-resolution upsample's rules
// (tetraprobe_upsample.glsl; the renderer runs them, nothing on the CPU does).
const std::set<std::string> kGlslOnly = {
    "TETRAPROBE_UPSAMPLE_MIN_WEIGHT", "TETRAPROBE_UPSAMPLE_PLANE_FOOTPRINTS",
    "TETRAPROBE_UPSAMPLE_MAX_SPREAD", "TETRAPROBE_UPSAMPLE_NORMAL_POWER"};

// Every valued constant of the lookup's GLSL equals its C++ twin, and every twin is found in the GLSL.
TEST(GlslLayout, EveryConstantEqualsItsCppTwin) {
  const std::map<std::string, Twin> twins = cppTwins();
  std::set<std::string> seen;
  const std::vector<GlslConstant> constants = glslConstants(nullptr);
  ASSERT_GT(constants.size(), 30u);
  for (const GlslConstant& c : constants) {
    if (kDerived.count(c.name) || kGlslOnly.count(c.name)) continue;
    const auto twin = twins.find(c.name);
    if (twin == twins.end()) {
      ADD_FAILURE() << c.file << ": " << c.name << " = " << c.text << " has no C++ twin in this test's table";
      continue;
    }
    seen.insert(c.name);
    const std::optional<double> v = parseGlslValue(c.text);
    ASSERT_TRUE(v) << c.file << ": " << c.name << " = '" << c.text << "' is not a literal this test reads";
    if (twin->second.isFloat)
      EXPECT_EQ(float(*v), float(twin->second.value))
          << c.file << ": " << c.name << " = " << c.text << " in GLSL, " << twin->second.value << " in C++";
    else
      EXPECT_EQ(*v, twin->second.value)
          << c.file << ": " << c.name << " = " << c.text << " in GLSL, " << twin->second.value << " in C++";
  }
  for (const auto& [name, twin] : twins)
    EXPECT_TRUE(seen.count(name)) << name << " (C++ " << twin.value << ") is not defined in the GLSL";
}

// The specialization constants' ids are ShaderSpecConstant's.
TEST(GlslLayout, SpecializationIdsAreShaderSpecConstants) {
  std::map<std::string, int> ids;
  glslConstants(&ids);
  const std::map<std::string, int> expected = {{"tetraprobeShOrder", kSpecShOrder},
                                               {"tetraprobeUsePlanes", kSpecPlanes},
                                               {"tetraprobeUseShadowMaps", kSpecShadowMaps},
                                               {"tetraprobeUseOuterCells", kSpecOuterCells},
                                               {"tetraprobeUseCellGrid", kSpecCellGrid},
                                               {"tetraprobeSpecTetVertexBits", kSpecTetVertexBits},
                                               {"tetraprobeSpecTetNeighbourBits", kSpecTetNeighbourBits},
                                               {"tetraprobeSpecTetStride", kSpecTetStride}};
  EXPECT_EQ(ids, expected);
  EXPECT_EQ(ids.size(), size_t(kShaderSpecConstantCount));
}

}  // namespace
}  // namespace tetraprobe
