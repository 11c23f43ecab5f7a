// CPU point location in the probe tetrahedralization and SH interpolation (Cupisz, GDC 2012: barycentric
// rows per tet, and a walk that steps across the face opposite the most negative weight), started from a
// coarse uniform grid of start tets (a lighter cousin of Valient 2014's per-cell lookup).
//
// Numerics: the level stores no barycentric rows (level.h): every weight is computed in double from the
// tet's four probe positions (signed volumes, ExactFrame), so a point on or near a face, edge or vertex gets a
// tet whose weights are exact to ~1e-16 x condition and within [-1e-6, 1 + 1e-6] before clamping, on slivers
// too, and two tets sharing a face agree on which side of it a point is. A walk is bounded (kMaxWalkSteps)
// and checked for cycles (Brent); a cycle is answered by the best tet on it (see walk()), and anything else
// ends in a brute-force scan, so every query terminates with a defined answer.
//
// Outside the hull (a walk leaving through a hull face whose plane the point is beyond, decided from the
// probe positions in double) the walk continues across the outer cells (outer_cells.h) to the
// cell whose extruded hull triangle holds the point, so the outside answer is continuous and
// path-independent.
#include "tetraprobe/runtime/query.h"

#include "blend_irradiance.h"
#include "tetraprobe/runtime/lookup_constants.h"
#include "tetraprobe/runtime/outer_cells.h"
#include "tetraprobe/runtime/shade.h"

#include <algorithm>
#include <cassert>
#include <cmath>
#include <cstring>
#include <limits>
#include <system_error>
#include <thread>

#include <glm/common.hpp>
#include <glm/geometric.hpp>

namespace tetraprobe {
namespace {

using runtime_detail::blendIrradiance;

constexpr int kMaxWalkSteps = 4096;
constexpr int kMaxHintSteps = kLookupMaxHintSteps;  // lookup_constants.h (the GLSL mirrors them)
constexpr double kCycleAcceptEps = kLookupCycleAcceptEps;
constexpr double kInsideEps = kLookupInsideEps;
constexpr double kProbesPerCell = 12.0;  // start grid density (8-16 probes per cell)
constexpr int kMaxGridDim = 1024;        // per axis
constexpr double kMaxGridCells = double(1 << 22);
constexpr int kExactRings = 2;  // nearest-centroid search radius before the flood fill takes over
constexpr size_t kMinBatchPerThread = 256;
// Plain walk steps (across a face x is clearly beyond) taken from the cell grid's start tet before
// the full walk (walk()); irradianceBatch takes them in lock step over a group of queries.
constexpr int kPlainSteps = 8;
constexpr int kHintPlainSteps = 3;  // irradianceBatch: steps from the previous query's tet
constexpr size_t kBatchGroup = 16;  // irradianceBatch: queries interleaved stage by stage
constexpr size_t kHintRecent = 4;   // irradianceBatch: "coherent" while the hint answered this recently
constexpr int kMaxOuterSteps =
    kLookupMaxOuterSteps;  // an outer-cell walk, before the scan of every outer cell
// A tet whose smallest weight at x is at least this holds x alone (no other tet within kInsideEps): its
// answer is final without a walk (gridLocate, irradianceBatch's previous tet).
constexpr double kBoundaryBand = 1e-4;

// Barycentric weights of local point x in a tet, computed in double from its four probe positions: w_i is
// the signed volume of the tet with vertex i moved to x, over the tet's own volume. Each of those volumes is
// (x - p) . n with n the cross product of two edges of the face opposite vertex i (short vectors between
// probes, exact in double: the float positions' differences), and the tet's volume comes from its edges
// alone, so a weight is exact to ~1e-16 x (condition number) near the tet (~1e-12 on the 1e4 slivers of placed
// levels) and keeps its sign far from it. (Volumes formed from vectors x - p_i instead cancel to nothing at
// 1e6 m from a sliver: they made a point 1e6 m outside the hull "inside" a tet of condition 3e9,
// tests/stability.) The four need not sum to exactly 1; callers renormalize (finish()).
//
// The level stores no barycentric rows (level.h): these are the only weights the CPU uses. ExactFrame holds
// what depends on the tet alone (the face normals and 1 / volume), so a tet tested against many points
// (irradianceBatch's previous tet) prepares it once; tetWeights() prepares and evaluates, with the same
// operations on the same values, so both give the same bits.
struct ExactFrame {
  glm::dvec3 p2{0.0}, p3{0.0};
  glm::dvec3 c[4];   // c[0..2]: normals of the faces opposite p0..p2 (about p3); c[3]: opposite p3 (about p2)
  double inv = 0.0;  // 1 / volume (infinite for a tet flat in float: the weights are then not finite)

