// Unit vectors in 32 bits: the octahedral encoding (Meyer et al. 2010, "On Floating-Point Normal Vectors";
// Cigolle et al. 2014, "A Survey of Efficient Representations for Independent Unit Vectors"), two 16-bit
// integers in units of 2^-15. The outer cells' vertex normals travel to the GPU this way (gpu_layout.h,
// GpuOuterCell), 12 bytes a cell instead of 48. Permissive: standard library and GLM only.
//
// Exactness. Decoding before the normalisation is exact dyadic arithmetic (every value a multiple of 2^-15 in
// [-1, 1]) in float and double alike, so the GLSL decode (tetraprobeOctDecode,
// shaders/tetraprobe_outer_cells.glsl) and this one agree bit for bit up to the final normalize; the CPU
// normalises in double and rounds once, the GPU normalises in float (a few ulp apart). Angular error of the
// encoding: below 5e-5 rad (the best of the four neighbouring codes is taken, by the decoded direction).
#pragma once

#include <cstdint>

#include <glm/vec3.hpp>

namespace tetraprobe {

inline constexpr double kOctNormalUnit = 1.0 / 32768.0;  // one step of the 16-bit components
inline constexpr int kOctNormalMax = 32767;              // components in [-32767, 32767]

// The code of the direction of `n` (any length; a zero or non-finite vector encodes +z). Code bits: x in
// 0..15, y in 16..31, each a two's-complement int16.
uint32_t encodeOctNormal(const glm::dvec3& n);

// The code's vector before normalisation: exact, |x| + |y| + |z| == 1.
glm::dvec3 decodeOctNormalRaw(uint32_t code);

// The code's unit vector, normalised in double and rounded to float once.
glm::vec3 decodeOctNormal(uint32_t code);

// decodeOctNormal(encodeOctNormal(n)): n on the code lattice. Idempotent: quantizing a quantized normal
// returns it bit for bit (OctNormal.QuantizeIsIdempotent).
glm::vec3 quantizeOctNormal(const glm::dvec3& n);

}  // namespace tetraprobe
