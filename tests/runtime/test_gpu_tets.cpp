// The GPU's packed tet records (runtime/gpu_tets.h): lossless for every width the counts can ask for, no
// field touching another, and the record no longer than the counts need.
#include <gtest/gtest.h>

#include <cstdint>
#include <random>
#include <vector>

#include "tetraprobe/runtime/gpu_layout.h"
#include "tetraprobe/runtime/gpu_tets.h"

namespace tetraprobe {
namespace {

TEST(GpuTets, BitsForIsTheSmallestWidthHoldingTheValue) {
  EXPECT_EQ(bitsFor(0), 1u);
  EXPECT_EQ(bitsFor(1), 1u);
  EXPECT_EQ(bitsFor(2), 2u);
  EXPECT_EQ(bitsFor(255), 8u);
  EXPECT_EQ(bitsFor(256), 9u);
  EXPECT_EQ(bitsFor(0xffffffffull), 32u);
  for (uint32_t b = 1; b < 32; ++b) {
    EXPECT_EQ(bitsFor((uint64_t(1) << b) - 1), b);
    EXPECT_EQ(bitsFor(uint64_t(1) << b), b + 1);
  }
}

// Random fields of every width at every offset: each reads back, and writing one leaves the bits around it.
TEST(GpuTets, PutBitsWritesOnlyItsFieldAndGetBitsReadsItBack) {
  std::mt19937_64 rng(7);
  for (uint32_t width = 1; width <= 32; ++width)
    for (uint64_t bit = 0; bit < 96; ++bit) {
      uint32_t words[5];
      for (uint32_t& w : words) w = uint32_t(rng());
      uint32_t before[5];
      std::copy(words, words + 5, before);
      const uint32_t value = uint32_t(rng());
      const uint32_t mask = width == 32 ? 0xffffffffu : (1u << width) - 1u;
      putBits(words, bit, width, value);
      ASSERT_EQ(getBits(words, bit, width), value & mask) << width << " bits at " << bit;
      for (uint64_t b = 0; b < 160; ++b) {
        if (b >= bit && b < bit + width) continue;
        ASSERT_EQ(words[b >> 5] >> (b & 31) & 1u, before[b >> 5] >> (b & 31) & 1u)
            << "bit " << b << " changed by a " << width << "-bit field at " << bit;
      }
    }
}

// Every index a level of these counts can hold, the extremes included, comes back from its record, and the
// record is the shortest whole number of words the fields fit in.
TEST(GpuTets, EveryTetComesBackFromItsRecordAtEveryLevelSize) {
  std::mt19937 rng(3);
  const size_t sizes[][2] = {{1, 1},
                             {4, 1},
                             {598, 3001},
                             {5357, 28096},
                             {16384, 65535},
                             {15162, 68433},
                             {480000, 2800000},
                             {(1u << 22), (1u << 26) - 1},
                             {(1u << 31) - 1, (1u << 31) - 1}};
  for (const auto& s : sizes) {
    const size_t probes = s[0], tets = s[1];
    const GpuTetPacking p = gpuTetPacking(probes, tets);
    EXPECT_LT(probes - 1, uint64_t(1) << p.vertexBits);
    EXPECT_LT(tets, uint64_t(1) << p.neighbourBits);
    EXPECT_EQ(p.strideUints, (4 * (p.vertexBits + p.neighbourBits) + 31) / 32);
    EXPECT_EQ(gpuTetBytes(probes, tets),
              sizeof(GpuTetHeader) + (tets * p.strideUints + kGpuTetTailUints) * sizeof(uint32_t));
    std::vector<Tet> cases;
    Tet hi{}, lo{};
    for (int i = 0; i < 4; ++i) {
      hi.v[i] = int32_t(probes - 1);
      hi.n[i] = int32_t(tets - 1);
      lo.v[i] = 0;
      lo.n[i] = -1;
    }
    cases.push_back(hi);
    cases.push_back(lo);
    for (int k = 0; k < 200; ++k) {
      Tet t{};
      for (int i = 0; i < 4; ++i) {
        t.v[i] = int32_t(rng() % probes);
        t.n[i] = int32_t(int64_t(rng() % (tets + 1)) - 1);
      }
      cases.push_back(t);
    }
    std::vector<uint32_t> record(p.strideUints + 1, 0xdeadbeefu);
    for (const Tet& t : cases) {
      packGpuTet(t, p, record.data());
      ASSERT_EQ(record[p.strideUints], 0xdeadbeefu) << "a record writes past its stride";
      const Tet back = unpackGpuTet(record.data(), p);
      for (int i = 0; i < 4; ++i) {
        ASSERT_EQ(back.v[i], t.v[i]) << probes << " probes, " << tets << " tets";
        ASSERT_EQ(back.n[i], t.n[i]) << probes << " probes, " << tets << " tets";
      }
    }
  }
  // The shared levels' sizes: half the CPU's 32 bytes up to 16 k probes and 64 k tets.
  EXPECT_EQ(gpuTetPacking(16384, 65535).strideUints, 4u);
  EXPECT_EQ(gpuTetPacking(598, 3001).strideUints, 3u);
}

}  // namespace
}  // namespace tetraprobe
