// Byte-level encoding shared by the sharded bake's part files (shard_part.h) and the trace farm's job and
// result files (trace_farm.h): little-endian fields one by one, FNV-1a 64 checksums (Fowler, Noll, Vo), and
// one probe's adaptive bake state as a record. Build side; not a level file and not for engines.
#pragma once

#include <cstdint>
#include <cstring>
#include <string>
#include <type_traits>
#include <vector>

#include "tetraprobe/bake/bake.h"

namespace tetraprobe::cli {

uint64_t fnv1a(const void* data, size_t n, uint64_t h = 0xcbf29ce484222325ull);

class ByteWriter {
 public:
  template <class T>
  void put(const T& v) {
    static_assert(std::is_arithmetic_v<T>);
    const size_t at = bytes.size();
    bytes.resize(at + sizeof(T));
    std::memcpy(bytes.data() + at, &v, sizeof(T));
  }
  // Appends the FNV-1a of every byte so far.
  void seal() { put(fnv1a(bytes.data(), bytes.size())); }
  std::string bytes;
};

// Reads fields in order; every failure throws InputError "<what> <path>: <why>".
class ByteReader {
 public:
  ByteReader(const std::vector<char>& b, std::string what, std::string path)
      : b_(b), what_(std::move(what)), path_(std::move(path)) {}
  template <class T>
  T get() {
    need(sizeof(T));
    T v;
    std::memcpy(&v, b_.data() + at_, sizeof(T));
    at_ += sizeof(T);
    return v;
  }
  void need(size_t n) const {
    if (b_.size() - at_ < n) fail("truncated");
  }
  std::string text(size_t n) {
    need(n);
    std::string s(b_.data() + at_, n);
    at_ += n;
    return s;
  }
  // Checks the magic (8 bytes; a file of another version named as such) and the trailing checksum.
  void open(const char (&magic)[8]);
  // Fails unless exactly the checksum is left.
  void finish() const {
    if (at_ + 8 != b_.size()) fail("trailing bytes");
  }
  [[noreturn]] void fail(const std::string& why) const;
  size_t at() const { return at_; }
  size_t left() const { return b_.size() - at_; }

 private:
  const std::vector<char>& b_;
  std::string what_, path_;
  size_t at_ = 0;
};

// Bytes of one state record without its lit-patch entries (16 bytes each).
inline constexpr size_t kProbeStateBytes =
    8 * 27 + 4 + 4 + 8 * 6 + 8 * 6 + 8 + 8 + 8 + 4 * kBakeGuideBins + 4 + 4 + 4;

// ProbeBakeState: f64 acc[27], i32 batches, i32 estimated, f64 mean[6], f64 m2[6], f64 achieved,
// u64 intersectRays, u64 occludedRays, f32 guide[128], i32 guideBatches, u32 P, P x (u64 key, f64 light),
// i32 patchBatches. readProbeState checks the counts against each other and the bytes left.
void putProbeState(ByteWriter& w, const ProbeBakeState& s);
ProbeBakeState getProbeState(ByteReader& r);

}  // namespace tetraprobe::cli
