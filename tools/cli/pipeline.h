// The bake pipeline: scene -> probe placement -> SH bake -> tetrahedralization -> Level. Shared by
// `tetraprobe bake` and the end-to-end tests.
#pragma once

#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "tetraprobe/bake/bake.h"
#include "tetraprobe/runtime/level.h"
#include "tetraprobe/scene/scene.h"

namespace tetraprobe::cli {

struct PipelineOptions {
  double spacing = 1.0;     // grid spacing, metres
  std::string probesCsv;    // user probes instead of the grid (kept exactly)
  std::string importShCsv;  // probes and their SH from another baker (bake/sh_csv.h); no path tracing
  BakeOptions bake;         // bake.shOrder 1 also truncates imported SH
  DeringOptions dering;     // applied to baked and imported SH alike
};

struct PipelineStats {
  size_t gridProbes = 0;      // placed by the grid before rejection
  size_t rejectedProbes = 0;  // inside geometry
  size_t userProbes = 0;
  size_t importedProbes = 0;  // --import-sh
  BakeStats bake;             // rays and time of the path tracer (zero when the SH were imported)
  DeringStats dering;
  std::vector<std::pair<std::string, double>> timings;  // stage -> seconds, in order
};

// Runs every stage on a loaded scene. Throws InputError when the input cannot give a level (e.g. fewer than
// four probes survive placement).
Level buildLevel(const Scene& scene, const PipelineOptions& options, PipelineStats& stats);

}  // namespace tetraprobe::cli
