// Little-endian fields at a byte pointer, as the level file stores them (docs/level_format.md): the
// framing parser, the streaming index and the streaming reader read and patch through these. Internal to
// the runtime; bounds are the caller's.
#pragma once

#include <bit>
#include <cstdint>

namespace tetraprobe::runtime_detail {

inline uint32_t u32At(const uint8_t* p) {
  uint32_t v = 0;
  for (int i = 0; i < 4; ++i) v |= uint32_t(p[i]) << (8 * i);
  return v;
}
inline uint64_t u64At(const uint8_t* p) {
  return uint64_t(u32At(p)) | uint64_t(u32At(p + 4)) << 32;
}
inline int32_t i32At(const uint8_t* p) {
  return int32_t(u32At(p));
}
inline float f32At(const uint8_t* p) {
  return std::bit_cast<float>(u32At(p));
}
inline void putU32(uint8_t* p, uint32_t v) {
  for (int i = 0; i < 4; ++i) p[i] = uint8_t(v >> (8 * i));
}

}  // namespace tetraprobe::runtime_detail
