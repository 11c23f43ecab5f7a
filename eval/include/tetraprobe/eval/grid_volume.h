// The regular irradiance grid a user would pick instead of tetrahedral probes (Unity's Adaptive Probe Volumes
// at one subdivision level, Godot/EEVEE irradiance volumes, DDGI without visibility): SH L2 RGB nodes on a
// cubic lattice, trilinear interpolation, nodes inside geometry replaced by their nearest valid node. Used by
// `tetraprobe eval` as the competitor at the tet level's bytes and at its probe count. Build side.
//
// Frames and units: world metres (right-handed, the scene's frame); node (i, j, k) sits at
// min + (i, j, k) x step. SH: the level's convention (runtime/sh.h: 9 RGB coefficients of incident radiance,
// W/(m^2 sr), index l*(l+1)+m; irradiance E(n) in W/m^2). Nodes are stored x fastest: index
// i + dims.x * (j + dims.y * k).
//
// Memory (what a runtime holds, the figure `bytes()` reports): kGridHeaderBytes (min and step as vec4, dims as
// ivec4) + 108 bytes (27 floats) per node. No locate structure: a node's index is arithmetic.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include <glm/vec3.hpp>

#include "tetraprobe/bake/bake.h"
#include "tetraprobe/bake/tracer.h"
#include "tetraprobe/runtime/sh.h"
#include "tetraprobe/runtime/sh_half.h"

namespace tetraprobe {

inline constexpr uint64_t kGridHeaderBytes = 48;  // vec4 min, vec4 step, ivec4 dims (std430)
// A node holds its SH as a level holds a probe's (ShHalf, runtime/sh_half.h: 56 bytes), so that at equal bytes
// the grid gets the same precision per coefficient as the tet level and twice the nodes it would get in float.
// (Its GPU pass, lighting_grid.comp, reads the decoded floats: its timing is for 108-byte nodes.)
inline constexpr uint64_t kGridNodeBytes = sizeof(ShHalf);
static_assert(kGridNodeBytes == 56, "a grid node is one ShHalf");

struct GridLayout {
  glm::dvec3 min{0.0};  // world metres: node (0, 0, 0)
  double step = 1.0;    // node spacing, metres, the same on every axis (> 0)
  glm::ivec3 dims{2};   // nodes per axis, each >= 2
  size_t nodes() const { return size_t(dims.x) * size_t(dims.y) * size_t(dims.z); }
  uint64_t bytes() const { return kGridHeaderBytes + kGridNodeBytes * nodes(); }
  glm::dvec3 node(size_t index) const;  // world position of node `index` (x fastest)
};

// The finest cubic lattice of at most `maxNodes` nodes (at least 2 per axis) covering the box [lo, hi]
// (world metres, lo <= hi per axis; a flat axis gets 2 nodes), centred on it. When maxNodes < 8 the result
// is the 2 x 2 x 2 lattice (over the budget). Throws std::invalid_argument for a non-finite or inverted box.
GridLayout gridLayoutForNodes(const glm::dvec3& lo, const glm::dvec3& hi, uint64_t maxNodes);

// The finest lattice (as above) whose bytes() is at most `maxBytes`.
GridLayout gridLayoutForBytes(const glm::dvec3& lo, const glm::dvec3& hi, uint64_t maxBytes);

class GridVolume {
 public:
  GridVolume() = default;
  // Takes `sh` (one per node, layout.nodes() of them) and replaces every node with invalid[i] != 0 by its
  // nearest valid node's SH (dilateInvalidProbes, bake/bake.h; nothing changes when no node is valid).
  // Throws std::invalid_argument when the sizes differ from layout.nodes().
  GridVolume(const GridLayout& layout, std::vector<ShRgb> sh, std::vector<uint8_t> invalid);

  const GridLayout& layout() const { return layout_; }
  const std::vector<ShRgb>& sh() const { return sh_; }              // after dilation
  const std::vector<uint8_t>& invalid() const { return invalid_; }  // as given (before dilation)
  size_t invalidNodes() const;
  uint64_t bytes() const { return layout_.bytes(); }

  // Trilinear blend of the 8 nodes around world point p (clamped to the lattice: outside it the nearest
  // face's values continue), evaluated as irradiance for unit normal n (W/m^2; may be negative where L2
  // rings, as the tet lookup). Thread-safe, allocates nothing.
  glm::vec3 irradiance(const glm::dvec3& p, const glm::vec3& n) const;
  // The blended SH itself (same weights).
  ShRgb blend(const glm::dvec3& p) const;

 private:
  GridLayout layout_;
  std::vector<ShRgb> sh_;
  std::vector<uint8_t> invalid_;
};

struct GridBakeStats {
  size_t nodes = 0, invalidNodes = 0;  // invalid: inside geometry (not traced, dilated)
  BakeStats bake;
  DeringStats dering;
  double seconds = 0.0;  // the whole bakeGridVolume call
};

// Bakes a grid the way `tetraprobe bake` bakes probes: nodes inside geometry (probesInsideGeometry: more than
// 25 % of 64 rays meet back faces) are not traced and take their nearest valid node's SH; the rest go
// through bakeProbes with `bake` (same seed, adaptive sampling, content and SH order as given), then every
// node is deringed with `dering` (after dilation, as the pipeline does). Deterministic for any thread count
// (bake.threads).
GridVolume bakeGridVolume(const SceneTracer& tracer, const GridLayout& layout, const BakeOptions& bake,
                          const DeringOptions& dering, GridBakeStats* stats = nullptr);

// The generator string's `key=value` items in order (Level::generator). Two forms: `tetraprobe bake`'s,
// "tetraprobe 0.1.0 bake --spacing=1 --placement=voxel ..." (items separated by spaces; keys are the option
// names, "--spacing"), and the earlier "tetraprobe 0.1.0 bake; placement=voxel; spacing=1; ..." (items
// separated by ';', keys trimmed of spaces; a text holding " --" is the first form). Items without '=' are
// skipped. The text is free-form: this is the one place that splits it (tools/cli/pipeline_options.h reads
// the options back).
std::vector<std::pair<std::string, std::string>> generatorFields(const std::string& generator);

}  // namespace tetraprobe
