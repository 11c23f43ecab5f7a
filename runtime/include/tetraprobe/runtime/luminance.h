// Rec. 709 luminance: the one definition of "how bright" a linear RGB value is, for every module (the
// bake's noise estimates and emitter sampling, eval's errors, refinement, tone mapping, the tools, the
// samples). Header-only; permissive: GLM only.
#pragma once

#include <glm/vec3.hpp>

namespace tetraprobe {

// Y = 0.2126 R + 0.7152 G + 0.0722 B (ITU-R BT.709 primaries, linear RGB), in the units of the input
// (W/m^2 for irradiance), evaluated left to right in the precision of the argument: float for glm::vec3,
// double for glm::dvec3. A float colour wanted in double is passed as glm::dvec3(c) (an exact conversion).
inline float luminance(const glm::vec3& c) {
  return 0.2126f * c.r + 0.7152f * c.g + 0.0722f * c.b;
}

inline double luminance(const glm::dvec3& c) {
  return 0.2126 * c.r + 0.7152 * c.g + 0.0722 * c.b;
}

}  // namespace tetraprobe