  void prepare(const Tet& t, const std::vector<glm::vec3>& probes) {
    glm::dvec3 p[4];
    for (int i = 0; i < 4; ++i) p[i] = glm::dvec3(probes[size_t(t.v[i])]);
    const glm::dvec3 e0 = p[0] - p[3], e1 = p[1] - p[3], e2 = p[2] - p[3];
    // D(a, b, c, d) = (a - d) . ((b - d) x (c - d)): the tet's volume is D(p0, p1, p2, p3), and vertex i moved
    // to x gives v0 = D(x, p1, p2, p3), v1 = D(p0, x, p2, p3), v2 = D(p0, p1, x, p3) (cyclic triple products
    // about p3), v3 = D(p0, p1, p2, x) = -D(x, p0, p1, p2) (about p2).
    c[0] = glm::cross(e1, e2);
    c[1] = glm::cross(e2, e0);
    c[2] = glm::cross(e0, e1);
    c[3] = glm::cross(p[0] - p[2], p[1] - p[2]);
    p2 = p[2];
    p3 = p[3];
    inv = 1.0 / glm::dot(e0, c[0]);
  }

  void weights(const glm::dvec3& x, double w[4]) const {
    const glm::dvec3 d3 = x - p3;
    w[0] = glm::dot(d3, c[0]) * inv;
    w[1] = glm::dot(d3, c[1]) * inv;
    w[2] = glm::dot(d3, c[2]) * inv;
    w[3] = -glm::dot(x - p2, c[3]) * inv;
  }
};

// Raw barycentric weights of local point x in tet t (may be negative outside), exact (ExactFrame).
inline void tetWeights(const Tet& t, const std::vector<glm::vec3>& probes, const glm::dvec3& x, double w[4]) {
  ExactFrame f;
  f.prepare(t, probes);
  f.weights(x, w);
}

// True when x is inside tet t by a margin (the smallest exact weight at least kBoundaryBand): no other tet
// holds x within kInsideEps, so every walk accepts this tet with these weights.
inline bool clearlyInside(double wMin) {
  return wMin >= kBoundaryBand;
}

// Smallest weight and its index.
inline int minIndex(const double w[4]) {
  int m = 0;
  for (int i = 1; i < 4; ++i)
    if (w[i] < w[m]) m = i;
  return m;
}

// A tet prepared for testing many nearby points (irradianceBatch's previous tet): its ExactFrame, so a
// point's weights are tetWeights()'s bits at a fraction of the cost.
struct PreparedTet {
  int32_t tet = -1;
  ExactFrame frame;

  void prepare(const std::vector<Tet>& tets, const std::vector<glm::vec3>& probes, int32_t t) {
    tet = t;
    frame.prepare(tets[size_t(t)], probes);
  }

