// Delaunay tetrahedralization of probe positions (CGAL Delaunay_triangulation_3 over EPICK: exact predicates,
// so the mesh is a true Delaunay mesh even for cospherical grids), extracted into a deterministic, positively
// oriented tet list with face neighbours, and the per-tet barycentric records of Cupisz (GDC 2012, "Light
// probe interpolation using tetrahedral tessellations"): M = inverse of [P0-P3 | P1-P3 | P2-P3].
//
// Determinism: CGAL spatially sorts the (point, index) range with a default-seeded generator and breaks
// cospherical ties by symbolic perturbation, so one input gives one triangulation; the extraction below then
// puts every tet into a canonical even permutation (orientation kept) and sorts the tets by the Morton code
// of their centroid, then by vertex tuple, so the output does not depend on CGAL's cell storage order either.
//
// This is the only translation unit of the module that includes CGAL (it compiles slowly).
#include "tetraprobe/tetra/tetrahedralize.h"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <string>
#include <utility>

#include <CGAL/Delaunay_triangulation_3.h>
#include <CGAL/Delaunay_triangulation_cell_base_3.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Triangulation_cell_base_with_info_3.h>
#include <CGAL/Triangulation_data_structure_3.h>
#include <CGAL/Triangulation_vertex_base_with_info_3.h>
#include <glm/common.hpp>
#include <glm/mat3x3.hpp>
#include <glm/matrix.hpp>

#include "tetraprobe/common/error.h"

namespace tetraprobe {
namespace {

using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
using VertexBase = CGAL::Triangulation_vertex_base_with_info_3<int32_t, Kernel>;
using CellBase = CGAL::Triangulation_cell_base_with_info_3<int32_t, Kernel,
                                                           CGAL::Delaunay_triangulation_cell_base_3<Kernel>>;
using Tds = CGAL::Triangulation_data_structure_3<VertexBase, CellBase, CGAL::Sequential_tag>;
using Delaunay = CGAL::Delaunay_triangulation_3<Kernel, Tds>;

std::string describe(const glm::dvec3& p) {
  return "(" + std::to_string(p.x) + ", " + std::to_string(p.y) + ", " + std::to_string(p.z) + ")";
}

// Rejects what CGAL cannot triangulate (or would silently merge), naming the offending input.
void validatePoints(const std::vector<glm::dvec3>& points) {
  if (points.size() < 4)
    throw InputError("tetrahedralize: " + std::to_string(points.size()) +
                     " probes; at least 4 non-coplanar probes are needed");
  if (points.size() > size_t(INT32_MAX))
    throw InputError("tetrahedralize: " + std::to_string(points.size()) +
                     " probes exceed the int32 index range");
  for (size_t i = 0; i < points.size(); ++i) {
    const glm::dvec3& p = points[i];
    if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z))
      throw InputError("tetrahedralize: probe " + std::to_string(i) + " has a non-finite coordinate " +
                       describe(p));
  }
  // Exact duplicates, found by a lexicographic sort of the indices (O(n log n); stable so the lower index of
  // a duplicate pair comes first).
  std::vector<int32_t> order(points.size());
  std::iota(order.begin(), order.end(), 0);
  auto less = [&](int32_t a, int32_t b) {
    const glm::dvec3 &p = points[size_t(a)], &q = points[size_t(b)];
    if (p.x != q.x) return p.x < q.x;
    if (p.y != q.y) return p.y < q.y;
    return p.z < q.z;
  };
  std::stable_sort(order.begin(), order.end(), less);
  for (size_t k = 1; k < order.size(); ++k) {
    if (points[size_t(order[k - 1])] == points[size_t(order[k])]) {
      const int32_t a = std::min(order[k - 1], order[k]), b = std::max(order[k - 1], order[k]);
      throw InputError("tetrahedralize: probes " + std::to_string(a) + " and " + std::to_string(b) +
                       " are at the same position " + describe(points[size_t(a)]));
    }
  }
}

// One extracted tet: vertices and neighbours in lockstep (neighbours[i] is across the face opposite v[i]).
struct RawTet {
  std::array<int32_t, 4> v;
  std::array<int32_t, 4> n;
};

