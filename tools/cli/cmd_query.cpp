// `tetraprobe query LEVEL.tpb X Y Z [NX NY NZ]` and `--points FILE.csv`: irradiance from the CPU runtime.
#include <cmath>
#include <cstdio>
#include <fstream>
#include <sstream>

#include <glm/geometric.hpp>

#include "args.h"
#include "commands.h"
#include "tetraprobe/common/error.h"
#include "tetraprobe/runtime/query.h"

namespace tetraprobe::cli {

namespace {

glm::vec3 normalOrThrow(glm::vec3 n, const std::string& where) {
  const float len = glm::length(n);
  if (!(len > 0.0f) || !std::isfinite(len))
    throw InputError(where + ": normal must be a non-zero finite vector");
  return n / len;
}

}  // namespace

int cmdQuery(int argc, char** argv) {
  Args args(
      "tetraprobe query LEVEL.tpb X Y Z [NX NY NZ] | tetraprobe query LEVEL.tpb --points FILE.csv",
      "Prints irradiance E (W/m^2, r,g,b) from the probes at world positions with surface normals\n"
      "(default normal 0,1,0). With --points, reads lines x,y,z,nx,ny,nz and prints one r,g,b line each.",
      {{"--points", "", "FILE.csv", "query every line of this file", ""},
       {"--threads", "", "N", "worker threads for --points, 0 = all cores", "0"}});
  if (!args.parse(argc, argv)) return 0;
  if (args.positional().empty()) throw UsageError("missing LEVEL.tpb");
  Level level;
  if (const LevelResult r = loadLevel(args.positional()[0], level); !r) throw InputError(r.message);
  const ProbeQuery query(level);

  if (args.has("--points")) {
    args.requirePositional(1, 1);
    const std::string file = args.str("--points");
    std::ifstream in(file);
    if (!in) throw InputError(file + ": cannot open");
    std::vector<glm::dvec3> pos;
    std::vector<glm::vec3> nrm;
    std::string line;
    for (int lineNo = 1; std::getline(in, line); ++lineNo) {
      if (line.empty() || line[0] == '#') continue;
      std::stringstream ss(line);
      std::string cell;
      double v[6];
      int k = 0;
      const std::string where = file + ":" + std::to_string(lineNo);
      while (std::getline(ss, cell, ',')) {
        if (k >= 6) throw InputError(where + ": expected x,y,z,nx,ny,nz");
        try {
          v[k++] = parseNumber(cell, "value");
        } catch (const UsageError& e) {
          throw InputError(where + ": " + e.what());
        }
      }
      if (k != 6) throw InputError(where + ": expected x,y,z,nx,ny,nz (6 numbers), got " + std::to_string(k));
      pos.emplace_back(v[0], v[1], v[2]);
      nrm.push_back(normalOrThrow(glm::vec3(float(v[3]), float(v[4]), float(v[5])), where));
    }
    std::vector<glm::vec3> out(pos.size());
    query.irradianceBatch(pos.data(), nrm.data(), out.data(), pos.size(), args.integer("--threads"));
    for (const auto& e : out) std::printf("%.9g,%.9g,%.9g\n", e.x, e.y, e.z);
    return 0;
  }

  args.requirePositional(4, 7);
  if (args.positional().size() != 4 && args.positional().size() != 7)
    throw UsageError("give X Y Z, or X Y Z NX NY NZ");
  double v[6] = {0, 0, 0, 0, 1, 0};
  for (size_t i = 1; i < args.positional().size(); ++i)
    v[i - 1] = parseNumber(args.positional()[i], "coordinate");
  const glm::vec3 n = normalOrThrow(glm::vec3(float(v[3]), float(v[4]), float(v[5])), "normal");
  const glm::vec3 e = query.irradiance(glm::dvec3(v[0], v[1], v[2]), n);
  std::printf("%.9g,%.9g,%.9g\n", e.x, e.y, e.z);
  return 0;
}

}  // namespace tetraprobe::cli
