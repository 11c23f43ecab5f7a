// SplitMix64 finaliser (Steele, Lea & Flood 2014, "Fast splittable pseudorandom number generators"): a
// bijective 64-bit mix. Seeds per probe, point or pixel are derived with it from (seed, index), so results
// never depend on the thread that computes them.
#pragma once

#include <cstdint>

namespace tetraprobe {

inline uint64_t splitmix64(uint64_t x) {
  x += 0x9e3779b97f4a7c15ull;
  x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ull;
  x = (x ^ (x >> 27)) * 0x94d049bb133111ebull;
  return x ^ (x >> 31);
}

}  // namespace tetraprobe