// Applies the even permutation that puts the smallest vertex first and the smallest of the other three
// second. Even permutations keep the orientation, and this representative is unique per tet.
void canonicalize(RawTet& t) {
  auto swapPair = [&](int a, int b, int c, int d) {  // swaps (a,b) and (c,d): an even permutation
    std::swap(t.v[size_t(a)], t.v[size_t(b)]);
    std::swap(t.n[size_t(a)], t.n[size_t(b)]);
    std::swap(t.v[size_t(c)], t.v[size_t(d)]);
    std::swap(t.n[size_t(c)], t.n[size_t(d)]);
  };
  const int m = int(std::min_element(t.v.begin(), t.v.end()) - t.v.begin());
  if (m == 1) swapPair(0, 1, 2, 3);
  if (m == 2) swapPair(0, 2, 1, 3);
  if (m == 3) swapPair(0, 3, 1, 2);
  // Cyclic rotation of positions 1..3 (a 3-cycle, even) until position 1 holds the smallest of them.
  auto rotate = [&] {
    std::rotate(t.v.begin() + 1, t.v.begin() + 2, t.v.end());
    std::rotate(t.n.begin() + 1, t.n.begin() + 2, t.n.end());
  };
  while (t.v[1] > t.v[2] || t.v[1] > t.v[3]) rotate();
}

// 63-bit Morton code (21 bits per axis, x lowest) of p quantized over [lo, hi].
uint64_t mortonKey(const glm::dvec3& p, const glm::dvec3& lo, const glm::dvec3& hi) {
  auto spread = [](uint64_t x) {  // 21 bits -> every third bit
    x &= 0x1FFFFF;
    x = (x | x << 32) & 0x1F00000000FFFFull;
    x = (x | x << 16) & 0x1F0000FF0000FFull;
    x = (x | x << 8) & 0x100F00F00F00F00Full;
    x = (x | x << 4) & 0x10C30C30C30C30C3ull;
    x = (x | x << 2) & 0x1249249249249249ull;
    return x;
  };
  uint64_t code = 0;
  for (int a = 0; a < 3; ++a) {
    const double extent = hi[a] - lo[a];
    const double f = extent > 0.0 ? std::clamp((p[a] - lo[a]) / extent, 0.0, 1.0) : 0.0;
    code |= spread(uint64_t(f * double((1u << 21) - 1))) << a;
  }
  return code;
}

}  // namespace

TetMesh tetrahedralizeDelaunay(const std::vector<glm::dvec3>& points) {
  validatePoints(points);

  std::vector<std::pair<Kernel::Point_3, int32_t>> input;
  input.reserve(points.size());
  for (size_t i = 0; i < points.size(); ++i)
    input.emplace_back(Kernel::Point_3(points[i].x, points[i].y, points[i].z), int32_t(i));
  Delaunay dt;
  dt.insert(input.begin(), input.end());  // spatially sorted insertion

  if (dt.dimension() < 3)
    throw InputError("tetrahedralize: all " + std::to_string(points.size()) + " probes are " +
                     (dt.dimension() == 2 ? "coplanar" : "collinear") + "; a volume needs probes off that " +
                     (dt.dimension() == 2 ? "plane" : "line"));
  if (dt.number_of_vertices() != points.size())  // duplicates were rejected above: this is a broken invariant
    throw std::logic_error("tetrahedralize: CGAL kept " + std::to_string(dt.number_of_vertices()) + " of " +
                           std::to_string(points.size()) + " probes");

  // Number the finite cells (infinite ones are -1), then read vertices and neighbours through those numbers.
  for (auto c = dt.all_cells_begin(); c != dt.all_cells_end(); ++c) c->info() = -1;
  int32_t count = 0;
  for (auto c : dt.finite_cell_handles()) c->info() = count++;
  std::vector<RawTet> raw(static_cast<size_t>(count));
  for (auto c : dt.finite_cell_handles()) {
    RawTet& t = raw[size_t(c->info())];
    for (int i = 0; i < 4; ++i) {
      t.v[size_t(i)] = c->vertex(i)->info();
      t.n[size_t(i)] = c->neighbor(i)->info();
    }
    canonicalize(t);  // CGAL's finite cells are positively oriented; even permutations keep that
  }

  // Deterministic, cache-friendly order: by the Morton code of the centroid (tets that are close in space are
  // close in memory, which keeps walks on the CPU and GPU in cache), ties by the canonical vertex tuple. Both
  // keys are pure functions of the input coordinates. Then renumber the neighbours.
  glm::dvec3 lo = points[0], hi = points[0];
  for (const glm::dvec3& p : points) {
    lo = glm::min(lo, p);
    hi = glm::max(hi, p);
  }
  std::vector<uint64_t> key(raw.size());
  for (size_t k = 0; k < raw.size(); ++k) {
    glm::dvec3 c(0.0);
    for (int32_t v : raw[k].v) c += points[size_t(v)];
    key[k] = mortonKey(0.25 * c, lo, hi);
  }
  std::vector<int32_t> order(raw.size());
  std::iota(order.begin(), order.end(), 0);
  std::sort(order.begin(), order.end(), [&](int32_t a, int32_t b) {
    const size_t ia = size_t(a), ib = size_t(b);
    return key[ia] != key[ib] ? key[ia] < key[ib] : raw[ia].v < raw[ib].v;
  });
  std::vector<int32_t> newIndex(raw.size());
  for (size_t k = 0; k < order.size(); ++k) newIndex[size_t(order[k])] = int32_t(k);

  TetMesh mesh;
  mesh.tets.resize(raw.size());
  mesh.neighbours.resize(raw.size());
  for (size_t k = 0; k < order.size(); ++k) {
    const RawTet& t = raw[size_t(order[k])];
    mesh.tets[k] = t.v;
    for (size_t i = 0; i < 4; ++i) mesh.neighbours[k][i] = t.n[i] < 0 ? -1 : newIndex[size_t(t.n[i])];
  }
  return mesh;
}

