// The shader variant a level needs (shader_variant.h): which occlusion kinds, SH band and location
// accelerators the GLSL lookup must keep, read from the level and what is uploaded with it.
#include "tetraprobe/runtime/shader_variant.h"

#include "tetraprobe/runtime/gpu_tets.h"

namespace tetraprobe {

void ShaderVariant::specValues(uint32_t out[kShaderSpecConstantCount]) const {
  out[kSpecShOrder] = shOrder;
  out[kSpecPlanes] = planes ? 1u : 0u;
  out[kSpecShadowMaps] = shadowMaps ? 1u : 0u;
  out[kSpecOuterCells] = outerCells ? 1u : 0u;
  out[kSpecCellGrid] = cellGrid ? 1u : 0u;
  out[kSpecTetVertexBits] = tetVertexBits;
  out[kSpecTetNeighbourBits] = tetNeighbourBits;
  out[kSpecTetStride] = tetStride;
}

std::string ShaderVariant::name() const {
  std::string s = shOrder == 1 ? "l1" : "l2";
  if (planes) s += "+planes";
  if (shadowMaps) s += "+shadow_maps";
  if (outerCells) s += "+outer";
  if (cellGrid) s += "+cells";
  return s;
}

bool parseShaderVariant(const std::string& name, ShaderVariant& out) {
  // 32 variants: compare with each one's name.
  for (uint32_t bits = 0; bits < 32; ++bits) {
    const ShaderVariant v{(bits & 1u) ? 2u : 1u, (bits & 2u) != 0, (bits & 4u) != 0, (bits & 8u) != 0,
                          (bits & 16u) != 0};
    if (v.name() == name) {
      out = v;
      return true;
    }
  }
  return false;
}

ShaderVariant shaderVariantFor(const Level& level, const std::vector<OuterCell>& outerCells,
                               const CellGrid& cellGrid) {
  ShaderVariant v;
  v.shOrder = 2;
  if (level.shOrder == 1) {
    bool bandTwoZero = true;
    for (const ShRgb& sh : level.sh)
      for (int i = 4; i < kShCoeffCount && bandTwoZero; ++i) bandTwoZero = sh.c[size_t(i)] == glm::vec3(0.0f);
    if (bandTwoZero) v.shOrder = 1;
  }
  v.planes = v.shadowMaps = false;
  for (const TetOcclusion& t : level.occlusion.tets) {
    v.planes = v.planes || t.kind() == kOcclusionPlanes;
    v.shadowMaps = v.shadowMaps || t.kind() == kOcclusionShadowMaps;
  }
  v.outerCells = !outerCells.empty();
  v.cellGrid = !cellGrid.slots.empty();
  const GpuTetPacking packing = gpuTetPacking(level.probes.size(), level.tets.size());
  v.tetVertexBits = packing.vertexBits;
  v.tetNeighbourBits = packing.neighbourBits;
  v.tetStride = packing.strideUints;
  return v;
}

bool shaderVariantCovers(const ShaderVariant& variant, const ShaderVariant& needed) {
  return variant.shOrder >= needed.shOrder && (variant.planes || !needed.planes) &&
         (variant.shadowMaps || !needed.shadowMaps) && (variant.outerCells || !needed.outerCells) &&
         (variant.cellGrid || !needed.cellGrid) &&
         ((variant.tetVertexBits == 0 && variant.tetNeighbourBits == 0 && variant.tetStride == 0) ||
          (variant.tetVertexBits == needed.tetVertexBits &&
           variant.tetNeighbourBits == needed.tetNeighbourBits && variant.tetStride == needed.tetStride));
}

std::vector<ShaderVariant> coveringShaderVariants(const ShaderVariant& needed) {
  std::vector<ShaderVariant> out{needed};
  const auto add = [&out](const ShaderVariant& v) {
    for (const ShaderVariant& o : out)
      if (o.name() == v.name()) return;
    out.push_back(v);
  };
  ShaderVariant v = needed;
  v.shOrder = 2;
  add(v);
  v = needed;
  v.planes = true;
  add(v);
  v = needed;
  v.shadowMaps = true;
  add(v);
  v = needed;
  v.outerCells = true;
  add(v);
  v = needed;
  v.cellGrid = true;
  add(v);
  add(kGenericShaderVariant);
  return out;
}

}  // namespace tetraprobe
