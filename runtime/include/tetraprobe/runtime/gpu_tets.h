// The tets as the GPU reads them: each tet's four probe indices and four neighbour codes packed into as few
// 32-bit words as the level's counts allow (gpu_layout.h, TetraprobeTets; GLSL: tetraprobeTetVertices,
// tetraprobeTetNeighbour in shaders/tetraprobe_tets.glsl). A probe index takes bitsFor(probes - 1) bits, a
// neighbour code (the neighbour's index + 1; 0 on the hull) bitsFor(tets) bits, so a level of up to 16 k
// probes and 64 k tets packs a tet into 16 bytes instead of the CPU's 32, and 4 M probes in 24. Fields go
// least significant bit first, v[0..3] then n[0..3], and may straddle two words. Lossless: unpackGpuTet gives
// the tet back. Permissive: standard library only.
#pragma once

#include <cstddef>
#include <cstdint>

#include "tetraprobe/runtime/level.h"

namespace tetraprobe {

// The smallest b in [1, 32] with value < 2^b (1 for 0). value must be below 2^32.
uint32_t bitsFor(uint64_t value);

// Writes the low `width` bits of `value` (width in [1, 32]) at bit `bit` of `words` (bit 0 = bit 0 of word
// 0), leaving every other bit as it was.
void putBits(uint32_t* words, uint64_t bit, uint32_t width, uint32_t value);

// The `width`-bit field (width in [1, 32]) at bit `bit` of `words`.
uint32_t getBits(const uint32_t* words, uint64_t bit, uint32_t width);

// Words holding `fields` fields of `width` bits packed back to back, plus one zero word: the shader reads the
// word after each field's first, so the last field's next word must exist.
size_t packedFieldWords(uint64_t fields, uint32_t width);

struct GpuTetPacking {
  uint32_t vertexBits = 1;     // bits of a probe index: bitsFor(probes - 1)
  uint32_t neighbourBits = 1;  // bits of a neighbour code (index + 1, 0 = none): bitsFor(tets)
  uint32_t strideUints = 1;    // words a tet: ceil(4 (vertexBits + neighbourBits) / 32), 1..8
};

// The packing of a level with `probes` probes and `tets` tets (both below 2^31).
GpuTetPacking gpuTetPacking(size_t probes, size_t tets);

// Writes tet t's record into packing.strideUints words at `record` (zeroed first). Every index must be in
// range for the packing (v in [0, probes), n in [-1, tets)); packLevelBuffers checks that before.
void packGpuTet(const Tet& t, const GpuTetPacking& packing, uint32_t* record);

// The tet a record holds: the inverse of packGpuTet.
Tet unpackGpuTet(const uint32_t* record, const GpuTetPacking& packing);

// Bytes of the TetraprobeTets buffer's content for such a level: the 16-byte header, the records and the
// zero tail (gpu_layout.h), before the upload's padding to 64 bytes.
size_t gpuTetBytes(size_t probes, size_t tets);

}  // namespace tetraprobe