std::vector<Tet> buildTetRecords(const std::vector<glm::dvec3>& points, const TetMesh& mesh,
                                 const glm::dvec3& origin) {
  if (mesh.neighbours.size() != mesh.tets.size())
    throw std::invalid_argument("buildTetRecords: " + std::to_string(mesh.tets.size()) + " tets but " +
                                std::to_string(mesh.neighbours.size()) + " neighbour entries");
  std::vector<Tet> records(mesh.tets.size());
  for (size_t t = 0; t < mesh.tets.size(); ++t) {
    Tet& rec = records[t];
    glm::dvec3 p[4];
    for (size_t i = 0; i < 4; ++i) {
      const int32_t v = mesh.tets[t][i];
      if (v < 0 || size_t(v) >= points.size())
        throw std::invalid_argument("buildTetRecords: tet " + std::to_string(t) + " names vertex " +
                                    std::to_string(v) + " of " + std::to_string(points.size()));
      p[i] = points[size_t(v)] - origin;  // local frame, still double
      rec.v[i] = v;
      rec.n[i] = mesh.neighbours[t][i];
    }
    // glm matrices are column-major: columns P0-P3, P1-P3, P2-P3.
    const glm::dmat3 a(p[0] - p[3], p[1] - p[3], p[2] - p[3]);
    const double det = glm::determinant(a);
    const glm::dmat3 m = glm::inverse(a);
    const glm::dvec3 centroid = 0.25 * (p[0] + p[1] + p[2] + p[3]);
    bool finite = det != 0.0 && std::isfinite(det);
    for (int i = 0; i < 3; ++i) {
      // Row i of M is (m[0][i], m[1][i], m[2][i]) in glm's [column][row] indexing, rounded to float. The
      // offset -(M P3)_i equals 0.25 - M_i . centroid; it is computed from the *rounded* row so that the
      // float record gives w_i(centroid) = 0.25 up to one rounding of the offset, instead of also carrying
      // the row's rounding error times the distance from the local origin.
      for (int j = 0; j < 3; ++j) rec.row[i][j] = float(m[j][i]);
      const double offset = 0.25 - (double(rec.row[i][0]) * centroid.x + double(rec.row[i][1]) * centroid.y +
                                    double(rec.row[i][2]) * centroid.z);
      rec.row[i][3] = float(offset);
      for (int j = 0; j < 4; ++j) finite = finite && std::isfinite(rec.row[i][j]);
    }
    if (!finite)
      throw InputError("buildTetRecords: tet " + std::to_string(t) + " (probes " + std::to_string(rec.v[0]) +
                       ", " + std::to_string(rec.v[1]) + ", " + std::to_string(rec.v[2]) + ", " +
                       std::to_string(rec.v[3]) +
                       ") is too flat for float barycentric rows; move or remove one of its probes");
  }
  return records;
}

}  // namespace tetraprobe