  // w = tetWeights(tets[tet], x); true when clearlyInside(min w).
  bool clearlyHolds(const glm::dvec3& x, double w[4]) const {
    frame.weights(x, w);
    return clearlyInside(w[minIndex(w)]);
  }
};

// Clamps to >= 0 and renormalizes; a degenerate sum (all clamped away, or non-finite) gives equal weights.
inline Location finish(int32_t tet, const double w[4], bool inside) {
  double c[4], sum = 0.0;
  for (int i = 0; i < 4; ++i) {
    c[i] = w[i] > 0.0 ? w[i] : 0.0;  // NaN -> 0
    sum += c[i];
  }
  Location loc;
  loc.tet = tet;
  loc.inside = inside;
  if (!(sum > 0.0) || !std::isfinite(sum)) {
    loc.weights = glm::vec4(0.25f);
    loc.inside = false;
    return loc;
  }
  for (int i = 0; i < 4; ++i) loc.weights[i] = float(c[i] / sum);
  return loc;
}

// finish(tet, w, true) for weights that are all positive and finite (PreparedTet::clearlyHolds accepted
// them): the same operations without the clamps and checks that cannot fire.
inline Location finishClear(int32_t tet, const double w[4]) {
  const double sum = ((w[0] + w[1]) + w[2]) + w[3];  // finish's 0.0 + w[0] is w[0]: w[0] > 0
  Location loc;
  loc.tet = tet;
  loc.inside = true;
  for (int i = 0; i < 4; ++i) loc.weights[i] = float(w[i] / sum);
  return loc;
}

// Local-frame point with a defined value for any input: NaN components go to the probe bounds' centre,
// +-Inf to the bounds, and points absurdly far away are pulled radially to `maxRadius` from the centre (the
// direction is kept, so the hull tet found is the same; the weights stay far from overflow).
// The bounds it needs are computed once per batch (SanitizeFrame), with the same operations as per query.
struct SanitizeFrame {
  glm::dvec3 lo, hi, centre;
  double maxRadius;
};

SanitizeFrame sanitizeFrame(const StartGrid& g) {
  SanitizeFrame f;
  f.lo = glm::dvec3(g.min);
  f.hi = f.lo + glm::dvec3(g.cellSize) * glm::dvec3(g.dims);
  f.centre = 0.5 * (f.lo + f.hi);
  f.maxRadius = 1e6 * (glm::length(f.hi - f.lo) + 1.0);
  return f;
}

inline glm::dvec3 sanitize(glm::dvec3 x, const SanitizeFrame& f) {
  for (int a = 0; a < 3; ++a) {
    if (std::isnan(x[a])) x[a] = f.centre[a];
    if (std::isinf(x[a])) x[a] = x[a] > 0 ? f.hi[a] : f.lo[a];
  }
  const glm::dvec3 d = x - f.centre;
  const double far = std::max({std::abs(d.x), std::abs(d.y), std::abs(d.z)});
  if (far > f.maxRadius) {
    const glm::dvec3 dir = d / far;  // scaled first: |d|^2 could overflow
    x = f.centre + dir * (f.maxRadius / glm::length(dir));
  }
  return x;
}

glm::dvec3 sanitize(const glm::dvec3& x, const StartGrid& g) {
  return sanitize(x, sanitizeFrame(g));
}

int32_t gridCell(const StartGrid& g, const glm::dvec3& x) {
  int c[3];
  for (int a = 0; a < 3; ++a) {
    const double f = std::floor((x[a] - double(g.min[a])) / double(g.cellSize[a]));
    c[a] = int(std::clamp(f, 0.0, double(g.dims[a] - 1)));  // clamp in double: no overflowing int conversion
  }
  return c[0] + g.dims.x * (c[1] + g.dims.y * c[2]);
}

// True when local point x lies strictly beyond the plane of tet t's face opposite t.v[f] (the side away from
// t.v[f]), from the probe positions in double.
bool beyondHullFace(const Tet& t, const std::vector<glm::vec3>& probes, int f, const glm::dvec3& x) {
  const glm::dvec3 p0(probes[size_t(t.v[(f + 1) & 3])]), p1(probes[size_t(t.v[(f + 2) & 3])]),
      p2(probes[size_t(t.v[(f + 3) & 3])]), opp(probes[size_t(t.v[f])]);
  const glm::dvec3 n = glm::cross(p1 - p0, p2 - p0);
  const double sx = glm::dot(n, x - p0), so = glm::dot(n, opp - p0);
  return (sx > 0.0 && so < 0.0) || (sx < 0.0 && so > 0.0);
}

// Walks from tet `cur` towards x, stepping across the face opposite the most negative weight. Weights are
// exact (tetWeights), so two tets sharing a face agree on its side to ~1e-16 x condition; a walk that still
// cycles (within that rounding, around a point on a sliver's face) answers with the tet along the walk that
// holds x best (largest smallest weight), if it holds it within kCycleAcceptEps; otherwise (or after
// maxSteps) the walk returns false and the caller scans.
// When the walk leaves through a hull face, `out` is the clamped hull tet and *exitFace the face's index.
bool walk(const std::vector<Tet>& tets, const std::vector<glm::vec3>& probes, const glm::dvec3& x,
          int32_t cur, int maxSteps, Location& out, int32_t* exitFace) {
  *exitFace = -1;
  int32_t saved = cur;  // Brent's cycle detection: compare against a checkpoint moved at powers of two
  int power = 1, lam = 0;
  int32_t best = -1;
  double bestMin = -std::numeric_limits<double>::infinity(), bestW[4] = {};
  const auto weights = [&](int32_t t, double w[4]) { tetWeights(tets[size_t(t)], probes, x, w); };
  // The answer's weights depend on the tet alone, not on the path.
  const auto accept = [&](int32_t t, const double w[4]) { return finish(t, w, true); };
  for (int step = 0; step < maxSteps; ++step) {
    double w[4];
    weights(cur, w);
    int m = minIndex(w);
    int32_t next = tets[size_t(cur)].n[m];
    if (w[m] >= -kInsideEps || std::isnan(w[m])) {
      // Inside within tolerance. A point within kInsideEps of a face may be more inside the neighbour: take
      // whichever tet holds it better, so the answer does not depend on the side the walk came from.
      if (w[m] < 0.0 && next >= 0) {
        double wn[4];
        weights(next, wn);
        if (wn[minIndex(wn)] > w[m]) {
          out = accept(next, wn);
          return true;
        }
      }
      out = accept(cur, w);
      return true;
    }
    if (next < 0) {
      // Leaving through a hull face: the point is outside the (convex) hull, if it is beyond the face's
      // plane (from the probe positions in double, the face's own orientation test).
      if (beyondHullFace(tets[size_t(cur)], probes, m, x)) {
        out = finish(cur, w, false);
        *exitFace = m;
        return true;
      }
      // Not beyond it: step across the most negative interior face instead, or stop here when none is
      // negative beyond the tolerance.
      int mi = -1;
      for (int i = 0; i < 4; ++i)
        if (tets[size_t(cur)].n[i] >= 0 && (mi < 0 || w[i] < w[mi])) mi = i;
      if (mi < 0 || w[mi] >= -kInsideEps) {
        out = accept(cur, w);
        return true;
      }
      next = tets[size_t(cur)].n[mi];
      m = mi;
    }
    if (w[m] > bestMin) {
      best = cur;
      bestMin = w[m];
      std::copy(w, w + 4, bestW);
    }
    assert(size_t(next) < tets.size());
    cur = next;
    if (cur == saved) {  // a cycle: every tet on it has been visited, so `best` is the best of them
      if (bestMin < -kCycleAcceptEps) return false;
      out = finish(best, bestW, bestMin >= -kInsideEps);
      return true;
    }
    if (++lam == power) {
      saved = cur;
      power *= 2;
      lam = 0;
    }
  }
  return false;
}

// One plain walk step from tet `cur`: the neighbour across the face of the most negative weight when x is
// beyond that face (below -kInsideEps) and the neighbour exists; else -1 (the full walk takes over). A walk's
// first steps are usually such steps: walk() from the tet they reach takes the same path the walk from `cur`
// would (it is deterministic, and such steps are its own).
inline int32_t plainStep(const std::vector<Tet>& tets, const std::vector<glm::vec3>& probes,
                         const glm::dvec3& x, int32_t cur, double w[4]) {
  const Tet& t = tets[size_t(cur)];
  tetWeights(t, probes, x, w);
  const int m = minIndex(w);
  if (!(w[m] < -kInsideEps)) return -1;
  return t.n[m];
}

inline void prefetchTet(const std::vector<Tet>& tets, int32_t t) {
  const char* p = reinterpret_cast<const char*>(tets.data() + t);
  __builtin_prefetch(p);
  __builtin_prefetch(p + sizeof(Tet) - 1);
}

inline void prefetchSh(const Level& level, const Tet& t) {
  for (int i = 0; i < 4; ++i) {
    const char* p = reinterpret_cast<const char*>(level.sh.data() + t.v[i]);
    __builtin_prefetch(p);
    __builtin_prefetch(p + 64);
    __builtin_prefetch(p + sizeof(ShRgb) - 1);
  }
}

Location scanAll(const Level& level, const glm::dvec3& x) {
  int32_t best = -1;
  double bestMin = -std::numeric_limits<double>::infinity(), bestW[4] = {0.25, 0.25, 0.25, 0.25};
  for (size_t t = 0; t < level.tets.size(); ++t) {
    double w[4];
    tetWeights(level.tets[t], level.probes, x, w);
    const double m = w[minIndex(w)];
    if (best < 0 || m > bestMin) {
      best = int32_t(t);
      bestMin = m;
      std::copy(w, w + 4, bestW);
    }
  }
  return finish(best, bestW, bestMin >= -kInsideEps);
}

// The answer of outer cell k: its triangle weights (tiny negatives clamped, renormalized) on the hull tet.
Location finishOuter(const std::vector<Tet>& tets, const std::vector<OuterCell>& cells, int32_t k,
                     const OuterWeights& ow) {
  const OuterCell& cell = cells[size_t(k)];
  const Tet& tet = tets[size_t(cell.tet)];
  double w[4] = {0.0, 0.0, 0.0, 0.0};
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 4; ++j)
      if (tet.v[j] == cell.v[i]) w[j] = ow.b[i];
  Location loc = finish(cell.tet, w, false);
  loc.inside = false;
  loc.outerCell = k;
  return loc;
}

// Builds the start grid: cells of ~kProbesPerCell probes over the probe bounds; each cell names the tet
// whose centroid is nearest its centre (exact search over rings of cells up to kExactRings, then a
// breadth-first flood fill for cells with no centroid that close). O(tets + cells), no per-cell scan.
StartGrid buildStartGrid(const Level& level) {
  StartGrid g;
  if (level.tets.empty()) return g;
  glm::dvec3 lo(std::numeric_limits<double>::infinity()), hi(-std::numeric_limits<double>::infinity());
  for (const glm::vec3& p : level.probes) {
    lo = glm::min(lo, glm::dvec3(p));
    hi = glm::max(hi, glm::dvec3(p));
  }
  glm::dvec3 ext = hi - lo;
  const double maxExt = std::max({ext.x, ext.y, ext.z, 1e-3});
  ext = glm::max(ext, glm::dvec3(1e-3 * maxExt));
  const double cells = std::clamp(double(level.probes.size()) / kProbesPerCell, 1.0, kMaxGridCells);
  const double cell = std::cbrt(ext.x * ext.y * ext.z / cells);
  for (int a = 0; a < 3; ++a) g.dims[a] = int(std::clamp(std::ceil(ext[a] / cell), 1.0, double(kMaxGridDim)));
  // Float cell geometry (the GPU's values), padded by a hair so the max-corner probes fall inside.
  g.min = glm::vec3(lo);
  g.cellSize = glm::vec3(ext * (1.0 + 1e-6) / glm::dvec3(g.dims));
  const glm::ivec3 dims = g.dims;
  const size_t cellCount = size_t(dims.x) * size_t(dims.y) * size_t(dims.z);

  // Bin tet centroids into cells (counting sort).
  std::vector<glm::dvec3> centroid(level.tets.size());
  std::vector<int32_t> cellOf(level.tets.size());
  std::vector<int32_t> start(cellCount + 1, 0);
  for (size_t t = 0; t < level.tets.size(); ++t) {
    glm::dvec3 c(0.0);
    for (int i = 0; i < 4; ++i) c += glm::dvec3(level.probes[size_t(level.tets[t].v[i])]);
    centroid[t] = 0.25 * c;
    cellOf[t] = gridCell(g, centroid[t]);
    ++start[size_t(cellOf[t]) + 1];
  }
  for (size_t c = 0; c < cellCount; ++c) start[c + 1] += start[c];
  std::vector<int32_t> binned(level.tets.size());
  {
    std::vector<int32_t> fill(start.begin(), start.end() - 1);
    for (size_t t = 0; t < level.tets.size(); ++t) binned[size_t(fill[size_t(cellOf[t])]++)] = int32_t(t);
  }

  const glm::dvec3 cs(g.cellSize), gmin(g.min);
  const double minCell = std::min({cs.x, cs.y, cs.z});
  g.startTet.assign(cellCount, -1);
  std::vector<int32_t> queue;
  queue.reserve(cellCount);
  for (int z = 0; z < dims.z; ++z)
    for (int y = 0; y < dims.y; ++y)
      for (int x = 0; x < dims.x; ++x) {
        const glm::dvec3 centre = gmin + (glm::dvec3(x, y, z) + 0.5) * cs;
        int32_t best = -1;
        double bestD = std::numeric_limits<double>::infinity();
        for (int r = 0; r <= kExactRings; ++r) {
          for (int cz = std::max(z - r, 0); cz <= std::min(z + r, dims.z - 1); ++cz)
            for (int cy = std::max(y - r, 0); cy <= std::min(y + r, dims.y - 1); ++cy)
              for (int cx = std::max(x - r, 0); cx <= std::min(x + r, dims.x - 1); ++cx) {
                if (std::max({std::abs(cx - x), std::abs(cy - y), std::abs(cz - z)}) != r)
                  continue;  // shell only
                const size_t c = size_t(cx) + size_t(dims.x) * (size_t(cy) + size_t(dims.y) * size_t(cz));
                for (int32_t k = start[c]; k < start[c + 1]; ++k) {
                  const int32_t t = binned[size_t(k)];
                  const glm::dvec3 d = centroid[size_t(t)] - centre;
                  const double d2 = glm::dot(d, d);
                  if (d2 < bestD || (d2 == bestD && t < best)) {
                    bestD = d2;
                    best = t;
                  }
                }
              }
          // Every centroid in ring r+1 is at least (r + 0.5) cells from this centre.
          const double bound = (r + 0.5) * minCell;
          if (best >= 0 && bestD <= bound * bound) break;
        }
        const int32_t cell = x + dims.x * (y + dims.y * z);
        g.startTet[size_t(cell)] = best;
        if (best >= 0) queue.push_back(cell);
      }
  // Flood fill the rest from resolved cells (face neighbours, breadth first: deterministic).
  for (size_t head = 0; head < queue.size(); ++head) {
    const int32_t cell = queue[head];
    const int x = cell % dims.x, y = (cell / dims.x) % dims.y, z = cell / (dims.x * dims.y);
    const int nb[6][3] = {{x - 1, y, z}, {x + 1, y, z}, {x, y - 1, z},
                          {x, y + 1, z}, {x, y, z - 1}, {x, y, z + 1}};
    for (const auto& n : nb) {
      if (n[0] < 0 || n[1] < 0 || n[2] < 0 || n[0] >= dims.x || n[1] >= dims.y || n[2] >= dims.z) continue;
      const int32_t ncell = n[0] + dims.x * (n[1] + dims.y * n[2]);
      if (g.startTet[size_t(ncell)] >= 0) continue;
      g.startTet[size_t(ncell)] = g.startTet[size_t(cell)];
      queue.push_back(ncell);
    }
  }
  return g;
}

}  // namespace

