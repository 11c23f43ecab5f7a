// Half-precision SH records (sh_half.h): binary16 conversion by bit manipulation (no F16C: the runtime is
// built for baseline x86-64 and other targets) and the per-probe power-of-two scale.
#include "tetraprobe/runtime/sh_half.h"

#include <cmath>
#include <cstring>

namespace tetraprobe {

namespace {

uint32_t bitsOf(float x) {
  uint32_t u;
  std::memcpy(&u, &x, 4);
  return u;
}

float floatOf(uint32_t u) {
  float x;
  std::memcpy(&x, &u, 4);
  return x;
}

// The exponent k of the scale 2^k for largest magnitude m > 0: m / 2^k in [2^14, 2^15) before rounding,
// raised by one when the largest coefficient would round up to 2^15 (so that re-encoding a decoded record
// finds the same k); clamped to [-24, 15].
int scaleExponent(float m) {
  int e = 0;
  std::frexp(m, &e);  // m = f 2^e, f in [0.5, 1)
  int k = e - 15;
  if (k < -24) k = -24;
  if (k > 15) k = 15;
  if (k < 15 && halfToFloat(floatToHalf(std::ldexp(m, -k))) >= 32768.0f) ++k;
  return k;
}

}  // namespace

uint16_t floatToHalf(float x) {
  const uint32_t u = bitsOf(x);
  const uint16_t sign = uint16_t((u >> 16) & 0x8000u);
  const uint32_t abs = u & 0x7fffffffu;
  if (abs >= 0x7f800000u) return uint16_t(sign | (abs > 0x7f800000u ? 0x7e00u : 0x7c00u));  // NaN / inf
  if (abs >= 0x477ff000u) return uint16_t(sign | 0x7c00u);  // rounds to >= 65520: overflow to infinity
  if (abs < 0x38800000u) {
    // Result is subnormal (or zero): value = abs * 2^24 in units of 2^-24, rounded to nearest even.
    if (abs < 0x33000000u) return sign;  // below half of the smallest subnormal (2^-25): zero
    const uint32_t mant = (abs & 0x7fffffu) | 0x800000u;
    const int shift = 126 - int(abs >> 23);  // 14..24 for exponents 102..112
    const uint32_t q = mant >> shift, rem = mant & ((1u << shift) - 1u), half = 1u << (shift - 1);
    const uint32_t r = q + ((rem > half || (rem == half && (q & 1u))) ? 1u : 0u);
    return uint16_t(sign | r);
  }
  // Normal: rebias the exponent (127 -> 15), round the 23-bit mantissa to 10 bits, nearest even; a carry
  // into the exponent is the right result.
  const uint32_t r = abs - 0x38000000u;  // exponent rebiased by 112
  const uint32_t q = r >> 13, rem = r & 0x1fffu;
  return uint16_t(sign | (q + ((rem > 0x1000u || (rem == 0x1000u && (q & 1u))) ? 1u : 0u)));
}

float halfToFloat(uint16_t h) {
  const uint32_t sign = uint32_t(h & 0x8000u) << 16, exp = (h >> 10) & 0x1fu, mant = h & 0x3ffu;
  if (exp == 0x1f) return floatOf(sign | 0x7f800000u | (mant << 13));  // inf / NaN
  if (exp == 0) {
    const float v = std::ldexp(float(mant), -24);  // subnormal or zero: exact
    return sign ? -v : v;
  }
  return floatOf(sign | ((exp + 112u) << 23) | (mant << 13));
}

bool encodeShHalf(const ShRgb& sh, ShHalf* out) {
  float m = 0.0f;
  for (const glm::vec3& c : sh.c)
    for (int ch = 0; ch < 3; ++ch) {
      if (!std::isfinite(c[ch])) return false;
      m = std::fmax(m, std::fabs(c[ch]));
    }
  if (double(m) > kShHalfMaxMagnitude) return false;
  const int k = m > 0.0f ? scaleExponent(m) : 0;
  ShHalf r;
  for (int i = 0; i < kShCoeffCount; ++i)
    for (int ch = 0; ch < 3; ++ch) r.h[3 * i + ch] = floatToHalf(std::ldexp(sh.c[size_t(i)][ch], -k));
  r.h[27] = floatToHalf(std::ldexp(1.0f, k));
  *out = r;
  return true;
}

ShRgb decodeShHalf(const ShHalf& sh, bool* valid) {
  const uint16_t s = sh.h[27];
  // A positive power of two: a normal half with zero mantissa (2^-14..2^15) or a subnormal with one bit.
  const bool scaleOk = (s & 0x8000u) == 0 && s != 0 &&
                       ((((s >> 10) & 0x1fu) != 0 && ((s >> 10) & 0x1fu) != 0x1f && (s & 0x3ffu) == 0) ||
                        (((s >> 10) & 0x1fu) == 0 && (s & (s - 1u)) == 0));
  bool ok = scaleOk;
  const float scale = scaleOk ? halfToFloat(s) : 0.0f;
  ShRgb out;
  for (int i = 0; i < kShCoeffCount; ++i)
    for (int ch = 0; ch < 3; ++ch) {
      const uint16_t h = sh.h[3 * i + ch];
      if (((h >> 10) & 0x1fu) == 0x1f) {
        ok = false;
        continue;
      }
      out.c[size_t(i)][ch] = halfToFloat(h) * scale;
    }
  if (valid) *valid = ok;
  return out;
}

ShRgb quantizeSh(const ShRgb& sh) {
  ShHalf h;
  return encodeShHalf(sh, &h) ? decodeShHalf(h) : sh;
}

}  // namespace tetraprobe
