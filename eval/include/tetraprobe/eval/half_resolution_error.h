// How far the half-resolution lookup (shaders/tetraprobe_upsample.glsl, RenderOptions::halfResolution) lands
// from the full-resolution lookup on the same G-buffer: `tetraprobe bench render` and `tetraprobe eval`
// report it beside the passes' times. Build side (images only).
//
// Per geometry pixel (full.a != 0), with Y = Rec. 709 luminance:
//   d = |Y(half) - Y(full)| / max(Y(full), floor),  floor = max(0.05 x mean Y(full), 0.01 W/m^2)
// (the floor keeps near-black pixels, where a tiny absolute difference is a large ratio, from deciding the
// figures; 5 % of the mean as eval's relative errors use, 0.01 W/m^2 as its absolute floor).
#pragma once

#include <cstddef>

#include "tetraprobe/render/render.h"

namespace tetraprobe {

struct HalfResolutionError {
  size_t pixels = 0;          // geometry pixels scored
  double floor = 0.0;         // the luminance floor used, in the images' unit
  double interpolated = 0.0;  // share of pixels interpolated from half-resolution samples (half.a == 1)
  double copied = 0.0;        // share that are their block's own lookup (half.a == 2; exact)
  double fullLookup = 0.0;    // share looked up at full resolution (half.a == 3; exact)
  double meanRel = 0.0, p95Rel = 0.0, p99Rel = 0.0, maxRel = 0.0;  // of d over the pixels
  double over5 = 0.0, over25 = 0.0;                                // share with d > 0.05, d > 0.25
};

// The figures above. `full` is RenderResult::color, `half` RenderResult::halfResolution of the same render;
// throws std::invalid_argument when their sizes differ. No geometry: every figure 0.
HalfResolutionError halfResolutionError(const Image& full, const Image& half);

}  // namespace tetraprobe
