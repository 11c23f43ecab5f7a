// The half-resolution lookup's figures as `bench render` and `eval` report them (one source for both): the
// three passes' times from a render made with RenderOptions::halfResolution and its difference from the
// full-resolution lighting pass of the same render (eval/half_resolution_error.h).
#pragma once

#include <nlohmann/json.hpp>

#include "tetraprobe/eval/half_resolution_error.h"
#include "tetraprobe/render/render.h"

namespace tetraprobe::cli {

struct HalfResolutionReport {
  double halfMs = 0, upsampleMs = 0, edgesMs = 0, totalMs = 0;  // the passes, and their sum
  double fullMs = 0, gridMs = 0;  // what the total is compared with (gridMs 0: no grid)
  HalfResolutionError error;
};

// The figures of render `r`, against the full lookup's `fullMs` and the grid's `gridMs` (0: none).
HalfResolutionReport halfResolutionReport(const RenderResult& r, double fullMs, double gridMs);

// JSON: lookup_half_ms, upsample_ms, lookup_edges_ms, total_ms, ratio_to_full, ratio_to_grid (only with a
// grid), pixel shares, error_vs_full {...}.
nlohmann::json halfResolutionJson(const HalfResolutionReport& report);

// Two indented lines: times and ratios, then pixel shares and the difference from full.
void printHalfResolution(const HalfResolutionReport& report);

}  // namespace tetraprobe::cli
