// TetGen 1.5 backend (Si 2015, "TetGen, a Delaunay-based quality tetrahedral mesh generator", ACM TOMS):
// Delaunay tetrahedralization of the probes, and optionally TetGen's quality refinement of that mesh, whose
// Steiner points become filler probes. TetGen's `q` applied to a bare point set silently returns an empty
// mesh, so refinement reads the stage-1 tets back in with `r`. TETLIBRARY is defined (TetGen::TetGen), so
// TetGen reports errors by throwing an int instead of calling exit(); they become InputError here.
//
// The output goes through the same canonical extraction as the CGAL backend (mesh_internal.h). TetGen's
// orientation convention is checked per tet with its exact orient3d (Shewchuk's sign: positive when the
// fourth point is below the first three, i.e. the opposite of ours) and fixed by an odd swap. Refinement
// uses `Y` (keep the hull faces unsplit): a Steiner point TetGen computes on a planar hull face is rounded
// off it and would leave a nearly flat tet on the hull.
//
// This is the only translation unit that includes tetgen.h.
#include <tetgen.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include <glm/common.hpp>

#include "mesh_internal.h"
#include "tetraprobe/common/error.h"
#include "tetraprobe/tetra/tetrahedralize.h"

namespace tetraprobe {
namespace {

const char* kWho = "tetrahedralize (tetgen)";

std::string tetgenError(int code) {
  switch (code) {
    case 1:
      return "out of memory";
    case 2:
      return "internal error (TetGen bug)";
    case 3:
      return "self-intersecting input";
    case 4:
      return "a very small input feature size";
    case 5:
      return "two very close input facets";
    case 10:
      return "an input error";
    default:
      return "error code " + std::to_string(code);
  }
}

void run(const std::string& switches, tetgenio& in, tetgenio& out) {
  std::vector<char> sw(switches.begin(), switches.end());
  sw.push_back('\0');
  try {
    tetrahedralize(sw.data(), &in, &out);
  } catch (int code) {
    throw InputError(std::string(kWho) + ": TetGen failed (" + tetgenError(code) + ") with switches '" +
                     switches + "'");
  }
}

// Exact dimension check with TetGen's orient3d (after exactinit): throws the same InputError as the CGAL
// backend for collinear or coplanar input.
void checkDimension(const std::vector<glm::dvec3>& points) {
  // No static filter (the extents only feed it, and TetGen asserts they are positive): exact for any input.
  exactinit(0, 0, 1, 1.0, 1.0, 1.0);
  auto o3 = [](glm::dvec3 a, glm::dvec3 b, glm::dvec3 c, glm::dvec3 d) {
    return orient3d(&a.x, &b.x, &c.x, &d.x);
  };
  const glm::dvec3 p0 = points[0];
  size_t i1 = 1;  // distinct (duplicates were rejected)
  // p is off the line p0 p1 iff orient3d(p0, p1, p, q) != 0 for one of three probes q = p0 + d e_k (q - p0
  // is exactly a positive multiple of e_k, so the three tests span every normal direction).
  std::array<glm::dvec3, 3> q;
  for (int k = 0; k < 3; ++k) {
    q[size_t(k)] = p0;
    q[size_t(k)][k] += std::max(1.0, 2.0 * std::abs(p0[k]));
  }
  size_t i2 = 0;
  for (size_t i = 2; i < points.size() && !i2; ++i)
    for (const auto& qk : q)
      if (o3(p0, points[i1], points[i], qk) != 0.0) {
        i2 = i;
        break;
      }
  if (!i2)
    throw InputError(std::string(kWho) + ": all " + std::to_string(points.size()) +
                     " probes are collinear; a volume needs probes off that line");
  for (size_t i = 2; i < points.size(); ++i)
    if (o3(p0, points[i1], points[i2], points[i]) != 0.0) return;
  throw InputError(std::string(kWho) + ": all " + std::to_string(points.size()) +
                   " probes are coplanar; a volume needs probes off that plane");
}

void loadPoints(tetgenio& io, const double* xyz, int count) {
  io.firstnumber = 0;
  io.numberofpoints = count;
  io.pointlist = new REAL[size_t(count) * 3];
  std::copy(xyz, xyz + size_t(count) * 3, io.pointlist);
}

}  // namespace

TetGenResult tetrahedralizeTetGen(const std::vector<glm::dvec3>& points, const TetGenOptions& options) {
  detail::validatePoints(points, kWho);
  checkDimension(points);
  const int n = int(points.size());

  tetgenio in, stage1;
  std::vector<double> xyz(points.size() * 3);
  for (size_t i = 0; i < points.size(); ++i)
    for (int k = 0; k < 3; ++k) xyz[3 * i + size_t(k)] = points[i][k];
  loadPoints(in, xyz.data(), n);
  run("Qnz", in, stage1);  // quiet, neighbours, zero-based

  tetgenio refined;
  tetgenio* mesh = &stage1;
  if (options.refine) {
    tetgenio again;
    loadPoints(again, stage1.pointlist, stage1.numberofpoints);
    again.numberofcorners = 4;
    again.numberoftetrahedra = stage1.numberoftetrahedra;
    again.tetrahedronlist = new int[size_t(stage1.numberoftetrahedra) * 4];
    std::copy(stage1.tetrahedronlist, stage1.tetrahedronlist + size_t(stage1.numberoftetrahedra) * 4,
              again.tetrahedronlist);
    char sw[128];
    std::snprintf(sw, sizeof(sw), "rYq%.17g/%.17gQnz", options.radiusEdge, options.minDihedralDeg);
    std::string switches = sw;
    if (options.maxSteiner >= 0) switches += "S" + std::to_string(options.maxSteiner);
    run(switches, again, refined);
    mesh = &refined;
  }

  TetGenResult result;
  const int total = mesh->numberofpoints;
  if (total < n || mesh->numberoftetrahedra <= 0)
    throw std::logic_error(std::string(kWho) + ": TetGen returned " + std::to_string(total) + " points and " +
                           std::to_string(mesh->numberoftetrahedra) + " tets for " + std::to_string(n) +
                           " probes");
  for (int i = 0; i < n; ++i)
    for (int k = 0; k < 3; ++k)
      if (mesh->pointlist[3 * i + k] != points[size_t(i)][k])
        throw std::logic_error(std::string(kWho) + ": TetGen moved or reordered probe " + std::to_string(i));
  std::vector<glm::dvec3> all = points;
  for (int i = n; i < total; ++i) {
    const glm::dvec3 p(mesh->pointlist[3 * i], mesh->pointlist[3 * i + 1], mesh->pointlist[3 * i + 2]);
    result.steiner.push_back(p);
    all.push_back(p);
  }

  const size_t tets = size_t(mesh->numberoftetrahedra);
  std::vector<detail::RawTet> raw(tets);
  for (size_t t = 0; t < tets; ++t) {
    detail::RawTet& r = raw[t];
    for (size_t i = 0; i < 4; ++i) {
      r.v[i] = mesh->tetrahedronlist[4 * t + i];
      const int nb = mesh->neighborlist[4 * t + i];
      r.n[i] = nb >= 0 && size_t(nb) < tets ? nb : -1;
      if (r.v[i] < 0 || r.v[i] >= total)
        throw std::logic_error(std::string(kWho) + ": TetGen tet names vertex " + std::to_string(r.v[i]));
    }
    glm::dvec3 p[4];
    for (size_t i = 0; i < 4; ++i) p[i] = all[size_t(r.v[i])];
    const double o = orient3d(&p[0].x, &p[1].x, &p[2].x, &p[3].x);
    if (o == 0.0) throw std::logic_error(std::string(kWho) + ": TetGen returned a flat tet");
    if (o > 0.0) {  // Shewchuk-positive = our negative: an odd swap fixes it
      std::swap(r.v[0], r.v[1]);
      std::swap(r.n[0], r.n[1]);
    }
  }
  result.mesh = detail::finalizeMesh(all, std::move(raw));
  return result;
}

}  // namespace tetraprobe
