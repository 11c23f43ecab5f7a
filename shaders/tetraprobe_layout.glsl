// tetraprobe_layout.glsl: the GPU buffers of one uploaded level (std430) and the constants of their records.
// Mirrored field for field in runtime/include/tetraprobe/runtime/gpu_layout.h, where sizes and offsets are
// static_assert'ed; tests/runtime/test_glsl_layout.cpp compiles this file with glslang and fails when one block
// offset, array stride, binding or constant here differs from the C++ (no Vulkan device needed). Permissive.
//
// Bindings (all storage buffers, read-only) in descriptor set TETRAPROBE_SET (tetraprobe::GpuBinding):
//   TETRAPROBE_BINDING + 0  TetraprobeTets  the tets, packed (tetraprobe::GpuTetHeader, runtime/gpu_tets.h)
//   TETRAPROBE_BINDING + 1  TetraprobeProbes  positions (3 floats a probe), then SH (tetraprobe::ShHalf, 14 uints
//                           a probe)
//   TETRAPROBE_BINDING + 2  TetraprobeGrid  the walk's start grid: a 48-byte header, then one int per cell
//   TETRAPROBE_BINDING + 3  TetraprobeOuterCells  the outer cells: a 16-byte header, then 48 bytes per cell
//   TETRAPROBE_BINDING + 4  TetraprobeCells  the start bricks: a 32-byte header, then int data (hash slots,
//                           bricks of start tets)
//   TETRAPROBE_BINDING + 5  TetraprobeOcclusion  per-tet occlusion: a 16-byte header, then uint data
// Define the macros before including to move them (tetraprobe::levelDescriptorBindings takes the same numbers).
#ifndef TETRAPROBE_LAYOUT_GLSL
#define TETRAPROBE_LAYOUT_GLSL

#ifndef TETRAPROBE_SET
#define TETRAPROBE_SET 0
#endif
#ifndef TETRAPROBE_BINDING
#define TETRAPROBE_BINDING 0
#endif

// Record constants (C++ names in brackets; checked against them by tests/runtime/test_glsl_layout.cpp).
#define TETRAPROBE_POSITION_UINTS 3  // a probe's position in TetraprobeProbes [kGpuPositionFloatsPerProbe]
#define TETRAPROBE_SH_UINTS 14       // a probe's ShHalf in TetraprobeProbes [kGpuShUintsPerProbe]
#define TETRAPROBE_SH_SCALE_UINT 13  // the uint whose high half holds the probe's scale [ShHalf::h[27]]
#define TETRAPROBE_CELL_SLOT_INTS 4  // a hash slot: key x, y, z, brick [CellSlot]
#define TETRAPROBE_EMPTY_LEAF int(0x80000000u)  // an empty slot's key x [kEmptyLeaf]
#define TETRAPROBE_OCC_RECORD_UINTS 1u          // a tet's occlusion record: its header [kGpuOccRecordUints]
#define TETRAPROBE_OCC_KIND_PLANES 1u           // header & 3 [kOcclusionPlanes]
#define TETRAPROBE_OCC_KIND_SHADOW_MAPS 2u      // header & 3 [kOcclusionShadowMaps]
#define TETRAPROBE_OCC_PROBE_MASK_SHIFT 4u      // (header >> it) & 15: probe flags [kGpuOccProbeMaskShift]
#define TETRAPROBE_OCC_OFFSET_SHIFT 8u          // header >> it: the first plane or block [kGpuOccOffsetShift]
#define TETRAPROBE_OCC_PLANE_UINTS 2u           // a plane: four snorm16 [OcclusionPlane]
// snorm16 to float: the float nearest 1 / 32767 [OcclusionPlane::kOcclusionPlaneUnit]
#define TETRAPROBE_OCC_PLANE_UNIT 3.0518509447574615e-05
#define TETRAPROBE_SHADOW_BLOCK_UINTS 16u  // a tet's four shadow maps [kShadowMapBlockBytes / 4]
#define TETRAPROBE_SHADOW_PROBE_UINTS 4u   // one probe's shadow map [kShadowMapTexels / 4]
#define TETRAPROBE_SHADOW_NO_HIT 255u  // a lattice depth byte: nothing met before the face [kShadowMapNoHit]
#define TETRAPROBE_SHADOW_SCALE 254.0  // depth byte = round(254 f) [kShadowMapScale]

// The tets (tetraprobe::GpuTetHeader, runtime/gpu_tets.h): a header, then one record of tetraprobeTetStride
// uints a tet, fields least significant bit first: v[0..3] (probe indices, tetraprobeTetVertexBits each), then
// n[0..3] (tetraprobeTetNeighbourBits each: the tet across the face opposite v[i], + 1; 0 on the hull); then
// one zero uint. Read them with tetraprobeTetVertices and tetraprobeTetNeighbour (tetraprobe_tets.glsl).
// Barycentrics come from the four probe positions (tetraprobeBaryFrame).
layout(std430, set = TETRAPROBE_SET, binding = TETRAPROBE_BINDING + 0) readonly buffer TetraprobeTets {
  uint tetraprobeTetVertexBits;     // offset 0
  uint tetraprobeTetNeighbourBits;  // offset 4
  uint tetraprobeTetStride;         // offset 8: uints a tet
  uint tetraprobeTetRecords;        // offset 12: tets
  uint tetraprobeTetData[];         // offset 16
};