ProbeQuery::ProbeQuery(const Level& level, float cellSize, int threads)
    : level_(level), grid_(buildStartGrid(level)) {
  if (level.outerCells.empty() && !level.tets.empty()) ownCells_ = buildOuterCells(level.probes, level.tets);
  if (cellSize != kStoredCellGridOnly &&
      (level.cellGrid.slots.empty() || level.cellGrid.cellSize != cellSize))
    ownGrid_ = buildCellGrid(level.probes, level.tets, cellSize, threads);
}

// Walks the outer cells from `startCell` to the one whose extruded triangle holds x: each step crosses the
// edge opposite the most negative barycentric. Bounded; a cycle, a missing link or the bound ends in the
// scan.
Location ProbeQuery::outerLocate(const glm::dvec3& x, int32_t startCell) const {
  const std::vector<OuterCell>& cells = outerCells();
  int32_t cur = startCell, saved = startCell;
  int power = 1, lam = 0;
  for (int step = 0; step < kMaxOuterSteps && cur >= 0; ++step) {
    const OuterWeights ow = outerCellWeights(cells[size_t(cur)], level_.probes, x);
    int m = 0;
    for (int i = 1; i < 3; ++i)
      if (ow.b[i] < ow.b[m]) m = i;
    if (ow.valid && ow.b[m] >= -kInsideEps) return finishOuter(level_.tets, cells, cur, ow);
    cur = cells[size_t(cur)].n[m];
    if (cur == saved) break;
    if (++lam == power) {
      saved = cur;
      power *= 2;
      lam = 0;
    }
  }
  return outerScan(x, scanAll(level_, x));
}

