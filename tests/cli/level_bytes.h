// Byte-level access to `.tpb` files for tests that forge bad levels: little-endian fields, the format's
// CRC-32, the section table (docs/level_format.md). Test code only; the loader has its own readers.
#pragma once

#include <gtest/gtest.h>

#include <cstddef>
#include <cstdint>
#include <cstring>
#include <vector>

namespace tetraprobe::test {

using Bytes = std::vector<uint8_t>;

inline uint32_t crc32(const uint8_t* p, size_t n) {  // IEEE 802.3, as the format
  uint32_t c = 0xFFFFFFFFu;
  for (size_t i = 0; i < n; ++i) {
    c ^= p[i];
    for (int k = 0; k < 8; ++k) c = (c & 1u) ? 0xEDB88320u ^ (c >> 1) : c >> 1;
  }
  return c ^ 0xFFFFFFFFu;
}
inline uint32_t getU32(const Bytes& b, size_t at) {
  uint32_t v = 0;
  for (int i = 0; i < 4; ++i) v |= uint32_t(b[at + size_t(i)]) << (8 * i);
  return v;
}
inline uint64_t getU64(const Bytes& b, size_t at) {
  return uint64_t(getU32(b, at)) | uint64_t(getU32(b, at + 4)) << 32;
}
inline void putU32(Bytes& b, size_t at, uint32_t v) {
  for (int i = 0; i < 4; ++i) b[at + size_t(i)] = uint8_t(v >> (8 * i));
}
inline void putU64(Bytes& b, size_t at, uint64_t v) {
  putU32(b, at, uint32_t(v));
  putU32(b, at + 4, uint32_t(v >> 32));
}
inline void putF32(Bytes& b, size_t at, float v) {
  uint32_t u;
  std::memcpy(&u, &v, 4);
  putU32(b, at, u);
}
inline int32_t getI32(const Bytes& b, size_t at) {
  return int32_t(getU32(b, at));
}

// Header, table and payload CRCs recomputed, so a change past them reaches the later checks.
inline void fixChecksums(Bytes& b) {
  putU32(b, 76, crc32(b.data(), 76));
  const size_t tableEnd = 80 + 24 * size_t(getU32(b, 72)) + 4;
  if (tableEnd + 4 > b.size()) return;  // a table larger than the file (the loader's own case)
  putU32(b, tableEnd - 4, crc32(b.data() + 80, tableEnd - 4 - 80));
  putU32(b, b.size() - 4, crc32(b.data() + 80, b.size() - 4 - 80));
}

// Offset of the section with this tag (four ASCII characters), from the table.
inline size_t section(const Bytes& b, const char* tag) {
  uint32_t t = 0;
  std::memcpy(&t, tag, 4);
  for (uint32_t i = 0; i < getU32(b, 72); ++i)
    if (getU32(b, 80 + 24 * size_t(i)) == t) return size_t(getU64(b, 80 + 24 * size_t(i) + 8));
  ADD_FAILURE() << "the level has no " << tag << " section";
  return 0;
}

}  // namespace tetraprobe::test
