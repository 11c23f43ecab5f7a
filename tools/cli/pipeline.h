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
  double spacing = 1.0;   // grid spacing, metres
  std::string probesCsv;  // user probes instead of the grid (kept exactly)
  BakeOptions bake;
};

struct PipelineStats {
  size_t gridProbes = 0;      // placed by the grid before rejection
  size_t rejectedProbes = 0;  // inside geometry
  size_t userProbes = 0;
  std::vector<std::pair<std::string, double>> timings;  // stage -> seconds, in order
};

// Runs every stage on a loaded scene. Throws InputError when the input cannot give a level (e.g. fewer than
// four probes survive placement).
Level buildLevel(const Scene& scene, const PipelineOptions& options, PipelineStats& stats);

}  // namespace tetraprobe::cli
