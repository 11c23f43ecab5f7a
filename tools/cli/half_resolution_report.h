// The half-resolution lookup's figures as `bench render` and `eval` report them (one source for both): the
// three passes' times from a render made with RenderOptions::halfResolution and its difference from the
// full-resolution lighting pass of the same render (eval/half_resolution_error.h).
#pragma once

#include <nlohmann/json.hpp>

#include "tetraprobe/render/render.h"

namespace tetraprobe::cli {

// JSON: lookup_half_ms, upsample_ms, lookup_edges_ms, total_ms, ratio_to_full (total / fullMs),
// ratio_to_grid (total / gridMs; only when gridMs > 0), pixel shares, error_vs_full {...}.
nlohmann::json halfResolutionJson(const RenderResult& r, double fullMs, double gridMs);

// Two indented lines under a heading: times and ratios, then pixel shares and the difference from full.
void printHalfResolution(const RenderResult& r, double fullMs, double gridMs);

}  // namespace tetraprobe::cli
