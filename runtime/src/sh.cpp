// SH L2 evaluation for the runtime: radiance and cosine-convolved irradiance (Ramamoorthi & Hanrahan 2001).
#include "tetraprobe/runtime/sh.h"

namespace tetraprobe {

glm::vec3 shIrradiance(const ShRgb& sh, const glm::vec3& n) {
  const auto y = shBasis<float>(n.x, n.y, n.z);
  glm::vec3 e(0.0f);
  for (int i = 0; i < kShCoeffCount; ++i) e += sh.c[i] * (y[i] * float(shCosineLobe(i)));
  return e;
}

glm::vec3 shRadiance(const ShRgb& sh, const glm::vec3& d) {
  const auto y = shBasis<float>(d.x, d.y, d.z);
  glm::vec3 l(0.0f);
  for (int i = 0; i < kShCoeffCount; ++i) l += sh.c[i] * y[i];
  return l;
}

ShRgb shBlend(const ShRgb* const* probes, const float* weights, int count) {
  ShRgb out;
  for (int p = 0; p < count; ++p)
    for (int i = 0; i < kShCoeffCount; ++i) out.c[i] += probes[p]->c[i] * weights[p];
  return out;
}

}  // namespace tetraprobe
