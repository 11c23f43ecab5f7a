// Which parts of the GLSL lookup (shaders/tetraprobe.glsl) a level needs: its shader variant. The lookup reads
// five Vulkan specialization constants; an engine specializes its pipeline with the level's variant so code
// the level cannot reach (shadow-map occlusion on a level with none, SH band 2 of an L1 level, ...) is removed
// by the driver's compiler. VkSpecializationInfo for a variant: shaderSpecialization() in vulkan_upload.h.
// Permissive: standard library only.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "tetraprobe/runtime/cell_grid.h"
#include "tetraprobe/runtime/level.h"

namespace tetraprobe {

// The specialization constants, constant_id TETRAPROBE_SPEC_ID + index (default base 0), each a 32-bit
// scalar (int or VkBool32) as tetraprobe.glsl declares them. Defaults in the GLSL are the generic variant.
enum ShaderSpecConstant : uint32_t {
  kSpecShOrder = 0,     // int tetraprobeShOrder: 1 blends and evaluates coefficients 0..3, 2 all 9
  kSpecPlanes = 1,      // bool tetraprobeUsePlanes: evaluate splitting-plane occlusion records
  kSpecShadowMaps = 2,  // bool tetraprobeUseShadowMaps: evaluate shadow-map occlusion records
  kSpecOuterCells = 3,  // bool tetraprobeUseOuterCells: continue outside the hull across the outer cells
  kSpecCellGrid = 4,    // bool tetraprobeUseCellGrid: start walks from the start bricks (start_bricks.h)
  // The level's tet packing (gpu_tets.h), so the driver folds the record's shifts and masks; 0: read from the
  // TetraprobeTets header at run time (right for any level, slower).
  kSpecTetVertexBits = 5,     // uint tetraprobeSpecTetVertexBits
  kSpecTetNeighbourBits = 6,  // uint tetraprobeSpecTetNeighbourBits
  kSpecTetStride = 7,         // uint tetraprobeSpecTetStride
  kShaderSpecConstantCount = 8,
};

// One variant. A feature turned off is not compiled in (after specialization): a level that holds such data
// gives wrong answers with it, so use shaderVariantFor() (or a variant that covers it).
struct ShaderVariant {
  uint32_t shOrder = 2;    // 1 or 2
  bool planes = true;      // occlusion records of kind kOcclusionPlanes are evaluated
  bool shadowMaps = true;  // occlusion records of kind kOcclusionShadowMaps are evaluated
  bool outerCells = true;  // points outside the hull go across the outer cells (else: the clamped hull tet)
  bool cellGrid = true;    // walks start from the start bricks (else from the coarse start grid)
  // The tet packing the level uploads with (gpuTetPacking), all three or none (0: read from the buffer).
  // Not a feature: name() leaves it out, and any packing is covered by 0.
  uint32_t tetVertexBits = 0, tetNeighbourBits = 0, tetStride = 0;

  bool operator==(const ShaderVariant&) const = default;
  // The 32-bit values of constants 0..7 in ShaderSpecConstant order (bools as 0 / 1).
  void specValues(uint32_t out[kShaderSpecConstantCount]) const;
  // A stable name: "l1" or "l2", then "+planes", "+shadow_maps", "+outer", "+cells" for the features on,
  // e.g. "l2+planes+outer+cells".
  std::string name() const;
};

// Parses a name() back ("l1" or "l2", then any of "+planes", "+shadow_maps", "+outer", "+cells" in that
// order); false (and `out` unchanged) for anything else.
bool parseShaderVariant(const std::string& name, ShaderVariant& out);

// Every feature on: right for any level (the GLSL defaults, used when a pipeline is not specialized).
inline constexpr ShaderVariant kGenericShaderVariant{};

// The smallest variant that answers exactly as the generic one for `level` uploaded with `outerCells` and
// `cellGrid` (the arguments given to uploadLevelBuffers): SH order 1 when Level::shOrder is 1 and every
// probe's coefficients 4..8 are zero; planes / shadow maps when some tet's occlusion record is of that kind;
// outer cells when `outerCells` is not empty; the cell grid when it has slots; the level's tet packing
// (gpuTetPacking). O(probes + tets).
ShaderVariant shaderVariantFor(const Level& level, const std::vector<OuterCell>& outerCells,
                               const CellGrid& cellGrid);

// True when `variant` has every feature `needed` has (and an SH order at least as high) and either no tet
// packing (read at run time) or needed's: its answers for a level that needs `needed` are the same.
bool shaderVariantCovers(const ShaderVariant& variant, const ShaderVariant& needed);

// The variants that cover `needed`: `needed` itself first, then each with one more feature turned on
// (order 2, planes, shadow maps, outer cells, cell grid, in that order, those not already on), then the
// generic variant; none twice by name (the ones with features added keep needed's tet packing; the generic
// one reads it at run time). What `tetraprobe bench render` times.
std::vector<ShaderVariant> coveringShaderVariants(const ShaderVariant& needed);

}  // namespace tetraprobe
