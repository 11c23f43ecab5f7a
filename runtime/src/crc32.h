// CRC-32 (IEEE 802.3, reflected polynomial 0xEDB88320, as zlib's crc32()), the level file's checksum
// (docs/level_format.md), incremental so a file can be checked in pieces. Internal to the runtime.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>

namespace tetraprobe::runtime_detail {

constexpr std::array<uint32_t, 256> makeCrcTable() {
  std::array<uint32_t, 256> t{};
  for (uint32_t i = 0; i < 256; ++i) {
    uint32_t c = i;
    for (int k = 0; k < 8; ++k) c = (c & 1u) ? 0xEDB88320u ^ (c >> 1) : c >> 1;
    t[i] = c;
  }
  return t;
}
inline constexpr std::array<uint32_t, 256> kCrcTable = makeCrcTable();
static_assert(kCrcTable[1] == 0x77073096u, "CRC-32 table matches zlib");

// Continues a CRC over n more bytes: crc32(b, n) == crc32Update(crc32Update(0, b, k), b + k, n - k).
inline uint32_t crc32Update(uint32_t crc, const uint8_t* p, size_t n) {
  uint32_t c = crc ^ 0xFFFFFFFFu;
  for (size_t i = 0; i < n; ++i) c = kCrcTable[(c ^ p[i]) & 0xFFu] ^ (c >> 8);
  return c ^ 0xFFFFFFFFu;
}

inline uint32_t crc32(const uint8_t* p, size_t n) {
  return crc32Update(0, p, n);
}

}  // namespace tetraprobe::runtime_detail
