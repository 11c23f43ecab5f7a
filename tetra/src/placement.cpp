// Probe placement inputs: a regular grid over a box, and user probes read from a CSV file.
// (Geometry-driven placement, Valient 2014's "a probe in every empty voxel next to geometry", lives with the
// scene voxelizer; this file holds only the inputs that need no scene.)
#include "tetraprobe/tetra/placement.h"

#include <charconv>
#include <cmath>
#include <fstream>
#include <string_view>

#include "tetraprobe/common/error.h"
#include "tetraprobe/common/text.h"

namespace tetraprobe {
namespace {

bool finite(const glm::dvec3& v) {
  return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z);
}

}  // namespace

std::vector<glm::dvec3> placeGridProbes(const glm::dvec3& lo, const glm::dvec3& hi, double spacing,
                                        size_t maxProbes) {
  if (!std::isfinite(spacing) || spacing <= 0.0)
    throw InputError("probe grid: spacing " + std::to_string(spacing) + " m must be positive and finite");
  if (!finite(lo) || !finite(hi)) throw InputError("probe grid: the box corners must be finite");
  glm::ivec3 n;
  glm::dvec3 start;
  double total = 1.0;
  for (int a = 0; a < 3; ++a) {
    const double extent = hi[a] - lo[a];
    if (!(extent >= 0.0))
      throw InputError("probe grid: box max " + std::to_string(hi[a]) + " is below min " +
                       std::to_string(lo[a]) + " on axis " + std::to_string(a));
    // Points fit inside [lo, hi]; a relative 1e-9 slack keeps an exact multiple of the spacing inclusive.
    const double steps = std::floor(extent / spacing * (1.0 + 1e-9));
    total *= steps + 1.0;
    if (total > double(maxProbes))
      throw InputError("probe grid: spacing " + std::to_string(spacing) + " m over the box gives more than " +
                       std::to_string(maxProbes) + " probes");
    n[a] = int(steps) + 1;
    start[a] = lo[a] + 0.5 * (extent - steps * spacing);  // equal margins on both sides
  }
  std::vector<glm::dvec3> probes;
  probes.reserve(size_t(total));
  for (int z = 0; z < n.z; ++z)
    for (int y = 0; y < n.y; ++y)
      for (int x = 0; x < n.x; ++x) probes.emplace_back(start + glm::dvec3(x, y, z) * spacing);
  return probes;
}

std::vector<glm::dvec3> readProbeCsv(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw InputError(path + ": cannot open probe CSV");
  std::vector<glm::dvec3> probes;
  std::string line;
  for (size_t lineNo = 1; std::getline(in, line); ++lineNo) {
    const std::string_view s = trimWhitespace(line);
    if (s.empty() || s.front() == '#') continue;
    glm::dvec3 p;
    std::string_view rest = s;
    int fields = 0;
    bool ok = true;
    while (true) {
      const size_t comma = rest.find(',');
      const std::string_view field = rest.substr(0, comma);
      if (fields < 3) ok = parseFiniteField(field, p[fields]) && ok;
      ++fields;
      if (comma == std::string_view::npos) break;
      rest.remove_prefix(comma + 1);
    }
    const std::string where = path + ":" + std::to_string(lineNo) + ": ";
    if (fields != 3)
      throw InputError(where + "expected 3 comma-separated values x,y,z, found " + std::to_string(fields) +
                       ": '" + std::string(s) + "'");
    if (!ok) throw InputError(where + "expected finite numbers x,y,z (metres): '" + std::string(s) + "'");
    probes.push_back(p);
  }
  if (in.bad()) throw InputError(path + ": read failed");
  return probes;
}

}  // namespace tetraprobe