// Every outer cell with a root: the one whose smallest barycentric is largest (ties: lowest index);
// `fallback` (the clamped best tet) when no cell reaches x.
Location ProbeQuery::outerScan(const glm::dvec3& x, const Location& fallback) const {
  const std::vector<OuterCell>& cells = outerCells();
  int32_t best = -1;
  OuterWeights bestW;
  double bestMin = -std::numeric_limits<double>::infinity();
  for (size_t k = 0; k < cells.size(); ++k) {
    const OuterWeights ow = outerCellWeights(cells[k], level_.probes, x);
    if (!ow.valid) continue;
    const double m = std::min({ow.b[0], ow.b[1], ow.b[2]});
    if (m > bestMin) {
      best = int32_t(k);
      bestMin = m;
      bestW = ow;
    }
  }
  return best >= 0 ? finishOuter(level_.tets, cells, best, bestW) : fallback;
}

Location ProbeQuery::bruteForceLocate(const glm::dvec3& world) const {
  if (level_.tets.empty()) return Location{};
  const glm::dvec3 x = sanitize(world - level_.origin, grid_);
  const Location loc = scanAll(level_, x);
  return loc.inside ? loc : outerScan(x, loc);
}

// The walk from `hint` (short budget, if valid), else from `start` (full budget), else the scans; leaving the
// hull continues across the outer cells.
Location ProbeQuery::walkFrom(const glm::dvec3& x, int32_t start, int32_t hint) const {
  Location loc;
  const std::vector<Tet>& tets = level_.tets;
  int32_t exitFace = -1;
  if (!(hint >= 0 && size_t(hint) < tets.size() &&
        walk(tets, level_.probes, x, hint, kMaxHintSteps, loc, &exitFace)) &&
      !walk(tets, level_.probes, x, start, kMaxWalkSteps, loc, &exitFace)) {
    loc = scanAll(level_, x);
    return loc.inside ? loc : outerScan(x, loc);
  }
  if (exitFace < 0) return loc;
  // Outside the hull: continue across the outer cells from the face the walk left through.
  const int32_t cell = findOuterCell(outerCells(), loc.tet, exitFace);
  return cell >= 0 ? outerLocate(x, cell) : loc;
}

