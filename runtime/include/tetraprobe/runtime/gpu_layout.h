// The C++ side of the GPU layout in shaders/tetraprobe_layout.glsl (std430). Every struct the shaders read is
// described here once, with its size and offsets pinned by static_assert. Permissive: standard library and
// GLM only (no Vulkan types; see vulkan_upload.h for the buffers).
#pragma once

#include <cstddef>
#include <cstdint>
#include <type_traits>
#include <vector>

#include "tetraprobe/runtime/cell_grid.h"
#include "tetraprobe/runtime/level.h"
#include "tetraprobe/runtime/occlusion_data.h"
#include "tetraprobe/runtime/oct_normal.h"
#include "tetraprobe/runtime/sh.h"
#include "tetraprobe/runtime/sh_half.h"

namespace tetraprobe {

// Binding TETRAPROBE_BINDING + i of set TETRAPROBE_SET (defaults: set 0, first binding 0).
enum GpuBinding : uint32_t {
  kGpuBindingTets = 0,  // TetraprobeTets: GpuTetHeader, then packed tets (gpu_tets.h)
  kGpuBindingProbes =
      1,                // TetraprobeProbes: positions (3 floats a probe), then SH (ShHalf: 14 uints a probe)
  kGpuBindingGrid = 2,  // TetraprobeGrid: GpuGridHeader, then int32 startTet[cells]
  kGpuBindingOuterCells = 3,  // TetraprobeOuterCells: GpuOuterHeader, then GpuOuterCell[] (48 bytes each)
  kGpuBindingCells = 4,       // TetraprobeCells: GpuCellGridHeader, then int32 data[] (slots, bricks)
  kGpuBindingOcclusion =
      5,  // TetraprobeOcclusion: GpuOcclusionHeader, then uint32 data[] (records, planes, maps)
  kGpuBindingCount = 6,
};

// The bytes of the six buffers as the shader reads them, each zero-padded to a multiple of 64 bytes and at
// least 64: exactly what an upload puts into each buffer (packLevelBuffers in vulkan_upload.h for a whole
// level, GpuSectorPool in gpu_sector_pool.h for a streamed one).
struct PackedLevelBuffers {
  std::vector<char> bytes[kGpuBindingCount];  // indexed by GpuBinding
};

// Header of the TetraprobeTets buffer (16 bytes): the tets packed as gpu_tets.h says (GpuTetPacking), one
// record of strideUints words a tet from offset 16, then kGpuTetTailUints zero words (the shader reads the
// word after every field's first, also after the last record's).
struct GpuTetHeader {
  uint32_t vertexBits;     // uint tetraprobeTetVertexBits: bits of a probe index
  uint32_t neighbourBits;  // uint tetraprobeTetNeighbourBits: bits of a neighbour code (index + 1; 0 = hull)
  uint32_t strideUints;    // uint tetraprobeTetStride: words a tet
  uint32_t count;          // uint tetraprobeTetRecords: tets
};
static_assert(std::is_standard_layout_v<GpuTetHeader>);
static_assert(sizeof(GpuTetHeader) == 16 && offsetof(GpuTetHeader, neighbourBits) == 4 &&
                  offsetof(GpuTetHeader, strideUints) == 8 && offsetof(GpuTetHeader, count) == 12,
              "TetraprobeTets header: 16 bytes, records at offset 16");
inline constexpr uint32_t kGpuTetTailUints = 1;

// The probe buffer (uint data[]): Level::probes as is (3 floats per probe, x y z, local frame) from index 0,
// then one ShHalf per probe (sh_half.h: 27 binary16 coefficients, coefficient-major then r,g,b, and the
// probe's power-of-two scale; 14 uints) from index 3 * probes (tetraprobeProbeCount of the grid header).
inline constexpr int kGpuPositionFloatsPerProbe = 3;
inline constexpr int kGpuShUintsPerProbe = 14;
static_assert(sizeof(ShHalf) == kGpuShUintsPerProbe * sizeof(uint32_t), "TetraprobeSh: 14 uints a probe");
static_assert(sizeof(glm::vec3) == 3 * sizeof(float), "ShRgb's vec3 must be packed (no GLM SIMD alignment)");

// Header of the TetraprobeGrid buffer (48 bytes); the int32 start-tet array follows at offset 48.
struct GpuGridHeader {
  float min[3];          // vec3 tetraprobeGridMin, local frame, metres
  int32_t tetCount;      // int tetraprobeTetCount
  float cellSize[3];     // vec3 tetraprobeGridCellSize, metres
  int32_t probeCount;    // int tetraprobeProbeCount
  int32_t dims[3];       // ivec3 tetraprobeGridDims
  int32_t maxWalkSteps;  // int tetraprobeMaxWalkSteps
};
static_assert(std::is_standard_layout_v<GpuGridHeader>);
static_assert(sizeof(GpuGridHeader) == 48, "TetraprobeGrid header is 48 bytes; startTet[] at offset 48");
static_assert(offsetof(GpuGridHeader, min) == 0 && offsetof(GpuGridHeader, tetCount) == 12 &&
                  offsetof(GpuGridHeader, cellSize) == 16 && offsetof(GpuGridHeader, probeCount) == 28 &&
                  offsetof(GpuGridHeader, dims) == 32 && offsetof(GpuGridHeader, maxWalkSteps) == 44,
              "TetraprobeGrid header offsets (std430: vec3 aligned to 16, a scalar packs after it)");
inline constexpr size_t kGpuGridStartTetOffset = sizeof(GpuGridHeader);

// Header of the TetraprobeOuterCells buffer (16 bytes); GpuOuterCell[count] follows at offset 16.
struct GpuOuterHeader {
  int32_t count;  // int tetraprobeOuterCellCount
  int32_t pad[3];
};
static_assert(sizeof(GpuOuterHeader) == 16, "TetraprobeOuterCells header: 16 bytes, cells at offset 16");

// One outer cell as the shader reads it: OuterCell (level.h) in 48 bytes instead of the CPU's 80, the three
// vertex normals as octahedral codes (oct_normal.h; the CPU's normals lie on that code lattice, so both
// extrude along the same directions); the shader reads the three probe positions from the probe buffer by
// index. GLSL: struct TetraprobeOuterCell { ivec4 v; ivec4 link; uvec4 n; }.
struct GpuOuterCell {
  int32_t v[4];     // v[0..2]: probe indices (outward winding); v[3]: the hull tet
  int32_t link[4];  // link[0..2]: outer cell across the edge opposite v[i], or -1; link[3]: the tet's face
  uint32_t n[4];    // n[0..2]: vertex normals of v[0..2], octahedral codes (oct_normal.h); n[3]: 0
};
static_assert(std::is_standard_layout_v<GpuOuterCell>);
static_assert(sizeof(GpuOuterCell) == 48 && offsetof(GpuOuterCell, link) == 16 &&
                  offsetof(GpuOuterCell, n) == 32,
              "TetraprobeOuterCell: std430 array stride 48");
inline constexpr size_t kGpuOuterCellsOffset = sizeof(GpuOuterHeader);

// An outer cell as the shader reads it. The normals are on the code lattice already (buildOuterCells,
// loadLevel): their code decodes to them.
inline GpuOuterCell gpuOuterCell(const OuterCell& c) {
  GpuOuterCell g{};
  for (int i = 0; i < 3; ++i) {
    g.n[i] = encodeOctNormal(glm::dvec3(c.normal[i][0], c.normal[i][1], c.normal[i][2]));
    g.v[i] = c.v[i];
    g.link[i] = c.n[i];
  }
  g.v[3] = c.tet;
  g.link[3] = c.face;
  return g;
}

// Header of the TetraprobeCells buffer (32 bytes): the start bricks of start_bricks.h (the cell grid's hash
// table with a brick per occupied cell; the BSP stays on the CPU). The int32 data[] that follows at offset 32
// holds the hash slots (CellSlot, 4 ints each: key x, y, z, the cell's brick index; key x = INT32_MIN when
// empty) from index 0, then the bricks (brickDim^3 start tets each, x fastest) from brickOffset.
struct GpuCellGridHeader {
  float min[3];         // vec3 tetraprobeCellMin, local frame, metres
  float cellSize;       // float tetraprobeCellSize, metres
  uint32_t slotMask;    // uint tetraprobeCellSlotMask: slots - 1
  uint32_t maxProbe;    // uint tetraprobeCellMaxProbe: 0 = no bricks (the walk starts from the start grid)
  int32_t brickOffset;  // int tetraprobeCellBrickOffset: index in data[] of brick 0
  int32_t brickDim;     // int tetraprobeCellBrickDim: sub-cells a brick edge
};
static_assert(std::is_standard_layout_v<GpuCellGridHeader>);
static_assert(sizeof(GpuCellGridHeader) == 32 && offsetof(GpuCellGridHeader, cellSize) == 12 &&
                  offsetof(GpuCellGridHeader, slotMask) == 16 &&
                  offsetof(GpuCellGridHeader, brickOffset) == 24 &&
                  offsetof(GpuCellGridHeader, brickDim) == 28,
              "TetraprobeCells header: 32 bytes, data[] at offset 32");
static_assert(sizeof(CellSlot) == 4 * sizeof(int32_t), "TetraprobeCells: 4 ints a slot");

// TetraprobeOcclusion (binding + 5): the level's per-tet occlusion (occlusion.h), packed into one uint array
// after this header, in less than the CPU's LevelOcclusion holds (gpuOcclusionBytes):
// - data[t]: tet t's header, TetOcclusion's repacked to hold the probe flags of the blend (face_blend.h,
//   faceBlendMask) between the plane count and the offset: kind (bits 0-1), plane count (2-3), probe mask
//   (4-7, bit 4 + i for probe slot i), offset (from bit 8, below 2^24; the upload refuses more).
// - Plane tets: from planeOffset, one block each: the tet's `cells` word, then its planes (2 uints each:
//   four snorm16, c[0] | c[1] << 16, c[2] | c[3] << 16); the header's offset is the block's first uint,
//   counted from planeOffset. Only plane tets carry a `cells` word (the CPU's 8-byte record gives every
//   tet one), 4 bytes a tet less for the others.
// - Shadow-map tets: the header's offset is the 64-byte block's index from shadowOffset (16 uints each,
//   little-endian bytes), as TetOcclusion's.
// tetCount 0: the level has none (a tiny dummy buffer; the shader skips the evaluation).
inline constexpr uint32_t kGpuOccRecordUints = 1;
inline constexpr uint32_t kGpuOccProbeMaskShift = 4;
inline constexpr uint32_t kGpuOccOffsetShift = 8;
inline constexpr uint32_t kGpuOccMaxOffset = (1u << (32 - kGpuOccOffsetShift)) - 1u;
inline uint32_t gpuOcclusionHeader(const TetOcclusion& rec, uint32_t probeMask, uint32_t offset) {
  return uint32_t(rec.kind()) | rec.planeCount() << 2 | (probeMask & 15u) << kGpuOccProbeMaskShift |
         offset << kGpuOccOffsetShift;
}

// Bytes of the GPU's occlusion data after its header, as the upload packs it: 4 a tet, 4 + 8 a plane a
// plane tet, the shadow-map blocks; 0 for a level without occlusion.
inline size_t gpuOcclusionBytes(const LevelOcclusion& occ) {
  if (occ.empty()) return 0;
  size_t bytes = occ.tets.size() * sizeof(uint32_t) + occ.shadowMaps.size();
  for (const TetOcclusion& t : occ.tets)
    if (t.kind() == kOcclusionPlanes) bytes += sizeof(uint32_t) + t.planeCount() * sizeof(OcclusionPlane);
  return bytes;
}

struct GpuOcclusionHeader {
  uint32_t tetCount;      // uint tetraprobeOccTetCount: 0 = no occlusion
  uint32_t planeOffset;   // uint tetraprobeOccPlaneOffset
  uint32_t shadowOffset;  // uint tetraprobeOccShadowOffset
  uint32_t pad;
};
static_assert(sizeof(GpuOcclusionHeader) == 16, "TetraprobeOcclusion header: 16 bytes, data[] at offset 16");

}  // namespace tetraprobe
