// `tetraprobe query LEVEL.tpb X Y Z [NX NY NZ]` and `--points FILE.csv`: irradiance from the CPU runtime.
#include <cmath>
#include <cstdio>
#include <fstream>
#include <limits>
#include <memory>
#include <sstream>

#include <glm/geometric.hpp>

#include "args.h"
#include "commands.h"
#include "tetraprobe/bake/tracer.h"
#include "tetraprobe/common/error.h"
#include "tetraprobe/runtime/luminance.h"
#include "tetraprobe/runtime/query.h"
#include "tetraprobe/runtime/shade.h"
#include "tetraprobe/scene/load.h"

namespace tetraprobe::cli {

namespace {

glm::vec3 normalOrThrow(glm::vec3 n, const std::string& where) {
  const float len = glm::length(n);
  if (!(len > 0.0f) || !std::isfinite(len))
    throw InputError(where + ": normal must be a non-zero finite vector");
  return n / len;
}

const char* occlusionKindText(const Level& level, int32_t tet) {
  if (level.occlusion.empty()) return "none stored in the level";
  switch (level.occlusion.tets[size_t(tet)].kind()) {
    case kOcclusionPlanes:
      return "planes";
    case kOcclusionShadowMaps:
      return "shadow maps";
    default:
      return "none (no geometry cuts this tet)";
  }
}

// What the answer is made of, in the runtime's own terms (ShadeRecord, from ProbeQuery::explain): the tet,
// its probes, the occlusion data's visibility and the fallback share. Printed after the r,g,b line so scripts
// can read line 1. With a tracer, also what rays from the point (moved off the surface along n by the
// tracer's epsilon) to each probe say (where the data and the rays disagree, the occlusion data is the
// culprit), and which side of the first surface along n the point faces (from behind: it may lie inside solid
// geometry).
void explain(const ProbeQuery& query, const glm::dvec3& world, const glm::vec3& n,
             const SceneTracer* tracer) {
  const Level& level = query.level();
  ShadeRecord record;
  query.explain(world, n, record);
  const Location& loc = record.location;
  if (loc.tet < 0) {
    std::printf("explain: the level has no tets\n");
    return;
  }
  const Tet& t = level.tets[size_t(loc.tet)];
  if (loc.outerCell >= 0)
    std::printf("explain: outside the hull, outer cell %d of hull tet %d (weights on its hull face)\n",
                loc.outerCell, loc.tet);
  else
    std::printf("explain: inside tet %d\n", loc.tet);
  std::printf("  occlusion: %s\n", occlusionKindText(level, loc.tet));
  // What the answer uses: the tet's data blended with the tets' around the point (face_blend.h).
  const glm::vec4 own = record.ownVisibility, vis = record.visibility;
  if (vis != own)
    std::printf(
        "  face blend: the visibility below is blended with the tets' around the point that hold each probe "
        "(the tet's data alone: %.3f %.3f %.3f %.3f)\n",
        own.x, own.y, own.z, own.w);
  const float fallback = record.fallback;
  // The rays column only with a tracer, so the rows read the same as before without one.
  std::printf("  %-8s %-36s %9s %8s %10s %9s %s%s\n", "probe", "position (world, m)", "distance", "weight",
              "visibility", "after occ", tracer ? " rays " : "", " E(n) r,g,b W/m^2");
  FlushDenormalsScope ftz;  // for the tracer's rays
  const glm::vec3 origin = glm::vec3(world) + n * (tracer ? tracer->rayEpsilon() : 0.0f);
  for (int i = 0; i < 4; ++i) {
    const int32_t p = t.v[i];
    const glm::dvec3 pw = level.origin + glm::dvec3(level.probes[size_t(p)]);
    const glm::vec3 ep = record.probeIrradiance[i];
    char pos[64];
    std::snprintf(pos, sizeof pos, "%.3f, %.3f, %.3f", pw.x, pw.y, pw.z);
    const char* rays = "";
    if (tracer) {
      const glm::vec3 d = glm::vec3(pw) - origin;
      const float len = glm::length(d);
      rays = glm::dot(d, n) < 0.0f                                              ? " back "
             : len > 0.0f && tracer->occluded(origin, d / len, 0.0f, len, 0.0f) ? "  hit "
                                                                                : " clear";
    }
    std::printf("  %-8d %-36s %9.3f %8.4f %10.3f %9.4f%s  %.4g, %.4g, %.4g\n", p, pos,
                glm::length(pw - world), loc.weights[i], vis[i], record.weights[i], rays, ep.r, ep.g, ep.b);
  }
  if (fallback > 0.0f)
    std::printf(
        "  fallback share %.3f: the data says the point sees %s of its probes; the answer blends toward the "
        "nearest probe in front of the surface, capped by the unoccluded blend (docs/occlusion.md)\n",
        fallback, fallback >= 1.0f ? "none" : "little");
  if (tracer) {
    const Hit h = tracer->intersect(origin, n, 0.0f, std::numeric_limits<float>::infinity());
    if (!h.hit)
      std::printf("  along the normal: open (no surface)\n");
    else
      std::printf("  along the normal: a surface %.3f m away, met from its %s\n", h.t,
                  h.frontFace ? "front (the point is in open space)"
                              : "back (the point may be inside solid geometry)");
  }
  const glm::vec3 answer = record.answer;
  std::printf("  answer %.4g, %.4g, %.4g W/m^2 (luminance %.4g)\n", answer.r, answer.g, answer.b,
              luminance(glm::dvec3(answer)));
}

}  // namespace

int cmdQuery(int argc, char** argv) {
  Args args(
      "tetraprobe query LEVEL.tpb X Y Z [NX NY NZ] | tetraprobe query LEVEL.tpb --points FILE.csv",
      "Prints irradiance E (W/m^2, r,g,b) from the probes at world positions with surface normals\n"
      "(default normal 0,1,0). With --points, reads lines x,y,z,nx,ny,nz and prints one r,g,b line each.",
      {{"--points", "", "FILE.csv", "query every line of this file", ""},
       {"--threads", "", "N", "worker threads for --points, 0 = all cores", "0"},
       {"--explain", "", "",
        "single point: also print why (its tet, each probe's position, distance, weight, visibility from the "
        "occlusion data and irradiance, the fallback share): where a spot is too dark or too bright",
        ""},
       {"--scene", "", "SCENE",
        "with --explain: also trace rays from the point to each probe in this scene (column rays: clear, hit "
        "by an opaque surface, or back = behind the surface) to check the occlusion data, and along the "
        "normal "
        "(a surface met from behind: the point may be inside solid geometry)",
        ""}});
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
  const glm::dvec3 world(v[0], v[1], v[2]);
  const glm::vec3 e = query.irradiance(world, n);
  std::printf("%.9g,%.9g,%.9g\n", e.x, e.y, e.z);
  if (args.has("--explain")) {
    std::unique_ptr<Scene> scene;
    std::unique_ptr<SceneTracer> tracer;
    if (args.has("--scene")) {
      scene = std::make_unique<Scene>(loadScene(args.str("--scene")));
      tracer = std::make_unique<SceneTracer>(*scene);
    }
    explain(query, world, n, tracer.get());
  }
  return 0;
}

}  // namespace tetraprobe::cli
