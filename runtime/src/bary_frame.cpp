// The float barycentric frame of a tet from its probe positions (level.h: BaryFrame). The level stores no
// barycentric rows; occlusion (CPU and GPU) evaluates its planes and shadow maps on these weights, so this
// is written operation for operation as shaders/tetraprobe.glsl's tetraprobeBaryFrame and
// tetraprobeBaryWeights (cross and dot products spelled out: no library may reorder them).
#include "tetraprobe/runtime/level.h"

namespace tetraprobe {
namespace {

inline glm::vec3 crossF(const glm::vec3& a, const glm::vec3& b) {
  return glm::vec3(a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x);
}
inline float dotF(const glm::vec3& a, const glm::vec3& b) {
  return (a.x * b.x + a.y * b.y) + a.z * b.z;
}

}  // namespace

BaryFrame baryFrame(const Tet& t, const std::vector<glm::vec3>& probes) {
  BaryFrame f;
  const glm::vec3 p3 = probes[size_t(t.v[3])];
  const glm::vec3 e0 = probes[size_t(t.v[0])] - p3, e1 = probes[size_t(t.v[1])] - p3,
                  e2 = probes[size_t(t.v[2])] - p3;
  const glm::vec3 c0 = crossF(e1, e2), c1 = crossF(e2, e0), c2 = crossF(e0, e1);
  const float inv = 1.0f / dotF(e0, c0);
  f.origin = p3;
  f.grad[0] = c0 * inv;
  f.grad[1] = c1 * inv;
  f.grad[2] = c2 * inv;
  return f;
}

glm::vec4 baryWeights(const BaryFrame& f, const glm::vec3& x) {
  const glm::vec3 d = x - f.origin;
  glm::vec4 w;
  w[0] = dotF(f.grad[0], d);
  w[1] = dotF(f.grad[1], d);
  w[2] = dotF(f.grad[2], d);
  w[3] = ((1.0f - w[0]) - w[1]) - w[2];
  return w;
}

}  // namespace tetraprobe