// Probe p's position (local frame, metres; float bits) at 3 * p + 0..2; its SH (tetraprobe::ShHalf) as 14
// uints from 3 * tetraprobeProbeCount + 14 * p: binary16 k (k = 3 * coefficient + channel, coefficient index
// l*(l+1)+m, channel 0 r, 1 g, 2 b) in the low (k even) or high (k odd) half of uint k / 2, and the probe's
// power-of-two scale in the high half of uint 13 (tetraprobeProbeSh in tetraprobe.glsl).
layout(std430, set = TETRAPROBE_SET, binding = TETRAPROBE_BINDING + 1) readonly buffer TetraprobeProbes {
  uint tetraprobeProbeData[];
};

// The start grid (tetraprobe::StartGrid): cell (x,y,z) of `dims` covers gridMin + [x,x+1) * cellSize, and
// names the tet the walk starts from at index x + dims.x * (y + dims.y * z).
layout(std430, set = TETRAPROBE_SET, binding = TETRAPROBE_BINDING + 2) readonly buffer TetraprobeGrid {
  vec3 tetraprobeGridMin;       // offset 0, local frame, metres
  int tetraprobeTetCount;       // offset 12
  vec3 tetraprobeGridCellSize;  // offset 16, metres
  int tetraprobeProbeCount;     // offset 28
  ivec3 tetraprobeGridDims;     // offset 32
  int tetraprobeMaxWalkSteps;   // offset 44: the walk's bound (same as the CPU query's)
  int tetraprobeStartTet[];     // offset 48
};

// One outer cell (tetraprobe::GpuOuterCell): a hull triangle p[0..2] (outward winding) extruded along unit
// vertex normals n[0..2]. v.xyz: its probes, v.w: its hull tet; link.xyz: the outer cell across the edge
// opposite v[i] (-1 if none), link.w: the index in the tet's v of the vertex opposite the hull face. Sorted
// by (hull tet, face).
struct TetraprobeOuterCell {
  ivec4 v;     // offset 0: v[0..2] probe indices (positions in TetraprobeProbes), v[3] the hull tet
  ivec4 link;  // offset 16: link[0..2] the cells across the edges, link[3] the hull tet's face
  uvec4 n;     // offset 32: n.xyz octahedral codes of the normals of v[0..2] (tetraprobeOctDecode), n.w 0;
               // 48 bytes in all
};

layout(std430, set = TETRAPROBE_SET, binding = TETRAPROBE_BINDING + 3) readonly buffer TetraprobeOuterCells {
  int tetraprobeOuterCellCount;                // offset 0 (0: no outer cells, clamped hull-tet answers)
  TetraprobeOuterCell tetraprobeOuterCells[];  // offset 16
};

// The start bricks (tetraprobe::GpuCellGridHeader, runtime/start_bricks.h). data[]: the cell grid's hash
// slots at 0 (4 ints: key x, y, z, the cell's brick; key x = INT_MIN when empty), then from
// tetraprobeCellBrickOffset one brick per occupied cell: tetraprobeCellBrickDim^3 start tets, sub-cell
// (i, j, k) of brick b the entry e = b dim^3 + i + dim * (j + dim * k), each packed at the tets' neighbour
// width (bitsFor(tets), runtime/gpu_tets.h) from bit e * width, then a zero word.
layout(std430, set = TETRAPROBE_SET, binding = TETRAPROBE_BINDING + 4) readonly buffer TetraprobeCells {
  vec3 tetraprobeCellMin;         // offset 0, local frame, metres
  float tetraprobeCellSize;       // offset 12, metres
  uint tetraprobeCellSlotMask;    // offset 16: slots - 1
  uint tetraprobeCellMaxProbe;    // offset 20: longest probe sequence; 0 = no bricks
  int tetraprobeCellBrickOffset;  // offset 24
  int tetraprobeCellBrickDim;     // offset 28
  int tetraprobeCellData[];       // offset 32
};

// Per-tet occlusion (tetraprobe::GpuOcclusionHeader, runtime/occlusion.h). data[t]: tet t's header (kind,
// plane count, probe flags, offset; gpu_layout.h). A plane tet's block from tetraprobeOccPlaneOffset + offset:
// its cells word, then its planes (2 uints each: four snorm16). A shadow-map tet's block from
// tetraprobeOccShadowOffset + 16 offset (16 uints, bytes little-endian). tetraprobeOccTetCount 0: none.
layout(std430, set = TETRAPROBE_SET, binding = TETRAPROBE_BINDING + 5) readonly buffer TetraprobeOcclusion {
  uint tetraprobeOccTetCount;      // offset 0
  uint tetraprobeOccPlaneOffset;   // offset 4
  uint tetraprobeOccShadowOffset;  // offset 8
  uint tetraprobeOccPad;           // offset 12
  uint tetraprobeOccData[];        // offset 16
};

#endif  // TETRAPROBE_LAYOUT_GLSL
