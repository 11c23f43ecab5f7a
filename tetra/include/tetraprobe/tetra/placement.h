// Automatic probe placement. Build side.
#pragma once

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include <glm/vec3.hpp>

namespace tetraprobe {

struct Scene;

// A regular grid at `spacing` metres covering [lo, hi] (inclusive, centred so the margins are equal), in
// x-fastest order: floor(extent / spacing) + 1 points per axis (an extent that is an exact multiple of the
// spacing, to 1e-9 relative, puts points on both faces), all inside the box. Throws InputError for a
// non-positive or non-finite spacing, non-finite corners, hi < lo on an axis, or when the grid would exceed
// `maxProbes` points (checked before allocating).
std::vector<glm::dvec3> placeGridProbes(const glm::dvec3& lo, const glm::dvec3& hi, double spacing,
                                        size_t maxProbes = 5'000'000);

// Reads user probes from a CSV file: one `x,y,z` a line (world metres); blank lines and lines starting with
// '#' are skipped. Throws InputError naming the file and line for anything else (non-numbers, NaN, Inf).
std::vector<glm::dvec3> readProbeCsv(const std::string& path);

// ---- Adaptive voxel placement (Valient 2014: "a probe in every empty voxel next to geometry") ----------

enum class ProbeKind : uint8_t {
  kUser = 0,     // from --probes: never moved, never merged away
  kSurface = 1,  // empty finest voxel 26-adjacent to a voxel holding geometry
  kVolume = 2,   // empty finest voxel inside a fine volume (Scene::fineVolumes), not next to geometry
  kOpen = 3,     // centre of an empty coarser octree cell (open space, graded up to maxSpacing)
  kFiller = 4,   // filler: open-space lattice at fillerSpacing, or added where tets were slivers
  kShell = 5,    // shell: lattice on the level's bounds grown outward (placeShellProbes), so every surface
                 // lies inside the tetrahedralization
};
const char* probeKindName(ProbeKind kind);

struct PlacedProbes {
  std::vector<glm::dvec3> positions;  // world metres
  std::vector<ProbeKind> kinds;       // one per position
  std::vector<double> spacing;        // local spacing (edge of the voxel the probe came from), metres
  size_t size() const { return positions.size(); }
  void add(const glm::dvec3& p, ProbeKind k, double s) {
    positions.push_back(p);
    kinds.push_back(k);
    spacing.push_back(s);
  }
  size_t count(ProbeKind k) const;
};

struct VoxelPlacementOptions {
  double spacing = 1.0;        // finest voxel edge, metres: near geometry and inside fine volumes
  double maxSpacing = 10.0;    // coarsest cell edge allowed (levels double the edge: spacing * 2^L <= this)
  double fillerSpacing = 4.0;  // open-space filler lattice, metres (0 = none)
  size_t maxProbes = 5'000'000;
  int threads = 0;  // voxelization threads, 0 = all cores (never changes the output)
};

// The octree, flattened into levels L = 0..Lmax with cell edge h_L = spacing * 2^L, Lmax the largest L with
// h_L <= maxSpacing (at least 0). Level-0 voxel centres lie on the world lattice spacing * Z^3 (so
// whole-spacing walls run through voxel middles, not along voxel faces); the domain covers the scene bounds
// grown by one spacing, whole top cells from the voxel at floor(min / spacing) - 1. A level-0 voxel "holds
// geometry" when a triangle overlaps the closed voxel box (exact SAT, Akenine-Moller 2001). A level-L cell (L
// >= 1) is split when it holds geometry, is within one level-L cell (26-neighbourhood) of a cell that does,
// or overlaps a fine volume. Probes go at the centres of:
//   - level-0 empty voxels that touch a geometry voxel (26-neighbourhood): kSurface;
//   - level-0 empty voxels inside a fine volume that are not next to geometry: kVolume;
//   - empty leaf cells of level L >= 1 (unsplit children of split cells, or unsplit top cells): kOpen;
// Probes outside the level's bounds (scene and fine volumes; each axis grown to at least 2 x spacing) are
// dropped: outside a closed level a probe sees only the backs of walls. Then the filler lattice (kFiller):
// points of a fillerSpacing lattice centred in that probe box with no other probe within fillerSpacing / 2
// and not in a geometry voxel. Deterministic (sorted sparse sets, no hashing order). Cost O(triangle-voxel
// overlaps + probes). Throws InputError for a scene without triangles, spacing <= 0 or non-finite, maxSpacing
// < spacing, negative fillerSpacing, a domain above 2^20 voxels per axis, or more than maxProbes probes.
PlacedProbes placeVoxelProbes(const Scene& scene, const VoxelPlacementOptions& options);

// Triangle / axis-aligned box overlap (separating axis test). Closed box [lo, hi]. Exposed for tests.
bool triangleBoxOverlap(const glm::dvec3& a, const glm::dvec3& b, const glm::dvec3& c, const glm::dvec3& lo,
                        const glm::dvec3& hi);

// ---- Shell probes ------------------------------------------------------------------------------------

// A lattice on the surface of the box [lo - margin, hi + margin] (margin = step / 2): every face split into
// cells of at most `step` metres (at least one per axis), probes at the cell corners, each point once. With
// them the probes' convex hull contains the whole box, so every surface of a level whose bounds are [lo, hi]
// is inside a tet, where per-tet occlusion decides which probes it sees (a wall between a surface and a
// shell probe outside a closed level is a splitting plane), instead of in the outer cells, which extrapolate
// from the hull probes with no occlusion. Shell probes outside a closed level see only the backs of walls:
// the pipeline bakes them and then replaces the SH of those that fail the inside rule by their nearest
// valid probe's (dilateInvalidProbes in bake/dilate.h). Deterministic order (z, then y, then x). Throws
// InputError for a non-finite box, hi < lo, a step <= 0 or non-finite, or more than `maxProbes` points.
std::vector<glm::dvec3> placeShellProbes(const glm::dvec3& lo, const glm::dvec3& hi, double step,
                                         size_t maxProbes = 5'000'000);

// Which of `points` lie near geometry (1) or far from it (0). Must be a pure function of its input.
using NearGeometryQuery = std::function<std::vector<uint8_t>(const std::vector<glm::dvec3>& points)>;

// The shell of placeShellProbes thinned where nothing needs it: a lattice point is kept when it lies on the
// coarse sub-lattice (every k-th point along each axis, k = max(1, floor(farStep / step)), the last point
// of each axis included) or when `nearGeometry` says it is near geometry. So the hull is still the whole
// grown box (its corners and edges are on the coarse sub-lattice), surfaces near the bounds still lie in
// tets with shell probes `step` apart, and the faces of an open level's box over open ground or sky (its
// top and sides: most of the shell, nothing lit there that a camera sees) hold probes `farStep` apart.
// farStep <= step, or no query, gives placeShellProbes' lattice. Deterministic order (z, then y, then x).
// Throws as placeShellProbes does, and InputError for a non-finite farStep.
std::vector<glm::dvec3> placeShellProbes(const glm::dvec3& lo, const glm::dvec3& hi, double step,
                                         double farStep, const NearGeometryQuery& nearGeometry,
                                         size_t maxProbes = 5'000'000);

// ---- Rejection / push-out ---------------------------------------------------------------------------

// What rays from a point see (computed by the caller, e.g. with the bake's SceneTracer; tetra links no
// ray tracer). All distances in metres.
struct Clearance {
  bool inside = false;     // more than 25 % of the rays hit back faces (Unity APV rule)
  glm::dvec3 escape{0.0};  // unit mean direction of rays that escaped or hit a front face farther than
                           // the query's reach; zero when none did
  double nearest = 1e300;  // distance of the closest hit over all rays (upper bound of the distance to
                           // the nearest surface)
  glm::dvec3 away{0.0};    // unit direction pointing away from that closest surface (its front normal
                           // for a front hit), zero when nothing was hit
};
// The inside rule both the pipeline and the tests apply to `rays` uniformly distributed rays of which `hits`
// hit something and `backHits` hit a back face: inside when backHits > 25 % of the rays (Unity APV), or when
// at least 1/16 of the rays hit back faces and back faces are the majority of the hits (a probe outside a
// closed level sees mostly the backs of its walls, at its corners over less than a quarter of the sphere; a
// probe in open space that mostly sees the back of a single-sided card is caught too, and pushed out or
// rejected).
bool insideByRays(int rays, int hits, int backHits);

// Batch query: one Clearance per point, rays reaching `reach` metres (hits beyond count as escapes).
// Must be a pure function of its inputs (it may run threads).
using ClearanceQuery = std::function<std::vector<Clearance>(const std::vector<glm::dvec3>& points,
                                                            const std::vector<double>& reach)>;

struct PushOutStats {
  size_t rejected = 0;  // inside geometry and not rescued, or pushed into geometry
  size_t pushed = 0;    // moved (out of geometry, or off a surface)
};

// The rule, for every probe that is not kUser (s = its local spacing):
//  1. inside -> move by s/2 along `escape` (reject when escape is zero); re-test: still inside or closer
//     than 0.05 s to a surface -> reject.
//  2. not inside but nearest < 0.05 s -> move along `away` to 0.05 s off that surface; re-test: inside ->
//     reject.
// User probes are kept untouched whatever they see. Removes rejected probes (order kept).
PushOutStats pushOutProbes(PlacedProbes& probes, const ClearanceQuery& query);

// ---- Merging ----------------------------------------------------------------------------------------

// Drops near-coincident probes: two probes i, j closer than tolerance * max(s_i, s_j) (s = local spacing)
// conflict, and the one later in priority order (kUser, kSurface, kVolume, kOpen, kFiller; then input
// order) is dropped. User probes are never dropped (user-user pairs are left to the tetrahedralizer, which
// rejects exact duplicates). Hash grids per distinct tolerance; O(n) expected. Deterministic. Returns the
// number dropped.
size_t mergeProbes(PlacedProbes& probes, double tolerance = 0.1);

}  // namespace tetraprobe
