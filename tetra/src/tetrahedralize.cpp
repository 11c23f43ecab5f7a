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

#include "mesh_internal.h"
#include "tetraprobe/common/error.h"

namespace tetraprobe {
namespace {

using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
using VertexBase = CGAL::Triangulation_vertex_base_with_info_3<int32_t, Kernel>;
using CellBase = CGAL::Triangulation_cell_base_with_info_3<int32_t, Kernel,
                                                           CGAL::Delaunay_triangulation_cell_base_3<Kernel>>;
using Tds = CGAL::Triangulation_data_structure_3<VertexBase, CellBase, CGAL::Sequential_tag>;
using Delaunay = CGAL::Delaunay_triangulation_3<Kernel, Tds>;

// The runtime reads probe positions as floats (Level::probes) and decides points near faces with weights
// computed from them (exact signed volumes, runtime/src/query.cpp). Two probes of a tet that collapse to one
// float position (near-duplicates: 1e-9 m apart at 1 m from the origin, 1 cm apart at 1000 km) make the tet
// flat there for good, and the runtime would answer it with equal weights: refused here, naming the probes.
// Tets that are flat or inverted in float without a collapse are kept: four probes coplanar in real numbers (a lattice face) are only
// off their plane by double rounding, and CGAL keeps the zero-volume tet they form; refusing it would refuse
// ordinary grids (tests/eval's probe grid has one). Such a tet holds no volume, so the walk rarely names it;
// query.h documents its answer.
void checkFloatCollapse(const glm::dvec3 (&local)[4], const Tet& rec, const std::string& name,
                        const glm::dvec3& origin) {
  glm::vec3 f[4];
  for (int i = 0; i < 4; ++i) f[i] = glm::vec3(local[i]);  // what Level::probes stores
  for (int i = 0; i < 4; ++i)
    for (int j = i + 1; j < 4; ++j)
      if (f[i] == f[j])
        throw InputError(name + " has probes " + std::to_string(rec.v[i]) + " and " +
                         std::to_string(rec.v[j]) + " at the same float position (" +
                         std::to_string(glm::length(local[i] - local[j])) +
                         " m apart) in the level frame at origin " + detail::describe(origin) +
                         "; move or remove one of them, or put the level origin nearer the probes");
}

}  // namespace

TetMesh tetrahedralizeDelaunay(const std::vector<glm::dvec3>& points) {
  detail::validatePoints(points, "tetrahedralize");

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
  std::vector<detail::RawTet> raw(static_cast<size_t>(count));
  for (auto c : dt.finite_cell_handles()) {
    detail::RawTet& t = raw[size_t(c->info())];
    for (int i = 0; i < 4; ++i) {
      t.v[size_t(i)] = c->vertex(i)->info();
      t.n[size_t(i)] = c->neighbor(i)->info();
    }
  }
  // CGAL's finite cells are positively oriented; finalizeMesh only applies even permutations.
  return detail::finalizeMesh(points, std::move(raw));
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
    // No barycentric rows are stored (level.h): the runtime computes weights from the probe positions. A
    // tet must still have a finite, non-zero volume in double for them to exist.
    const double det = glm::determinant(glm::dmat3(p[0] - p[3], p[1] - p[3], p[2] - p[3]));
    const bool finite = det != 0.0 && std::isfinite(det);
    const std::string name = "buildTetRecords: tet " + std::to_string(t) + " (probes " +
                             std::to_string(rec.v[0]) + ", " + std::to_string(rec.v[1]) + ", " +
                             std::to_string(rec.v[2]) + ", " + std::to_string(rec.v[3]) + ")";
    if (!finite) throw InputError(name + " is flat (zero volume); move or remove one of its probes");
    checkFloatCollapse(p, rec, name, origin);
  }
  return records;
}

}  // namespace tetraprobe
