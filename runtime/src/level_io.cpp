// The `.tpb` level file: explicit little-endian serialisation, field by field, and a loader that is safe on
// untrusted input (parse -> validate -> hand out, in the manner of cgltf). The byte layout, the field table
// and the version policy are in docs/level_format.md; the constants below are the single source of truth.
//
// Integrity: a CRC-32 over the header (checked before any count is trusted) and a CRC-32 over everything
// after it; then every count is checked against the file size before anything is allocated, and every index
// and number is validated (validateLevel) before the level is handed out.
#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <cstring>
#include <string>
#include <utility>

#include "tetraprobe/runtime/file_io.h"
#include "tetraprobe/runtime/level.h"

namespace tetraprobe {
namespace {

constexpr std::array<uint8_t, 8> kMagic = {0x89, 'T', 'P', 'B', '\r', '\n', 0x1A, '\n'};
constexpr uint32_t kVersion = 1;
constexpr uint32_t kHeaderBytes = 80;
constexpr uint32_t kHeaderCrcOffset = 76;               // CRC-32 of header bytes [0, 76)
constexpr uint64_t kProbeBytes = 3 * 4;                 // position: 3 x f32
constexpr uint64_t kShBytes = 27 * 4;                   // SH: 9 coefficients x RGB f32
constexpr uint64_t kTetBytes = 4 * 4 + 4 * 4 + 12 * 4;  // v[4] i32, n[4] i32, row[3][4] f32
constexpr uint64_t kTrailerBytes = 4;                   // CRC-32 of bytes [kHeaderBytes, size - 4)
constexpr uint64_t kMaxCount = uint64_t(INT32_MAX);     // probe and tet indices are int32
constexpr uint64_t kMaxGeneratorBytes = 1u << 20;
static_assert(kTetBytes == sizeof(Tet), "the file's tet record is the GPU's 80-byte std430 Tet");
static_assert(kShBytes == sizeof(ShRgb), "the file's SH record is the 108-byte ShRgb");

// CRC-32 (IEEE 802.3, reflected polynomial 0xEDB88320, as zlib's crc32()).
constexpr std::array<uint32_t, 256> makeCrcTable() {
  std::array<uint32_t, 256> t{};
  for (uint32_t i = 0; i < 256; ++i) {
    uint32_t c = i;
    for (int k = 0; k < 8; ++k) c = (c & 1u) ? 0xEDB88320u ^ (c >> 1) : c >> 1;
    t[i] = c;
  }
  return t;
}
constexpr std::array<uint32_t, 256> kCrcTable = makeCrcTable();

uint32_t crc32(const uint8_t* p, size_t n) {
  uint32_t c = 0xFFFFFFFFu;
  for (size_t i = 0; i < n; ++i) c = kCrcTable[(c ^ p[i]) & 0xFFu] ^ (c >> 8);
  return c ^ 0xFFFFFFFFu;
}
static_assert(makeCrcTable()[1] == 0x77073096u, "CRC-32 table matches zlib");

// --- writing ---------------------------------------------------------------------------------------------
class Writer {
 public:
  void bytes(const void* p, size_t n) { out_.append(static_cast<const char*>(p), n); }
  void u32(uint32_t v) {
    for (int i = 0; i < 4; ++i) out_.push_back(char(uint8_t(v >> (8 * i))));
  }
  void u64(uint64_t v) {
    for (int i = 0; i < 8; ++i) out_.push_back(char(uint8_t(v >> (8 * i))));
  }
  void i32(int32_t v) { u32(uint32_t(v)); }
  void f32(float v) { u32(std::bit_cast<uint32_t>(v)); }
  void f64(double v) { u64(std::bit_cast<uint64_t>(v)); }
  void patchU32(size_t at, uint32_t v) {
    for (int i = 0; i < 4; ++i) out_[at + size_t(i)] = char(uint8_t(v >> (8 * i)));
  }
  uint32_t crcOf(size_t from, size_t to) const {
    return crc32(reinterpret_cast<const uint8_t*>(out_.data()) + from, to - from);
  }
  std::string& str() { return out_; }

 private:
  std::string out_;
};

// --- reading (bounds are checked by the caller against the file size before any read)
// -----------------------
class Reader {
 public:
  explicit Reader(const uint8_t* p) : p_(p) {}
  uint32_t u32() {
    uint32_t v = 0;
    for (int i = 0; i < 4; ++i) v |= uint32_t(p_[i]) << (8 * i);
    p_ += 4;
    return v;
  }
  uint64_t u64() {
    uint64_t v = 0;
    for (int i = 0; i < 8; ++i) v |= uint64_t(p_[i]) << (8 * i);
    p_ += 8;
    return v;
  }
  int32_t i32() { return int32_t(u32()); }
  float f32() { return std::bit_cast<float>(u32()); }
  double f64() { return std::bit_cast<double>(u64()); }
  const uint8_t* skip(size_t n) {
    const uint8_t* at = p_;
    p_ += n;
    return at;
  }

