// tetraprobe_variant.glsl: the shader variant's specialization constants (runtime/shader_variant.h).
// Part of the lookup of tetraprobe.glsl, whose contract holds here too: an engine includes tetraprobe.glsl,
// which includes this file. Permissive.
#ifndef TETRAPROBE_VARIANT_GLSL
#define TETRAPROBE_VARIANT_GLSL

// The shader variant (tetraprobe::ShaderSpecConstant, runtime/shader_variant.h; defaults: the generic one).
#ifndef TETRAPROBE_SPEC_ID
#define TETRAPROBE_SPEC_ID 0
#endif
layout(constant_id = TETRAPROBE_SPEC_ID + 0) const int tetraprobeShOrder = 2;  // 1: coefficients 0..3 only
layout(constant_id = TETRAPROBE_SPEC_ID + 1) const bool tetraprobeUsePlanes = true;
layout(constant_id = TETRAPROBE_SPEC_ID + 2) const bool tetraprobeUseShadowMaps = true;
layout(constant_id = TETRAPROBE_SPEC_ID + 3) const bool tetraprobeUseOuterCells = true;
layout(constant_id = TETRAPROBE_SPEC_ID + 4) const bool tetraprobeUseCellGrid = true;
// The level's tet packing (runtime/gpu_tets.h), so the record's shifts and masks fold; 0: read the
// TetraprobeTets header at run time.
layout(constant_id = TETRAPROBE_SPEC_ID + 5) const uint tetraprobeSpecTetVertexBits = 0u;
layout(constant_id = TETRAPROBE_SPEC_ID + 6) const uint tetraprobeSpecTetNeighbourBits = 0u;
layout(constant_id = TETRAPROBE_SPEC_ID + 7) const uint tetraprobeSpecTetStride = 0u;

#endif  // TETRAPROBE_VARIANT_GLSL
