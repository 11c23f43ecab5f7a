// CPU queries against a loaded level: which tet holds a point, its barycentric weights, and the
// interpolated irradiance. Permissive: standard library and GLM only. Thread-safe for concurrent const use.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include <glm/vec3.hpp>
#include <glm/vec4.hpp>

#include "tetraprobe/runtime/cell_grid.h"
#include "tetraprobe/runtime/level.h"
#include "tetraprobe/runtime/sh.h"

namespace tetraprobe {

struct ShadeRecord;  // shade.h

// A coarse uniform grid over the probe bounds (local frame) naming, per cell, a tet near the cell centre to
// start a walk from, so walks stay short. Shared by the CPU query and the GPU upload (same layout as
// shaders/tetraprobe_layout.glsl). Cell (x,y,z) is at index x + dims.x * (y + dims.y * z).
struct StartGrid {
  glm::vec3 min{0.0f};       // local frame, metres
  glm::vec3 cellSize{1.0f};  // metres
  glm::ivec3 dims{0};
  std::vector<int32_t> startTet;
};

// Where a point is. Inside the hull: a tet and its barycentrics. Outside: the outer cell `outerCell` (an
// index into ProbeQuery::outerCells()) whose extruded hull triangle holds the point; `tet` is then that
// cell's hull tet and `weights` its triangle barycentrics expressed on tet.v[0..3] (0 on the vertex opposite
// the hull face), so every consumer can blend tet.v[] with weights[] whichever case it is.
struct Location {
  int32_t tet = -1;         // containing tet, or the outer cell's hull tet; -1 for an empty level
  glm::vec4 weights{0.0f};  // weights of tet.v[0..3]: non-negative, sum to 1
  bool inside = false;      // true when the point lies in the tet (within 1e-6 on each weight)
  int32_t outerCell = -1;   // outside the hull: the outer cell holding the point; -1 inside (or no cell)
};

// ProbeQuery's cellSize for "the level's stored cell grid if it has one, never build one": without a grid,
// points are located by walks from the coarse start grid, which give the same answers (the walk decides
// them; the grid only shortens it). For levels that change between queries, such as the bake's hole and
// refinement rounds, where building a grid per round would cost more than the walks.
inline constexpr float kStoredCellGridOnly = 0.0f;

class ProbeQuery {
 public:
  // Keeps a reference to `level` (which must outlive the query) and builds its acceleration data: the start
  // grid, the outer cells when the level carries none, and the cell grid + BSP with cells of `cellSize`
  // metres unless the level stores one of that cell size (on up to `threads` threads, 0 = all cores; the
  // result does not depend on it; about 45 s for a million probes on two cores, hence stored at bake).
  // cellSize kStoredCellGridOnly: the stored grid whatever its cell size, or none.
  explicit ProbeQuery(const Level& level, float cellSize = 16.0f, int threads = 0);

  // Locates a world-space point. `hint` is a tet to start from (for example the tet of the same object
  // last frame), or -1. Outside the probe hull the walk continues across the outer cells (outer_cells.h) to
  // the one whose extruded triangle holds the point: a continuous answer that does not depend on the hint or
  // the walk's path (up to 1e-6 in the weights where two cells share the point).
  //
  // Inside the hull the weights come from the tet's float rows where they hold the point by more than their
  // rounding; on or near a face, edge or vertex (within 1e-4, or within the rows' rounding, which reaches
  // ~1e-4 on slivers) the walk decides with weights computed in double from the four probe positions, so the
  // tet named holds the point with exact weights within [-1e-6, 1 + 1e-6] and those are the weights returned.
  //
  // Those exact weights come from the float probe positions (Level::probes). A tet that is flat there has
  // none: a point decided in it gets the equal weights 0.25 on its four probes with `inside` false (finite,
  // within the probes' range, but not an interpolation). The build refuses tets whose probes collapse to one
  // float (buildTetRecords, tetra/tetrahedralize.h); a zero-volume tet on a lattice face, coplanar but for
  // double rounding, may remain, and holds no volume for a point to be in but its own plane.
  // Slivers that are positively oriented in float are answered exactly, whatever their condition number
  // (tests/stability: up to 1e12).
  //
  // The hint changes the speed, not the answer: its walk is taken only where it ends clearly inside a tet
  // (every weight at least 1e-4), where no other tet holds the point; otherwise the point is located as
  // without it.
  //
  // Without a hint (or when the hint's short walk fails or leaves the hull) the start tet is the one the
  // sparse cell grid's BSP leaf names (cell_grid.h), which holds the point but within rounding of its faces;
  // a point whose cell is absent, or whose leaf is empty, starts from the coarse start grid and ends in the
  // outer cells.
  Location locate(const glm::dvec3& world, int32_t hint = -1) const;

  // The same answer found the previous way, by a walk from the coarse start grid's tet (no cell grid): for
  // benchmarks and tests.
  Location walkLocate(const glm::dvec3& world) const;

  // Reference answer for tests and the walk's fallback: scans every tet (O(tets)) and returns the one whose
  // smallest weight is largest (ties: lowest index), clamped and renormalized as locate() does; when that
  // tet does not hold the point, scans every outer cell the same way. Agrees with locate() (up to which of
  // two tets or cells sharing a point is named).
  Location bruteForceLocate(const glm::dvec3& world) const;

