// The baked level as the runtime sees it: probes with SH radiance, their tetrahedralization, and the data
// needed to locate a point. Read from and written to one binary `.tpb` file (format: docs/level_format.md).
// Permissive: standard library and GLM only.
//
// Frames and units: world space is the input level's frame (right-handed, metres after the scene's unit
// scale). To keep float precision far from the world origin, every stored position is relative to
// `origin` (double): world = origin + local.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include <glm/vec3.hpp>
#include <glm/vec4.hpp>

#include "tetraprobe/runtime/cell_grid.h"
#include "tetraprobe/runtime/occlusion_data.h"
#include "tetraprobe/runtime/sh.h"

namespace tetraprobe {

// What light the probes hold (bit flags, stored in the file).
enum ProbeContent : uint32_t {
  kContentEmissive = 1u << 0,        // light arriving directly from emissive surfaces
  kContentSky = 1u << 1,             // light arriving directly from the sky
  kContentIndirect = 1u << 2,        // light after one or more diffuse bounces
  kContentDirectPunctual = 1u << 3,  // light arriving directly from point, spot and directional lights
  kContentDefault = kContentEmissive | kContentSky | kContentIndirect,
  kContentAll = kContentDefault | kContentDirectPunctual,
};

// One tetrahedron, laid out exactly as the GPU reads it (std430, 32 bytes; mirrored in
// shaders/tetraprobe_layout.glsl).
// - v[i]: probe indices. n[i]: the tet across the face opposite v[i], or -1 on the hull.
// - No barycentric rows are stored (they were 48 of 80 bytes): the weights come from the four probe
//   positions, in double on the CPU (ProbeQuery) and in float through baryFrame() for occlusion and on the GPU.
struct alignas(16) Tet {
  int32_t v[4];
  int32_t n[4];
};
static_assert(sizeof(Tet) == 32, "Tet is 32 bytes in std430");

// The barycentric frame of a tet in float, from its probe positions (local frame): w_i = dot(grad[i], X -
// origin) for i = 0..2, w_3 = 1 - w_0 - w_1 - w_2, with origin = P3 and grad[i] the rows of the inverse of
// [P0-P3 | P1-P3 | P2-P3] (the gradients of w_i, 1/metres). Computed operation for operation as the GLSL's
// tetraprobeBaryFrame, so CPU occlusion and GPU occlusion see the same weights. A tet flat in float gives
// non-finite gradients (callers treat the weights as they would any non-finite input).
struct BaryFrame {
  glm::vec3 origin{0.0f};
  glm::vec3 grad[3] = {glm::vec3(0.0f), glm::vec3(0.0f), glm::vec3(0.0f)};
};
BaryFrame baryFrame(const Tet& t, const std::vector<glm::vec3>& probes);
// Raw weights of local point x in the frame (may be negative outside; float, as the GPU).
glm::vec4 baryWeights(const BaryFrame& f, const glm::vec3& x);

// One outer cell: a hull triangle extruded along unit vertex normals, covering the space outside the hull
// beyond it (runtime/outer_cells.h). 80 bytes, as the old OUTC section stored it; the GPU reads the 48-byte
// GpuOuterCell (gpu_layout.h), with the normals as octahedral codes.
// - v[i]: the hull face's probe indices, counter-clockwise seen from outside ((P1-P0) x (P2-P0) points out).
// - tet: the hull tet owning the face; face: the index in tet.v of the tet's vertex opposite the face
//   (tet.n[face] == -1).
// - n[i]: the outer cell across the hull edge opposite v[i] (edge v[i+1], v[i+2]), or -1.
// - normal[i].xyz: unit vertex normal at v[i] (angle-weighted mean of the adjacent hull faces' outward
//   normals; equal in every cell naming that probe), on the octahedral code lattice (quantizeOctNormal,
//   oct_normal.h: what the GPU decodes); normal[i].w = 0.
struct alignas(16) OuterCell {
  int32_t v[3];
  int32_t tet;
  int32_t n[3];
  int32_t face;
  float normal[3][4];
};
static_assert(sizeof(OuterCell) == 80, "OuterCell is 80 bytes (the OUTC record)");

// Why a probe exists: the bake stage that placed it (one byte per probe in the optional `KIND` section,
// docs/level_format.md). Debug views and reports only; the lookup never reads it. Values 0..5 equal
// tetra/placement.h's ProbeKind.
enum class LevelProbeKind : uint8_t {
  kUser = 0,        // from --probes or --import-sh
  kSurface = 1,     // voxel placement: empty finest voxel next to geometry
  kVolume = 2,      // voxel placement: inside a fine volume
  kOpen = 3,        // voxel placement: centre of a coarser open-space cell
  kFiller = 4,      // open-space lattice, or added where tets were slivers
  kShell = 5,       // on the level's grown bounds, holding its own baked SH
  kDilated = 6,     // a shell probe that took its nearest valid probe's SH (outside a closed level)
  kHole = 7,        // added by occlusion-hole filling
  kRefinement = 8,  // added by error-driven refinement
  kGrid = 9,        // regular grid placement (--placement grid)
};
constexpr uint32_t kLevelProbeKindCount = 10;
// The kind's name in reports ("user", "surface", ..., "grid"); "unknown" past the last kind.
const char* levelProbeKindName(LevelProbeKind kind);

struct Level {
  uint32_t content = kContentDefault;  // ProbeContent flags
  uint32_t shOrder = 2;                // 1 or 2 (L1 probes have coefficients 4..8 zero)
  glm::dvec3 origin{0.0};              // world position of the local frame's origin, metres
  std::vector<glm::vec3> probes;       // probe positions, local frame, metres
  std::vector<ShRgb> sh;               // one per probe: incident radiance SH
  std::vector<Tet> tets;               // tetrahedralization of `probes` (every probe is a vertex)
  // One per hull face, sorted by (tet, face) (buildOuterCells in outer_cells.h). Optional: when empty,
  // ProbeQuery builds them itself on construction.
  std::vector<OuterCell> outerCells;
  // The point-location accelerator (buildCellGrid in cell_grid.h). Optional: when it has no slots,
  // ProbeQuery builds it itself on construction (about 45 s for a million probes on two cores).
  CellGrid cellGrid;
  // Per-tet occlusion against light leaking (occlusion.h, docs/occlusion.md). Optional: empty = none (every
  // probe visible); otherwise occlusion.tets.size() == tets.size().
  LevelOcclusion occlusion;
  // Optional: empty = not recorded (levels written before the KIND section); else one per probe.
  std::vector<LevelProbeKind> probeKinds;
  std::string generator;  // free text: tool version and options that produced the file
  // Optional: the streaming index (section STRM: sectors of cells and a coarse probe set, streaming.h),
  // bytes as stored; empty = none. loadLevel and saveLevel carry it unparsed; StreamingLevel reads it.
  std::vector<uint8_t> stream;
};

enum class LevelStatus {
  kOk,
  kCannotOpen,
  kNotALevel,
  kUnsupportedVersion,
  kTruncated,
  kCorrupt,
  kWriteFailed,
  kTooLarge,  // the file is larger than the load's byte limit, or its level does not fit in memory
};

struct LevelResult {
  LevelStatus status = LevelStatus::kOk;
  std::string message;  // one line naming the problem (empty when ok)
  explicit operator bool() const { return status == LevelStatus::kOk; }
};

// The level file format version this reader and writer implement (docs/level_format.md, version policy).
inline constexpr uint32_t kLevelFormatVersion = 5;

// Bytes one probe index takes in the level file's tet records (`TETC`, docs/level_format.md): the fewest
// that hold every index of a level of `probeCount` probes (2 up to 65,536 probes, 3 up to 2^24, else 4).
inline constexpr uint32_t levelProbeIndexBytes(uint64_t probeCount) {
  return probeCount <= (uint64_t(1) << 16) ? 2u : probeCount <= (uint64_t(1) << 24) ? 3u : 4u;
}

// The default byte limit of loadLevel: 4 GiB (a placed level of a million probes is about 0.4 GiB).
inline constexpr uint64_t kDefaultMaxLevelBytes = uint64_t(4) << 30;

// Reads `path`. Safe on untrusted input and never throws: every count, index and size is validated before
// use (docs/level_format.md, "Loading untrusted files"); a file larger than `maxBytes`, or one whose level
// does not fit in memory, is kTooLarge. On failure `out` is left empty and the result names the file and
// the problem in one line. Allocates the file's size, then the level's arrays.
LevelResult loadLevel(const std::string& path, Level& out, uint64_t maxBytes = kDefaultMaxLevelBytes);

// loadLevel on a file already in memory (`size` bytes at `bytes`; an engine's own file system, a pack
// file, a fuzzer). `name` prefixes the messages in place of the path. Same checks, same results.
LevelResult loadLevelFromMemory(const void* bytes, size_t size, const std::string& name, Level& out);

// Checks the in-memory invariants (sizes agree, indices in range, finite numbers). Used by load and save.
LevelResult validateLevel(const Level& level);

// Writes `level` to `path` atomically (a temporary file beside it, then rename): a failed write never
// leaves a partial file. The output is a pure function of `level` (bit-identical for equal input).
LevelResult saveLevel(const std::string& path, const Level& level);

}  // namespace tetraprobe
