// Byte-level access to `.tpb` files for tests that forge bad levels: little-endian fields, the format's
// CRC-32, the section table (docs/level_format.md). Test code only; the loader has its own readers.
#pragma once

#include <gtest/gtest.h>

#include <cstddef>
#include <cstdint>
#include <cstring>
#include <vector>

#include "tetraprobe/runtime/crc32.h"
#include "tetraprobe/runtime/level_file.h"

namespace tetraprobe::test {

using Bytes = std::vector<uint8_t>;

using tetraprobe::crc32;  // the format's one CRC-32 (tetraprobe/runtime/crc32.h)
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

// Every checksum recomputed (header, table, payload, and a streaming index's own and its sectors'), so a
// change past them reaches the later checks: the runtime's recomputeLevelChecksums (level_file.h).
inline void fixChecksums(Bytes& b) {
  tetraprobe::recomputeLevelChecksums(b.data(), b.size());
}

// Offset of the section with this tag (four ASCII characters), from the table; 0 when there is none.
inline size_t findSection(const Bytes& b, const char* tag) {
  uint32_t t = 0;
  std::memcpy(&t, tag, 4);
  for (uint32_t i = 0; i < getU32(b, 72); ++i)
    if (getU32(b, 80 + 24 * size_t(i)) == t) return size_t(getU64(b, 80 + 24 * size_t(i) + 8));
  return 0;
}

// Offset of the section with this tag, which the level must have.
inline size_t section(const Bytes& b, const char* tag) {
  const size_t at = findSection(b, tag);
  if (at == 0) ADD_FAILURE() << "the level has no " << tag << " section";
  return at;
}

}  // namespace tetraprobe::test
