// The SH blend and irradiance of a tet's four probes, inlined for the lookup's hot paths (shade.cpp, and
// query.cpp's batch without occlusion). Internal to the runtime.
#pragma once

#include <cstring>
#include <vector>

#include <glm/vec3.hpp>
#include <glm/vec4.hpp>

#include "tetraprobe/runtime/level.h"
#include "tetraprobe/runtime/sh.h"

namespace tetraprobe::runtime_detail {

#if defined(__GNUC__) && defined(__has_builtin)
#if __has_builtin(__builtin_shufflevector)
#define TETRAPROBE_FLOAT4 1
#endif
#endif

#ifdef TETRAPROBE_FLOAT4
typedef float Float4 __attribute__((vector_size(16)));  // GCC/Clang vector extension: one SSE/NEON register

inline Float4 load4(const float* p) {
  Float4 v;
  std::memcpy(&v, p, sizeof v);
  return v;
}
#endif

// shIrradiance(shBlend(the tet's 4 probes, weights), normal), inlined: the same float operations in the same
// order (so the same bits). With GCC/Clang vectors: the 27-float blend b as 7 vectors of 4 (the last starting
// at float 23, overlapping the sixth: no read past a record), then the 9 irradiance terms with the three
// channels in the lanes of one vector (b[3i..3i+2] shuffled out of the registers, not stored and reloaded),
// each lane summing its terms in shIrradiance's order.
inline glm::vec3 blendIrradiance(const std::vector<ShRgb>& sh, const Tet& t, const glm::vec4& weights,
                                 const glm::vec3& normal) {
  static_assert(sizeof(ShRgb) == 27 * sizeof(float));
  const float* p[4];
  for (int i = 0; i < 4; ++i) p[i] = reinterpret_cast<const float*>(&sh[size_t(t.v[i])]);
  const float w0 = weights[0], w1 = weights[1], w2 = weights[2], w3 = weights[3];
  const auto y = shBasis<float>(normal.x, normal.y, normal.z);
  float f[kShCoeffCount];
  for (int i = 0; i < kShCoeffCount; ++i) f[i] = y[size_t(i)] * float(shCosineLobe(i));
#ifdef TETRAPROBE_FLOAT4
  const auto blend = [&](int j) {
    return ((load4(p[0] + j) * w0 + load4(p[1] + j) * w1) + load4(p[2] + j) * w2) + load4(p[3] + j) * w3;
  };
  const Float4 b0 = blend(0), b4 = blend(4), b8 = blend(8), b12 = blend(12), b16 = blend(16), b20 = blend(20),
               b23 = blend(23);
  // Lane c of term i is b[3i + c] (lane 3 unused).
  const Float4 term[kShCoeffCount] = {b0,
                                      __builtin_shufflevector(b0, b4, 3, 4, 5, 6),
                                      __builtin_shufflevector(b4, b8, 2, 3, 4, 5),
                                      __builtin_shufflevector(b8, b12, 1, 2, 3, 4),
                                      b12,
                                      __builtin_shufflevector(b12, b16, 3, 4, 5, 6),
                                      __builtin_shufflevector(b16, b20, 2, 3, 4, 5),
                                      __builtin_shufflevector(b20, b23, 1, 2, 4, 5),
                                      __builtin_shufflevector(b23, b23, 1, 2, 3, 3)};
  Float4 e = {0.0f, 0.0f, 0.0f, 0.0f};
  for (int i = 0; i < kShCoeffCount; ++i) e += term[i] * f[i];
  return glm::vec3(e[0], e[1], e[2]);
#else
  float b[27];
  for (int j = 0; j < 27; ++j) b[j] = ((p[0][j] * w0 + p[1][j] * w1) + p[2][j] * w2) + p[3][j] * w3;
  glm::vec3 e(0.0f);
  for (int i = 0; i < kShCoeffCount; ++i) e += glm::vec3(b[3 * i], b[3 * i + 1], b[3 * i + 2]) * f[i];
  return e;
#endif
}

}  // namespace tetraprobe::runtime_detail