bool locateByWalk(const Level& level, const glm::dvec3& x, int32_t start, Location& out) {
  if (start < 0 || size_t(start) >= level.tets.size()) return false;
  Location loc;
  int32_t exitFace = -1;
  if (!walk(level.tets, level.probes, x, start, kMaxWalkSteps, loc, &exitFace) || exitFace >= 0) return false;
  out = loc;
  return true;
}

Location ProbeQuery::locate(const glm::dvec3& world, int32_t hint) const {
  if (level_.tets.empty()) return Location{};
  const glm::dvec3 x = sanitize(world - level_.origin, grid_);
  if (hint >= 0 && size_t(hint) < level_.tets.size()) {
    // A per-object hint first: its short walk usually ends at once (Unity-style caching). Its answer is
    // taken only where no other tet can hold the point (clearly inside: the weights the full locate gives
    // too); on or near a face, edge or vertex several tets hold it and the occluded, face-blended light of
    // each differs a little, so the full locate names the one it always names.
    Location loc;
    int32_t exitFace = -1;
    if (walk(level_.tets, level_.probes, x, hint, kMaxHintSteps, loc, &exitFace) && exitFace < 0 &&
        clearlyInside(
            std::min(std::min(loc.weights.x, loc.weights.y), std::min(loc.weights.z, loc.weights.w))))
      return loc;
  }
  return gridLocate(x);
}

// The cell grid's leaf names the tet holding the leaf's region; the walk from it decides the answer (it
// accepts at once unless the point is within rounding of a face, so the answer does not depend on how the
// tree was split), stepping to the neighbour or out to the outer cells as needed.
Location ProbeQuery::gridLocate(const glm::dvec3& x) const {
  int32_t cur = startTet(x, cellGridLeaf(cellGrid(), x));
  double w[4];
  for (int s = 0; s < kPlainSteps; ++s) {
    const int32_t next = plainStep(level_.tets, level_.probes, x, cur, w);
    if (next < 0) {
      // Clearly inside (the leaf's tet, usually): the walk would accept these weights at once.
      if (clearlyInside(w[minIndex(w)])) return finish(cur, w, true);
      break;
    }
    cur = next;
  }
  return walkFrom(x, cur, -1);
}

