// Deterministic random numbers for the bake: a SplitMix64 hash to derive independent streams from
// (seed, item, sample) keys, and PCG32 (O'Neill 2014, "PCG: a family of simple fast space-efficient
// statistically good algorithms for random number generation") to draw from each stream. Results depend only
// on the keys, never on the thread that draws them. Internal to the bake module.
#pragma once

#include <cstdint>

#include "tetraprobe/common/splitmix.h"

namespace tetraprobe::bake_detail {

// Key for one stream: chained mixing keeps (a, b, c) and (b, a, c) apart.
inline uint64_t streamKey(uint64_t seed, uint64_t a, uint64_t b = 0) {
  return splitmix64(splitmix64(splitmix64(seed) ^ a) ^ b);
}

class Rng {
 public:
  explicit Rng(uint64_t key) : state_(0), inc_((splitmix64(key ^ 0x5851f42d4c957f2dull) << 1) | 1u) {
    next();
    state_ += splitmix64(key);
    next();
  }

  uint32_t next() {
    const uint64_t old = state_;
    state_ = old * 6364136223846793005ull + inc_;
    const uint32_t xorshifted = uint32_t(((old >> 18u) ^ old) >> 27u);
    const uint32_t rot = uint32_t(old >> 59u);
    return (xorshifted >> rot) | (xorshifted << ((32u - rot) & 31u));
  }

  // Uniform in [0, 1): 24 random bits, so the result is exactly representable and never rounds up to 1.
  float uniform() { return float(next() >> 8) * 0x1p-24f; }
  // Uniform in [0, 1) with 53 bits.
  double uniformDouble() {
    const uint64_t hi = next(), lo = next();
    return double(((hi << 32) | lo) >> 11) * 0x1p-53;
  }

 private:
  uint64_t state_;
  uint64_t inc_;
};

}  // namespace tetraprobe::bake_detail
