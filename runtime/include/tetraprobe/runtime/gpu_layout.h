// The C++ side of the GPU layout in shaders/tetraprobe_layout.glsl (std430). Every struct the shaders read is
// described here once, with its size and offsets pinned by static_assert. Permissive: standard library and
// GLM only (no Vulkan types; see vulkan_upload.h for the buffers).
#pragma once

#include <cstddef>
#include <cstdint>
#include <type_traits>

#include "tetraprobe/runtime/level.h"
#include "tetraprobe/runtime/sh.h"

namespace tetraprobe {

// Binding TETRAPROBE_BINDING + i of set TETRAPROBE_SET (defaults: set 0, first binding 0).
enum GpuBinding : uint32_t {
  kGpuBindingTets = 0,        // TetraprobeTets: Tet[] (80 bytes each)
  kGpuBindingSh = 1,          // TetraprobeSh: float[27 * probes] (ShRgb[], 108 bytes each)
  kGpuBindingGrid = 2,        // TetraprobeGrid: GpuGridHeader, then int32 startTet[cells]
  kGpuBindingOuterCells = 3,  // TetraprobeOuterCells: GpuOuterHeader, then GpuOuterCell[] (128 bytes each)
  kGpuBindingCount = 4,
};

// The tet buffer holds tetraprobe::Tet as is: GLSL `struct TetraprobeTet { ivec4 v; ivec4 n; vec4 row[3]; }`.
static_assert(std::is_standard_layout_v<Tet>);
static_assert(sizeof(Tet) == 80 && alignof(Tet) == 16, "TetraprobeTet: 80 bytes, std430 array stride 80");
static_assert(offsetof(Tet, v) == 0 && offsetof(Tet, n) == 16 && offsetof(Tet, row) == 32, "TetraprobeTet");

// The SH buffer holds tetraprobe::ShRgb as is: 27 floats per probe, coefficient-major then r,g,b
// (float index 27 * probe + 3 * coefficient + channel).
inline constexpr int kGpuShFloatsPerProbe = 27;
static_assert(sizeof(ShRgb) == kGpuShFloatsPerProbe * sizeof(float),
              "TetraprobeSh: 27 packed floats a probe");
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

// One outer cell as the shader reads it: OuterCell (level.h) with its three probe positions copied in, so the
// extrusion needs no other buffer. GLSL: struct TetraprobeOuterCell { vec4 p[3]; vec4 n[3]; ivec4 v; ivec4
// link; }.
struct GpuOuterCell {
  float p[3][4];    // probe positions of v[0..2] (xyz, local frame, metres; w = 0)
  float n[3][4];    // unit vertex normals (xyz; w = 0)
  int32_t v[4];     // v[0..2]: probe indices (outward winding); v[3]: the hull tet
  int32_t link[4];  // link[0..2]: outer cell across the edge opposite v[i], or -1; link[3]: the tet's face
};
static_assert(std::is_standard_layout_v<GpuOuterCell>);
static_assert(sizeof(GpuOuterCell) == 128 && offsetof(GpuOuterCell, n) == 48 &&
                  offsetof(GpuOuterCell, v) == 96 && offsetof(GpuOuterCell, link) == 112,
              "TetraprobeOuterCell: std430 array stride 128");
inline constexpr size_t kGpuOuterCellsOffset = sizeof(GpuOuterHeader);

}  // namespace tetraprobe
