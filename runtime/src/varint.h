// LEB128 varints and zigzag signed mapping, for the level file's packed sections (bsp_codec.h, tet_codec.h).
// Internal to the runtime.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>

namespace tetraprobe::runtime_detail {

// zigzag(d) = 2d for d >= 0, -2d - 1 below: small magnitudes of either sign give small codes.
inline uint64_t zigzag(int64_t v) {
  return v < 0 ? (uint64_t(-(v + 1)) << 1) | 1u : uint64_t(v) << 1;
}
inline int64_t unzigzag(uint64_t z) {
  return (z & 1u) ? -int64_t(z >> 1) - 1 : int64_t(z >> 1);
}

// Unsigned LEB128: 7 bits a byte, low first, the high bit set on every byte but the last.
inline void putVarint(std::string& out, uint64_t v) {
  while (v >= 0x80) {
    out.push_back(char(uint8_t(v) | 0x80));
    v >>= 7;
  }
  out.push_back(char(uint8_t(v)));
}

// Reads the varint at p[*at], advancing *at; false when the bytes end first or it runs past 64 bits.
inline bool getVarint(const uint8_t* p, size_t size, size_t* at, uint64_t* v) {
  uint64_t r = 0;
  for (int shift = 0; shift < 64; shift += 7) {
    if (*at >= size) return false;
    const uint8_t b = p[(*at)++];
    if (shift == 63 && b > 1) return false;
    r |= uint64_t(b & 0x7F) << shift;
    if (!(b & 0x80)) {
      *v = r;
      return true;
    }
  }
  return false;
}

}  // namespace tetraprobe::runtime_detail
