// The GPU's packed tet records (gpu_tets.h).
#include "tetraprobe/runtime/gpu_tets.h"

#include <algorithm>
#include <bit>

#include "tetraprobe/runtime/gpu_layout.h"

namespace tetraprobe {

uint32_t bitsFor(uint64_t value) {
  return std::max<uint32_t>(1u, uint32_t(std::bit_width(value)));
}

void putBits(uint32_t* words, uint64_t bit, uint32_t width, uint32_t value) {
  const uint64_t mask = (uint64_t(1) << width) - 1u;
  const uint64_t word = bit >> 5;
  const uint32_t shift = uint32_t(bit & 31u);
  const uint64_t field = (uint64_t(value) & mask) << shift, fieldMask = mask << shift;
  words[word] = uint32_t((words[word] & ~uint32_t(fieldMask)) | uint32_t(field));
  if (shift + width > 32u)
    words[word + 1] = uint32_t((words[word + 1] & ~uint32_t(fieldMask >> 32)) | uint32_t(field >> 32));
}

uint32_t getBits(const uint32_t* words, uint64_t bit, uint32_t width) {
  const uint64_t word = bit >> 5;
  const uint32_t shift = uint32_t(bit & 31u);
  uint64_t v = uint64_t(words[word]) >> shift;
  if (shift + width > 32u) v |= uint64_t(words[word + 1]) << (32u - shift);
  return uint32_t(v & ((uint64_t(1) << width) - 1u));
}

size_t packedFieldWords(uint64_t fields, uint32_t width) {
  return size_t((fields * width + 31u) / 32u + 1u);
}

GpuTetPacking gpuTetPacking(size_t probes, size_t tets) {
  GpuTetPacking p;
  p.vertexBits = bitsFor(probes > 0 ? uint64_t(probes) - 1u : 0u);
  p.neighbourBits = bitsFor(uint64_t(tets));
  p.strideUints = (4u * (p.vertexBits + p.neighbourBits) + 31u) / 32u;
  return p;
}

void packGpuTet(const Tet& t, const GpuTetPacking& packing, uint32_t* record) {
  std::fill(record, record + packing.strideUints, 0u);
  for (int i = 0; i < 4; ++i) {
    putBits(record, uint64_t(i) * packing.vertexBits, packing.vertexBits, uint32_t(t.v[i]));
    putBits(record, 4u * uint64_t(packing.vertexBits) + uint64_t(i) * packing.neighbourBits,
            packing.neighbourBits, uint32_t(t.n[i] + 1));
  }
}

Tet unpackGpuTet(const uint32_t* record, const GpuTetPacking& packing) {
  Tet t{};
  for (int i = 0; i < 4; ++i) {
    t.v[i] = int32_t(getBits(record, uint64_t(i) * packing.vertexBits, packing.vertexBits));
    t.n[i] = int32_t(getBits(record, 4u * uint64_t(packing.vertexBits) + uint64_t(i) * packing.neighbourBits,
                             packing.neighbourBits)) -
             1;
  }
  return t;
}

size_t gpuTetBytes(size_t probes, size_t tets) {
  return sizeof(GpuTetHeader) +
         (tets * gpuTetPacking(probes, tets).strideUints + kGpuTetTailUints) * sizeof(uint32_t);
}

}  // namespace tetraprobe