 private:
  const uint8_t* p_;
};

LevelResult fail(LevelStatus status, std::string message) {
  return {status, std::move(message)};
}

bool finite3(const glm::vec3& v) {
  return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z);
}

}  // namespace

LevelResult validateLevel(const Level& level) {
  const auto corrupt = [](std::string m) { return fail(LevelStatus::kCorrupt, std::move(m)); };
  if ((level.content & ~uint32_t(kContentAll)) != 0)
    return corrupt("unknown content flags " + std::to_string(level.content) +
                   " (known: " + std::to_string(uint32_t(kContentAll)) + ")");
  if (level.shOrder != 1 && level.shOrder != 2)
    return corrupt("SH order " + std::to_string(level.shOrder) + " (expected 1 or 2)");
  if (!std::isfinite(level.origin.x) || !std::isfinite(level.origin.y) || !std::isfinite(level.origin.z))
    return corrupt("non-finite origin");
  if (level.probes.size() > kMaxCount || level.tets.size() > kMaxCount)
    return corrupt(std::to_string(level.probes.size()) + " probes / " + std::to_string(level.tets.size()) +
                   " tets exceed the int32 index range");
  if (level.sh.size() != level.probes.size())
    return corrupt(std::to_string(level.probes.size()) + " probes but " + std::to_string(level.sh.size()) +
                   " SH records");
  if (level.generator.size() > kMaxGeneratorBytes)
    return corrupt("generator string of " + std::to_string(level.generator.size()) + " bytes exceeds " +
                   std::to_string(kMaxGeneratorBytes));
  const int64_t probeCount = int64_t(level.probes.size()), tetCount = int64_t(level.tets.size());
  for (int64_t p = 0; p < probeCount; ++p) {
    if (!finite3(level.probes[size_t(p)]))
      return corrupt("probe " + std::to_string(p) + ": non-finite position");
    const ShRgb& sh = level.sh[size_t(p)];
    for (int i = 0; i < kShCoeffCount; ++i) {
      if (!finite3(sh.c[size_t(i)]))
        return corrupt("probe " + std::to_string(p) + ": non-finite SH coefficient " + std::to_string(i));
      if (level.shOrder == 1 && i >= 4 && sh.c[size_t(i)] != glm::vec3(0.0f))
        return corrupt("probe " + std::to_string(p) + ": L1 level with non-zero L2 coefficient " +
                       std::to_string(i));
    }
  }
  for (int64_t t = 0; t < tetCount; ++t) {
    const Tet& tet = level.tets[size_t(t)];
    const std::string where = "tet " + std::to_string(t) + ": ";
    for (int i = 0; i < 4; ++i) {
      if (tet.v[i] < 0 || tet.v[i] >= probeCount)
        return corrupt(where + "vertex " + std::to_string(tet.v[i]) + " out of range (" +
                       std::to_string(probeCount) + " probes)");
      for (int j = 0; j < i; ++j)
        if (tet.v[i] == tet.v[j]) return corrupt(where + "vertex " + std::to_string(tet.v[i]) + " repeated");
      const int32_t n = tet.n[i];
      if (n < -1 || n >= tetCount || n == t)
        return corrupt(where + "neighbour " + std::to_string(n) + " out of range (" +
                       std::to_string(tetCount) + " tets)");
      if (n >= 0) {  // adjacency is mutual: the neighbour names this tet back
        const Tet& other = level.tets[size_t(n)];
        if (other.n[0] != t && other.n[1] != t && other.n[2] != t && other.n[3] != t)
          return corrupt(where + "neighbour " + std::to_string(n) + " does not name it back");
      }
    }
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 4; ++c)
        if (!std::isfinite(tet.row[r][c])) return corrupt(where + "non-finite barycentric row");
  }
  return {};
}

LevelResult saveLevel(const std::string& path, const Level& level) {
  if (LevelResult v = validateLevel(level); !v)
    return fail(LevelStatus::kWriteFailed, path + ": refusing to write an invalid level: " + v.message);
  Writer w;
  w.str().reserve(size_t(kHeaderBytes + level.probes.size() * (kProbeBytes + kShBytes) +
                         level.tets.size() * kTetBytes + level.generator.size() + kTrailerBytes));
  w.bytes(kMagic.data(), kMagic.size());
  w.u32(kVersion);
  w.u32(kHeaderBytes);
  w.u32(level.content);
  w.u32(level.shOrder);
  w.f64(level.origin.x);
  w.f64(level.origin.y);
  w.f64(level.origin.z);
  w.u64(level.probes.size());
  w.u64(level.tets.size());
  w.u64(level.generator.size());
  w.u32(0);  // reserved
  w.u32(w.crcOf(0, kHeaderCrcOffset));
  for (const glm::vec3& p : level.probes) {
    w.f32(p.x);
    w.f32(p.y);
    w.f32(p.z);
  }
  for (const ShRgb& sh : level.sh)
    for (const glm::vec3& c : sh.c) {
      w.f32(c.x);
      w.f32(c.y);
      w.f32(c.z);
    }
  for (const Tet& t : level.tets) {
    for (int32_t v : t.v) w.i32(v);
    for (int32_t n : t.n) w.i32(n);
    for (const auto& row : t.row)
      for (float x : row) w.f32(x);
  }
  w.bytes(level.generator.data(), level.generator.size());
  w.u32(w.crcOf(kHeaderBytes, w.str().size()));
  std::string error;
  if (!writeFileAtomic(path, w.str(), &error)) return fail(LevelStatus::kWriteFailed, error);
  return {};
}

