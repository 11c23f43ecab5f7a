// The bake pipeline, stage by stage, with timings.
#include "pipeline.h"

#include <chrono>
#include <cmath>
#include <sstream>

#include <glm/common.hpp>

#include "tetraprobe/bake/sh_csv.h"
#include "tetraprobe/common/error.h"
#include "tetraprobe/runtime/outer_cells.h"
#include "tetraprobe/tetra/placement.h"
#include "tetraprobe/tetra/tetrahedralize.h"

namespace tetraprobe::cli {

namespace {

class StageTimer {
 public:
  explicit StageTimer(PipelineStats& stats) : stats_(stats) {}
  void mark(const std::string& stage) {
    const auto now = std::chrono::steady_clock::now();
    stats_.timings.emplace_back(stage, std::chrono::duration<double>(now - last_).count());
    last_ = now;
  }

 private:
  PipelineStats& stats_;
  std::chrono::steady_clock::time_point last_ = std::chrono::steady_clock::now();
};

std::string contentName(uint32_t content) {
  return content == kContentAll ? "all" : "default";
}

std::string deringName(const DeringOptions& d) {
  if (d.mode == DeringMode::kNone) return "none";
  if (d.mode == DeringMode::kAuto) return "auto";
  std::ostringstream s;
  s << d.strength;
  return s.str();
}

}  // namespace

Level buildLevel(const Scene& scene, const PipelineOptions& options, PipelineStats& stats) {
  StageTimer timer(stats);
  SceneTracer tracer(scene);
  timer.mark("bvh");

  std::vector<glm::dvec3> probes;
  ProbeShTable imported;
  if (!options.importShCsv.empty()) {
    if (!options.probesCsv.empty())
      throw InputError("give either a probe CSV or an SH CSV to import, not both");
    imported = readShCsv(options.importShCsv);
    probes = imported.positions;
    stats.importedProbes = stats.userProbes = probes.size();
  } else if (!options.probesCsv.empty()) {
    probes = readProbeCsv(options.probesCsv);
    stats.userProbes = probes.size();
  } else {
    glm::vec3 lo, hi;
    sceneBounds(scene, lo, hi);
    // Half a spacing in from the bounds, so no probe sits on the level's outer surfaces.
    const glm::dvec3 margin(options.spacing * 0.5);
    const glm::dvec3 glo = glm::dvec3(lo) + margin, ghi = glm::max(glm::dvec3(hi) - margin, glo);
    std::vector<glm::dvec3> grid = placeGridProbes(glo, ghi, options.spacing);
    stats.gridProbes = grid.size();
    const std::vector<uint8_t> inside = probesInsideGeometry(tracer, grid, 64, 0.25, options.bake.threads);
    for (size_t i = 0; i < grid.size(); ++i)
      if (!inside[i]) probes.push_back(grid[i]);
    stats.rejectedProbes = grid.size() - probes.size();
  }
  timer.mark("place");
  if (probes.size() < 4) {
    std::ostringstream msg;
    msg << "only " << probes.size() << " probe(s) left after placement (need at least 4 that are not all "
        << "coplanar); the level may be smaller than --spacing " << options.spacing
        << " m or closed with the probes outside";
    throw InputError(msg.str());
  }

  const TetMesh mesh = tetrahedralizeDelaunay(probes);
  timer.mark("tetrahedralize");

  Level level;
  level.content = options.bake.content;
  level.shOrder = uint32_t(options.bake.shOrder);
  // Local origin: the probe bounds' centre rounded to whole metres (deterministic, keeps floats small).
  glm::dvec3 plo = probes[0], phi = probes[0];
  for (const auto& p : probes) {
    plo = glm::min(plo, p);
    phi = glm::max(phi, p);
  }
  level.origin = glm::round((plo + phi) * 0.5);
  level.probes.reserve(probes.size());
  for (const auto& p : probes) level.probes.push_back(glm::vec3(p - level.origin));
  level.tets = buildTetRecords(probes, mesh, level.origin);
  level.outerCells = buildOuterCells(level.probes, level.tets);  // continuous answers outside the hull
  if (!options.importShCsv.empty()) {
    level.sh = std::move(imported.sh);
    truncateShOrder(level.sh, options.bake.shOrder);
    timer.mark("import");
  } else {
    level.sh = bakeProbes(tracer, probes, options.bake, &stats.bake);
    timer.mark("bake");
  }
  DeringOptions dering = options.dering;
  dering.threads = options.bake.threads;
  stats.dering = deringProbes(level.sh, dering);
  timer.mark("dering");

  std::ostringstream gen;
  gen << "tetraprobe 0.1.0 bake; placement="
      << (!options.importShCsv.empty() ? "imported"
          : options.probesCsv.empty()  ? "grid"
                                       : "user")
      << "; spacing=" << options.spacing << "; bounces=" << options.bake.bounces
      << "; samples=" << options.bake.samplesPerProbe << "; content=" << contentName(options.bake.content)
      << "; seed=" << options.bake.seed << "; sh_order=" << options.bake.shOrder
      << "; dering=" << deringName(options.dering);
  level.generator = gen.str();
  return level;
}

}  // namespace tetraprobe::cli
