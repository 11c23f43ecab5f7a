// Per-pixel error of the probe lookup against the path-traced reference, as a signed log2 ratio of
// luminances, a heat map with a fixed scale, and the fractions of grossly wrong pixels
// (`tetraprobe render --mode error`). Build side (no Embree in here; the inputs come from reference_image.h).
//
// Per hit pixel, with Y = Rec. 709 luminance of irradiance in W/m^2 and the evaluation's 0.01 W/m^2 floor
// (evaluate.h) so pixels black in both count as right:
//   e = log2( max(Y(lookup), 0.01) / max(Y(reference), 0.01) )
// e = +1: the probes are twice too bright; e = -1: half as bright as they should be.
// Heat map: e clamped to [-2, +2] (4x either way) through ColorBrewer's diverging RdBu scheme (11 classes,
// interpolated): dark blue at -2 (too dark), near-white #f7f7f7 at 0 (right), dark red at +2 (too bright).
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include <glm/vec3.hpp>

#include "tetraprobe/eval/reference_image.h"
#include "tetraprobe/render/render.h"

namespace tetraprobe {

inline constexpr double kErrorFloor = 0.01;      // W/m^2 (evaluate.h's floor)
inline constexpr double kErrorScaleStops = 2.0;  // the heat map spans e in [-2, +2]
inline constexpr double kGrossStops = 1.0;       // gross: |e| > 1, off by more than 2x either way
inline constexpr double kDarkHoleStops = -2.0;   // dark hole: e < -2, below a quarter of the reference

// e for one pixel (see above). Non-finite or negative luminances count as 0 (hence as the floor).
float signedLog2Error(const glm::vec3& lookup, const glm::vec3& reference);

struct ErrorStats {
  size_t pixels = 0;         // hit pixels scored
  double gross = 0.0;        // fraction of them with |e| > kGrossStops
  double darkHoles = 0.0;    // fraction with e < kDarkHoleStops
  double tooBright = 0.0;    // fraction with e > kGrossStops (part of gross)
  double tooDark = 0.0;      // fraction with e < -kGrossStops (part of gross; includes the dark holes)
  double meanLog2 = 0.0;     // mean e: the overall bias in stops
  double meanAbsLog2 = 0.0;  // mean |e|
};

struct ErrorImage {
  int width = 0, height = 0;
  std::vector<uint8_t> hit;      // the G-buffer's: 1 where scored
  std::vector<float> log2Ratio;  // e per pixel, unclamped; 0 for background
  ErrorStats stats;
};

// e at every hit pixel of `gbuffer`, and the statistics over them. `lookup` and `reference` hold one value
// per pixel (probeLookupImage, ReferenceImage::irradiance); throws std::invalid_argument when their sizes
// differ from the G-buffer's.
ErrorImage computeErrorImage(const ReferenceGBuffer& gbuffer, const std::vector<glm::vec3>& lookup,
                             const std::vector<glm::vec3>& reference);

// The heat map's colour for e (clamped to +-kErrorScaleStops), linear RGB in [0, 1] (write it with
// writePngLinear to get the scheme's sRGB values back).
glm::vec3 errorColor(float log2Ratio);

// RGBA image of the heat map: rgb = errorColor(e), a = 1 on hit pixels; background pixels all 0 (black).
Image errorHeatMap(const ErrorImage& error);

// RGBA float image of the values: rgb = e (unclamped, the same in all three), a = 1 on hit pixels;
// background pixels all 0. For .exr output.
Image errorValues(const ErrorImage& error);

}  // namespace tetraprobe
