// SH in half precision, as the level file (section SHRH) and the GPU probe buffer store it: 27 IEEE 754
// binary16 coefficients (coefficient-major, then r, g, b, as ShRgb) and one binary16 power of two scaling
// them all, 56 bytes a probe instead of ShRgb's 108. The value of coefficient j is half(h[j]) * half(h[27]),
// exact in float (a half times a power of two), so the CPU (decodeShHalf) and the GPU (unpackHalf2x16 times
// the scale) read the same floats bit for bit.
//
// Precision: each coefficient keeps 11 significant bits of its own magnitude (relative error <= 2^-11 after
// round-to-nearest-even, 4.9e-4), down to 2^-29 of the probe's largest coefficient (below that the half is
// subnormal: an absolute error <= 2^-39 of the probe's largest coefficient). The scale is chosen per probe from its largest
// |coefficient| m, so a probe lit by a megawatt source and one in the dark keep the same relative precision;
// m up to kShHalfMaxMagnitude (about 2.1e9 W/(m^2 sr)) is representable. Permissive: standard library only.
#pragma once

#include <cstdint>

#include "tetraprobe/runtime/sh.h"

namespace tetraprobe {

struct ShHalf {
  uint16_t h[28];  // [0, 27): coefficients (ShRgb order); [27]: the scale, a power of two in [2^-24, 2^15]
};
static_assert(sizeof(ShHalf) == 56, "ShHalf is 28 binary16 values (14 uints on the GPU)");

// The largest |coefficient| an ShHalf holds: the largest finite half times the largest scale 2^15.
inline constexpr double kShHalfMaxMagnitude = 65504.0 * 32768.0;

// IEEE 754 binary16 from float, round to nearest even; overflow -> infinity, NaN -> a quiet NaN. Exact for
// every float that is a half.
uint16_t floatToHalf(float x);
// The float a binary16 holds (exact: every half is a float).
float halfToFloat(uint16_t h);

// Encodes `sh`; false (out untouched) when a coefficient is not finite or |coefficient| > kShHalfMaxMagnitude.
// All-zero SH encode with scale 1. Deterministic (a pure function of the bits of `sh`).
bool encodeShHalf(const ShRgb& sh, ShHalf* out);

// The floats an ShHalf holds. `valid` (optional) is set false when a value is not finite or the scale is not
// a positive power of two in [2^-24, 2^15] (a corrupt record); the result is then unspecified but finite.
ShRgb decodeShHalf(const ShHalf& sh, bool* valid = nullptr);

// decodeShHalf(encodeShHalf(sh)): the SH as a level stores them. Idempotent in value
// (quantizeSh(quantizeSh(x)) == quantizeSh(x)). Precondition: encodable (else returns sh unchanged).
ShRgb quantizeSh(const ShRgb& sh);

}  // namespace tetraprobe