LevelResult loadLevel(const std::string& path, Level& out) {
  out = Level{};
  std::vector<char> file;
  std::string error;
  if (!readFile(path, file, &error)) return fail(LevelStatus::kCannotOpen, error);
  const uint8_t* data = reinterpret_cast<const uint8_t*>(file.data());
  const uint64_t size = file.size();
  const std::string name = path + ": ";

  // Magic (a prefix of it in a short file means truncated, anything else is not a level), then version.
  if (size > 0 && std::memcmp(data, kMagic.data(), size_t(std::min<uint64_t>(size, kMagic.size()))) != 0)
    return fail(LevelStatus::kNotALevel, name + "not a tetraprobe level (bad magic)");
  if (size < kMagic.size() + 4)
    return fail(LevelStatus::kTruncated, name + "truncated: " + std::to_string(size) + " bytes");
  Reader r(data + kMagic.size());
  const uint32_t version = r.u32();
  if (version != kVersion)
    return fail(LevelStatus::kUnsupportedVersion, name + "format version " + std::to_string(version) +
                                                      " (this reader understands version " +
                                                      std::to_string(kVersion) + ")");
  if (size < kHeaderBytes)
    return fail(LevelStatus::kTruncated, name + "truncated header: " + std::to_string(size) + " bytes");
  Reader crcField(data + kHeaderCrcOffset);
  if (crc32(data, kHeaderCrcOffset) != crcField.u32())
    return fail(LevelStatus::kCorrupt, name + "header checksum mismatch");

  const uint32_t headerBytes = r.u32();
  Level level;
  level.content = r.u32();
  level.shOrder = r.u32();
  level.origin.x = r.f64();
  level.origin.y = r.f64();
  level.origin.z = r.f64();
  const uint64_t probeCount = r.u64(), tetCount = r.u64(), generatorBytes = r.u64();
  const uint32_t reserved = r.u32();
  if (headerBytes != kHeaderBytes || reserved != 0)
    return fail(LevelStatus::kCorrupt, name + "unexpected header size or reserved field");
  // Counts are checked against the limits first, so the size arithmetic below cannot overflow (< 2^40).
  if (probeCount > kMaxCount || tetCount > kMaxCount || generatorBytes > kMaxGeneratorBytes)
    return fail(LevelStatus::kCorrupt, name + "implausible counts: " + std::to_string(probeCount) +
                                           " probes, " + std::to_string(tetCount) + " tets, " +
                                           std::to_string(generatorBytes) + " generator bytes");
  const uint64_t expected = kHeaderBytes + probeCount * (kProbeBytes + kShBytes) + tetCount * kTetBytes +
                            generatorBytes + kTrailerBytes;
  if (size < expected)
    return fail(LevelStatus::kTruncated, name + "truncated: " + std::to_string(size) +
                                             " bytes, the header needs " + std::to_string(expected));
  if (size > expected)
    return fail(LevelStatus::kCorrupt, name + std::to_string(size - expected) + " unexpected trailing bytes");
  Reader trailer(data + expected - kTrailerBytes);
  if (crc32(data + kHeaderBytes, size_t(expected - kHeaderBytes - kTrailerBytes)) != trailer.u32())
    return fail(LevelStatus::kCorrupt, name + "payload checksum mismatch");

  // Sizes are now known to be backed by the file: allocate and parse.
  Reader body(data + kHeaderBytes);
  level.probes.resize(size_t(probeCount));
  for (glm::vec3& p : level.probes) {
    p.x = body.f32();
    p.y = body.f32();
    p.z = body.f32();
  }
  level.sh.resize(size_t(probeCount));
  for (ShRgb& sh : level.sh)
    for (glm::vec3& c : sh.c) {
      c.x = body.f32();
      c.y = body.f32();
      c.z = body.f32();
    }
  level.tets.resize(size_t(tetCount));
  for (Tet& t : level.tets) {
    for (int32_t& v : t.v) v = body.i32();
    for (int32_t& n : t.n) n = body.i32();
    for (auto& row : t.row)
      for (float& x : row) x = body.f32();
  }
  const uint8_t* gen = body.skip(size_t(generatorBytes));
  level.generator.assign(reinterpret_cast<const char*>(gen), size_t(generatorBytes));

  if (LevelResult v = validateLevel(level); !v) return fail(v.status, name + v.message);
  out = std::move(level);
  return {};
}

}  // namespace tetraprobe
