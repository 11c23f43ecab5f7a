// Byte-level encoding of part and farm files (state_io.h).
#include "state_io.h"

#include <bit>

#include "tetraprobe/common/error.h"

namespace tetraprobe::cli {

static_assert(std::endian::native == std::endian::little,
              "part and farm files are written on little-endian hosts");

uint64_t fnv1a(const void* data, size_t n, uint64_t h) {
  const auto* p = static_cast<const unsigned char*>(data);
  for (size_t i = 0; i < n; ++i) h = (h ^ p[i]) * 0x100000001b3ull;
  return h;
}

void ByteReader::fail(const std::string& why) const {
  throw InputError(what_ + " " + path_ + ": " + why);
}

void ByteReader::open(const char (&magic)[8]) {
  if (b_.size() >= 8 && std::memcmp(b_.data(), magic, 7) == 0 && b_[7] != magic[7])
    fail("a file of another version (" + std::string(b_.data(), 8) + ") than this tetraprobe's");
  if (b_.size() < 8 || std::memcmp(b_.data(), magic, 8) != 0) fail("not a " + what_ + " file");
  if (b_.size() < 16) fail("truncated");
  uint64_t stored;
  std::memcpy(&stored, b_.data() + b_.size() - 8, 8);
  if (fnv1a(b_.data(), b_.size() - 8) != stored) fail("checksum mismatch (damaged or truncated)");
  at_ = 8;
}

void putProbeState(ByteWriter& w, const ProbeBakeState& s) {
  for (int i = 0; i < kShCoeffCount; ++i)
    for (int c = 0; c < 3; ++c) w.put(s.acc[i][c]);
  w.put(s.batches);
  w.put(s.estimated);
  for (double v : s.mean) w.put(v);
  for (double v : s.m2) w.put(v);
  w.put(s.achieved);
  w.put(s.intersectRays);
  w.put(s.occludedRays);
  for (float v : s.guide) w.put(v);
  w.put(s.guideBatches);
  w.put(uint32_t(s.patches.size()));
  for (const auto& [key, value] : s.patches) {
    w.put(key);
    w.put(value);
  }
  w.put(s.patchBatches);
}

ProbeBakeState getProbeState(ByteReader& r) {
  ProbeBakeState s;
  for (int i = 0; i < kShCoeffCount; ++i)
    for (int c = 0; c < 3; ++c) s.acc[i][c] = r.get<double>();
  s.batches = r.get<int32_t>();
  s.estimated = r.get<int32_t>();
  for (double& v : s.mean) v = r.get<double>();
  for (double& v : s.m2) v = r.get<double>();
  s.achieved = r.get<double>();
  s.intersectRays = r.get<uint64_t>();
  s.occludedRays = r.get<uint64_t>();
  for (float& v : s.guide) v = r.get<float>();
  s.guideBatches = r.get<int32_t>();
  if (s.guideBatches < 0 || s.guideBatches > s.batches) r.fail("bad guide batch count");
  const uint32_t patches = r.get<uint32_t>();
  if (patches > r.left() / 16) r.fail("bad lit-patch histogram size");
  s.patches.resize(patches);
  for (auto& [key, value] : s.patches) {
    key = r.get<uint64_t>();
    value = r.get<double>();
  }
  s.patchBatches = r.get<int32_t>();
  if (s.patchBatches < 0 || s.patchBatches > s.batches) r.fail("bad lit-patch batch count");
  return s;
}

}  // namespace tetraprobe::cli
