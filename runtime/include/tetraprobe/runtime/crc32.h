// CRC-32 (IEEE 802.3, reflected polynomial 0xEDB88320, initial value and final XOR 0xFFFFFFFF: zlib's
// crc32()), the level file's checksum (docs/level_format.md). The one implementation: the loader, the
// streaming reader, the writer, the tests that forge files, the fuzzers and the benchmarks call it.
// Permissive: standard library only.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>

namespace tetraprobe {

namespace crc32_detail {
constexpr std::array<uint32_t, 256> makeTable() {
  std::array<uint32_t, 256> t{};
  for (uint32_t i = 0; i < 256; ++i) {
    uint32_t c = i;
    for (int k = 0; k < 8; ++k) c = (c & 1u) ? 0xEDB88320u ^ (c >> 1) : c >> 1;
    t[i] = c;
  }
  return t;
}
inline constexpr std::array<uint32_t, 256> kTable = makeTable();
static_assert(kTable[1] == 0x77073096u, "CRC-32 table matches zlib");
}  // namespace crc32_detail

// The CRC-32 of `n` bytes at `data` continuing `crc` (0 to start), so a file can be checked in pieces:
// crc32(b, n) == crc32(b + k, n - k, crc32(b, k)). `data` may be null when n is 0.
inline uint32_t crc32(const void* data, size_t n, uint32_t crc = 0) {
  const auto* p = static_cast<const uint8_t*>(data);
  uint32_t c = crc ^ 0xFFFFFFFFu;
  for (size_t i = 0; i < n; ++i) c = crc32_detail::kTable[(c ^ p[i]) & 0xFFu] ^ (c >> 8);
  return c ^ 0xFFFFFFFFu;
}

}  // namespace tetraprobe