  // Irradiance E in W/m^2 at a world-space point on a surface with unit normal `normal`. When `tetCache` is
  // given it is read as the walk's starting hint and updated with the tet found (per-object caching); the
  // answer is the same, bit for bit, as without it.
  // It is shadeLocated(level, occlusion(), locate(world), world, normal) (shade.h): the level's stored
  // occlusion (Level::occlusion, occlusion.h) drops the probes the point cannot see:
  // w = applyOcclusion(weights, lookupVisibility(level, occlusion, location, own, local, normal)) with own the
  // tet's occlusionVisibility, the normal biasing the point off its surface (a zero normal: no bias), blended
  // inside the hull with the face neighbours' (face_blend.h); a point that sees none falls back
  // (occludedIrradiance). Outside the hull `tet` is the outer cell's hull tet, whose occlusion applies to the
  // cell's weights the same way (no blend).
  glm::vec3 irradiance(const glm::dvec3& world, const glm::vec3& normal, int32_t* tetCache = nullptr) const;

  // The interpolated L2 SH at a world-space point, for an object that lights its own normals from it (Unity's
  // LightProbes.GetInterpolatedProbe): 9 RGB coefficients of incident radiance in W/(m^2 sr), sh.h's real
  // basis (index l*(l+1)+m, orthonormal, no Condon-Shortley phase), of radiance, not irradiance:
  // shIrradiance(sh, n) gives E in W/m^2 for unit normal n. On an L1 level coefficients 4..8 are 0.
  // It is shadeLocatedSh(level, occlusion(), locate(world), world) (shade.h): the probes of the same tet or
  // outer cell as irradiance(), blended with the same weights, outside the hull too (the outer cell's,
  // continuous). The level's occlusion is applied as for a volume, from the point itself with no normal (a
  // zero normal in irradiance()'s terms: no bias off a surface, no probe counted behind one), blended across
  // faces and falling back as irradiance() does: one SH answers every normal of the object, so there is no
  // single surface to bias from or to put probes behind. Hence:
  //   without occlusion: shIrradiance(interpolatedSh(x), n) == irradiance(x, n) bit for bit, for every n;
  //   with occlusion: equal where the visibility irradiance() computes does not depend on n and no fallback
  //   runs; elsewhere it is the object-centre answer (irradiance() biases a surface point off its surface
  //   and drops probes behind it; its fallback caps by the unoccluded blend per normal, which SH cannot).
  // `tetCache` as in irradiance(): the object's tet from last call, read as the walk's hint and updated; the
  // answer is the same bits with or without it. A level with no tets gives zero SH. Thread-safe for
  // concurrent const use (each object its own tetCache).
  ShRgb interpolatedSh(const glm::dvec3& world, int32_t* tetCache = nullptr) const;

  // irradiance(world, normal) with the record of how it was made (ShadeRecord, shade.h: the location, the
  // visibility before and after the face blend, the weights blended, the fallback): returns the same bits,
  // which `record.answer` holds too. For tools that explain or audit an answer (`query --explain`, the
  // bake's occlusion-hole finder); a few SH evaluations dearer than irradiance().
  glm::vec3 explain(const glm::dvec3& world, const glm::vec3& normal, ShadeRecord& record) const;

  // Batch form: out[i] = irradiance(world[i], normal[i]), bit-identical. Runs on up to `threads` threads
  // (0 = all cores), each on a contiguous share of the items, interleaving groups of 16 queries with
  // prefetching (fast for random order on large levels) and trying the previous item's tet first (fast for
  // coherent order, such as the pixels of a render: pass items in that order).
  void irradianceBatch(const glm::dvec3* world, const glm::vec3* normal, glm::vec3* out, size_t count,
                       int threads = 0) const;

  // Occlusion on (the default) or off (every probe visible, as if the level stored none): for comparisons.
  // Not to be changed while other threads query.
  void setUseOcclusion(bool use) { useOcclusion_ = use; }
  bool usesOcclusion() const { return useOcclusion_ && !level_.occlusion.empty(); }
  // The occlusion irradiance() applies (shadeLocated's `occlusion`): the level's, or null when off or empty.
  const LevelOcclusion* occlusion() const { return usesOcclusion() ? &level_.occlusion : nullptr; }

  const Level& level() const { return level_; }
  const StartGrid& startGrid() const { return grid_; }
  // The level's stored cell grid when it has one of the asked cell size, else the one built on construction.
  const CellGrid& cellGrid() const { return ownGrid_.slots.empty() ? level_.cellGrid : ownGrid_; }
  // The level's outer cells, or the ones built on construction when the level carries none.
  const std::vector<OuterCell>& outerCells() const {
    return ownCells_.empty() ? level_.outerCells : ownCells_;
  }

 private:
  Location gridLocate(const glm::dvec3& x) const;  // locate() without a hint, from the local point
  Location outerLocate(const glm::dvec3& x, int32_t startCell) const;
  Location walkFrom(const glm::dvec3& x, int32_t start, int32_t hint) const;
  Location outerScan(const glm::dvec3& x, const Location& fallback) const;
  int32_t startTet(const glm::dvec3& x, int32_t leafTet) const;
  void batchRange(const glm::dvec3* world, const glm::vec3* normal, glm::vec3* out, size_t begin,
                  size_t end) const;

  const Level& level_;
  StartGrid grid_;
  std::vector<OuterCell> ownCells_;
  CellGrid ownGrid_;
  bool useOcclusion_ = true;
};

// Locates local point x (the level's frame, finite) by ProbeQuery's own walk from tet `start` (any tet of the
// level), with no grid and no outer cells: true with the tet holding x and its weights, as
// ProbeQuery::locate answers them inside the hull; false when the walk leaves through a face without a
// neighbour or does not settle (a cycle off every tet, the step bound). For levels that are parts of a larger
// one, whose cut faces have no neighbour (GpuSectorPool::irradiance).
bool locateByWalk(const Level& level, const glm::dvec3& x, int32_t start, Location& out);

}  // namespace tetraprobe
