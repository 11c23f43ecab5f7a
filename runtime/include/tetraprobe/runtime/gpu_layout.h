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
  kGpuBindingTets = 0,  // TetraprobeTets: Tet[] (80 bytes each)
  kGpuBindingSh = 1,    // TetraprobeSh: float[27 * probes] (ShRgb[], 108 bytes each)
  kGpuBindingGrid = 2,  // TetraprobeGrid: GpuGridHeader, then int32 startTet[cells]
  kGpuBindingCount = 3,
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

}  // namespace tetraprobe