// The leaf's tet, or where there is none (an absent cell or an empty leaf: outside the tets, up to rounding)
// the coarse start grid's tet.
int32_t ProbeQuery::startTet(const glm::dvec3& x, int32_t leafTet) const {
  return leafTet >= 0 ? leafTet : grid_.startTet[size_t(gridCell(grid_, x))];
}

Location ProbeQuery::walkLocate(const glm::dvec3& world) const {
  if (level_.tets.empty()) return Location{};
  const glm::dvec3 x = sanitize(world - level_.origin, grid_);
  return walkFrom(x, grid_.startTet[size_t(gridCell(grid_, x))], -1);
}

glm::vec3 ProbeQuery::irradiance(const glm::dvec3& world, const glm::vec3& normal, int32_t* tetCache) const {
  const Location loc = locate(world, tetCache ? *tetCache : -1);
  if (tetCache) *tetCache = loc.tet;
  return shadeLocated(level_, occlusion(), loc, world, normal);
}

ShRgb ProbeQuery::interpolatedSh(const glm::dvec3& world, int32_t* tetCache) const {
  const Location loc = locate(world, tetCache ? *tetCache : -1);
  if (tetCache) *tetCache = loc.tet;
  return shadeLocatedSh(level_, occlusion(), loc, world);
}

glm::vec3 ProbeQuery::explain(const glm::dvec3& world, const glm::vec3& normal, ShadeRecord& record) const {
  return shadeLocated(level_, occlusion(), locate(world), world, normal, &record);
}

// Random queries on a large level are bound by memory latency: the hash slot, a dozen or more BSP nodes, the
// leaf's tet and four SH records, each a dependent cache miss. A group of kBatchGroup queries therefore goes
// through locate()'s stages in lock step, each stage prefetching what the next needs for every query of the
// group, so their misses overlap (group prefetching, Chen et al., "Improving hash join performance through
// prefetching", ICDE 2004). Coherent queries (pixel order) first try the previous query's tet when they lie
// within a quarter cell of the previous query: a few steps from it to a tet that holds the point clearly (by
// more than kBoundaryBand) give the answer the full locate() gives, as no other tet can hold such a point
// within tolerance. That tet is kept prepared (PreparedTet: its face normals and inverse volume in double), and
// a query it misses shortly after a hit is located at once rather than in the group's pipeline, so the next
// query starts from its tet. Without occlusion the SH blend and irradiance run inline (blendIrradiance).
// Every stage computes what locate() computes, in the same order: out[i] is bit-identical to
// irradiance(world[i], normal[i]).
void ProbeQuery::batchRange(const glm::dvec3* world, const glm::vec3* normal, glm::vec3* out, size_t begin,
                            size_t end) const {
  const std::vector<Tet>& tets = level_.tets;
  const CellGrid& grid = cellGrid();
  const bool hasGrid = !grid.slots.empty();
  glm::dvec3 x[kBatchGroup];
  int32_t key[kBatchGroup][3], code[kBatchGroup], cur[kBatchGroup];
  size_t slot[kBatchGroup];
  bool haveKey[kBatchGroup], done[kBatchGroup];
  Location loc[kBatchGroup];
  PreparedTet hint;            // the previous query's tet
  ShadeFrameCache frameCache;  // the last occluded tet's BaryFrame (shadeLocated)
  // Queries since the hint last answered one: while small (coherent order) a query the hint misses is
  // located at once, so the next one has its tet as hint (deferring it to the group's pipeline would leave
  // the rest of the group a stale hint, a few tets behind).
  size_t sinceHit = kBatchGroup;
  glm::dvec3 prevX(std::numeric_limits<double>::infinity());
  const double hintGate = 0.25 * double(grid.cellSize);
  const SanitizeFrame frame = sanitizeFrame(grid_);
  for (size_t g = begin; g < end; g += kBatchGroup) {
    const size_t n = std::min(kBatchGroup, end - g);
    // The local point and its cell; the previous query's tet for a point in the same cell.
    for (size_t k = 0; k < n; ++k) {
      x[k] = sanitize(world[g + k] - level_.origin, frame);
      done[k] = false;
      const glm::dvec3 d = glm::abs(x[k] - prevX);
      prevX = x[k];
      ++sinceHit;
      if (hint.tet >= 0 && std::max({d.x, d.y, d.z}) < hintGate) {
        double w[4];
        done[k] = hint.clearlyHolds(x[k], w);
        // Else up to kHintPlainSteps plain steps (across a face x is clearly beyond) from it.
        for (int s = 0; s < kHintPlainSteps && !done[k]; ++s) {
          const Tet& t = tets[size_t(hint.tet)];
          const int m = minIndex(w);
          if (!(w[m] < -kInsideEps) || t.n[m] < 0) break;
          hint.prepare(tets, level_.probes, t.n[m]);
          prefetchSh(level_, tets[size_t(hint.tet)]);
          done[k] = hint.clearlyHolds(x[k], w);
        }
        if (done[k]) {
          loc[k] = finishClear(hint.tet, w);
          sinceHit = 0;
          continue;
        }
      }
      if (sinceHit <= kHintRecent) {
        loc[k] = gridLocate(x[k]);
        done[k] = true;
        if (loc[k].inside) hint.prepare(tets, level_.probes, loc[k].tet);
        prefetchSh(level_, tets[size_t(loc[k].tet)]);
        continue;
      }
      haveKey[k] = hasGrid && cellGridKey(grid, x[k], key[k]);
      if (haveKey[k]) {
        slot[k] = cellGridSlot(grid, key[k]);
        __builtin_prefetch(grid.slots.data() + slot[k]);
      }
    }
    // The cell's tree, then its nodes down to the leaf, one level per round; each step prefetches what the
    // code it reached names (a node, or the leaf's tet). True while a node is still to descend.
    const auto prefetchCode = [&](int32_t c) {
      if (c >= 0)
        __builtin_prefetch(grid.nodes.data() + c);
      else if (bspLeafTet(c) >= 0)
        prefetchTet(tets, bspLeafTet(c));
      return c >= 0;
    };
    bool descending = false;
    for (size_t k = 0; k < n; ++k) {
      code[k] = 0;
      if (done[k]) continue;
      if (!haveKey[k] || !cellGridFind(grid, key[k], slot[k], &code[k])) {
        haveKey[k] = false;  // no leaf: the start grid's tet
        continue;
      }
      descending |= prefetchCode(code[k]);
    }
    while (descending) {
      descending = false;
      for (size_t k = 0; k < n; ++k) {
        if (done[k] || !haveKey[k] || code[k] < 0) continue;
        code[k] = cellGridChild(grid.nodes[size_t(code[k])], x[k]);
        descending |= prefetchCode(code[k]);
      }
    }
    // The leaf's tet, then plain walk steps in lock step.
    for (size_t k = 0; k < n; ++k) {
      if (done[k]) continue;
      cur[k] = startTet(x[k], haveKey[k] ? bspLeafTet(code[k]) : -1);
      prefetchTet(tets, cur[k]);
      code[k] = 0;  // now: plain steps still to take (0 = taking them)
    }
    for (int s = 0; s < kPlainSteps; ++s) {
      bool moved = false;
      for (size_t k = 0; k < n; ++k) {
        if (done[k] || code[k] != 0) continue;
        double w[4];
        const int32_t next = plainStep(tets, level_.probes, x[k], cur[k], w);
        if (next < 0) {
          code[k] = 1;
          // Clearly inside (the leaf's tet, usually): the walk would accept these weights at once.
          if (clearlyInside(w[minIndex(w)])) {
            loc[k] = finish(cur[k], w, true);
            prefetchSh(level_, tets[size_t(cur[k])]);
            code[k] = 2;
          }
          continue;
        }
        cur[k] = next;
        prefetchTet(tets, next);
        moved = true;
      }
      if (!moved) break;
    }
    // The full walk from there (usually accepting at once), then the SH records.
    for (size_t k = 0; k < n; ++k) {
      if (done[k] || code[k] == 2) continue;
      loc[k] = walkFrom(x[k], cur[k], -1);
      if (loc[k].tet >= 0) prefetchSh(level_, tets[size_t(loc[k].tet)]);
    }
    if (usesOcclusion()) {
      for (size_t k = 0; k < n; ++k)
        out[g + k] = shadeLocated(level_, &level_.occlusion, loc[k], world[g + k], normal[g + k], nullptr,
                                  &frameCache);
    } else {  // shadeLocated() without occlusion, inlined (every located query has a tet)
      for (size_t k = 0; k < n; ++k)
        out[g + k] = blendIrradiance(level_.sh, tets[size_t(loc[k].tet)], loc[k].weights, normal[g + k]);
    }
    if (loc[n - 1].inside && loc[n - 1].tet != hint.tet) hint.prepare(tets, level_.probes, loc[n - 1].tet);
  }
}

void ProbeQuery::irradianceBatch(const glm::dvec3* world, const glm::vec3* normal, glm::vec3* out,
                                 size_t count, int threads) const {
  if (count == 0) return;
  if (level_.tets.empty()) {
    std::fill(out, out + count, glm::vec3(0.0f));
    return;
  }
  size_t n = threads > 0 ? size_t(threads) : size_t(std::max(1u, std::thread::hardware_concurrency()));
  n = std::clamp<size_t>((count + kMinBatchPerThread - 1) / kMinBatchPerThread, 1, n);
  auto work = [=, this](size_t begin, size_t end) { batchRange(world, normal, out, begin, end); };
  std::vector<std::thread> pool;
  pool.reserve(n - 1);
  const size_t chunk = (count + n - 1) / n;
  for (size_t k = 1; k < n; ++k) {
    const size_t begin = std::min(count, k * chunk), end = std::min(count, begin + chunk);
    try {
      pool.emplace_back(work, begin, end);
    } catch (const std::system_error&) {
      work(begin, end);  // no thread available: do that share here
    }
  }
  work(0, std::min(count, chunk));
  for (std::thread& t : pool) t.join();
}

}  // namespace tetraprobe
