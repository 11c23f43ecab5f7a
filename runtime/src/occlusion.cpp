// Run-time evaluation of per-tet probe occlusion: splitting planes and 16-texel shadow maps (Killzone Shadow
// Fall, Valient GDC 2014), all in the tet's barycentric frame so the GPU mirror needs only the weights it
// has. Contract and constants: runtime/include/tetraprobe/runtime/occlusion.h; layout: docs/occlusion.md.
#include "tetraprobe/runtime/occlusion.h"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <limits>

#include <glm/geometric.hpp>

namespace tetraprobe {
namespace {

constexpr int kRowStart[4] = {0, 7, 12, 15};

// GLSL smoothstep (edge0 < edge1).
inline bool finite3(const glm::vec3& v) {
  return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z);
}
inline bool finite4(const glm::vec4& v) {
  return finite3(glm::vec3(v)) && std::isfinite(v.w);
}

inline float smoothStep(float e0, float e1, float x) {
  const float t = std::clamp((x - e0) / (e1 - e0), 0.0f, 1.0f);
  return t * t * (3.0f - 2.0f * t);
}

glm::vec4 planesVisibility(const TetOcclusion& rec, const OcclusionPlane* planes, const glm::vec4& w) {
  const uint32_t count = rec.planeCount();
  if (count == 0 || count > 3 || planes == nullptr) return glm::vec4(1.0f);
  float t[3] = {1.0f, 1.0f, 1.0f};  // weight of the positive side of each plane
  for (uint32_t k = 0; k < count; ++k) {
    const glm::vec4 c(planes[k].value(0), planes[k].value(1), planes[k].value(2), planes[k].value(3));
    t[k] = smoothStep(-kOcclusionPlaneFalloff, kOcclusionPlaneFalloff, glm::dot(c, w));
  }
  glm::vec4 vis(0.0f);
  for (uint32_t cell = 0; cell < (1u << count); ++cell) {
    float weight = 1.0f;
    for (uint32_t k = 0; k < count; ++k) weight *= (cell >> k & 1u) ? t[k] : 1.0f - t[k];
    const uint32_t mask = rec.cells >> (4 * cell) & 15u;
    for (int i = 0; i < 4; ++i) vis[i] += (mask >> i & 1u) ? weight : 0.0f;
  }
  return glm::clamp(vis, 0.0f, 1.0f);
}

glm::vec4 shadowMapVisibility(const uint8_t* texels, const glm::vec4& w) {
  if (texels == nullptr) return glm::vec4(1.0f);
  glm::vec4 vis(1.0f);
  for (int i = 0; i < 4; ++i) {
    // The ray from probe i through the point leaves the tet on the opposite face at barycentrics
    // w_j / (1 - w_i) (j != i), after a fraction 1 - w_i of its length inside the tet.
    int slot[3], n = 0;
    for (int j = 0; j < 4; ++j)
      if (j != i) slot[n++] = j;
    const float a = std::max(w[slot[0]], 0.0f), b = std::max(w[slot[1]], 0.0f),
                c = std::max(w[slot[2]], 0.0f);
    const float sum = a + b + c;
    const float u = sum > 0.0f ? b / sum : 1.0f / 3.0f, v = sum > 0.0f ? c / sum : 1.0f / 3.0f;
    const float depth = shadowMapDepth(texels + i * kShadowMapTexels, u, v);
    if (depth > 1.0f) continue;
    const float f = 1.0f - w[i];
    vis[i] = 1.0f - smoothStep(depth - kOcclusionShadowFalloff, depth + kOcclusionShadowFalloff, f);
  }
  return vis;
}

// Clamps (u, v) onto the face and finds its sub-triangle: cell row iv, column iu, upper or lower.
void locateOnFace(float& u, float& v, int& iu, int& iv, bool& upper) {
  u = std::isfinite(u) ? std::clamp(u, 0.0f, 1.0f) : 0.0f;
  v = std::isfinite(v) ? std::clamp(v, 0.0f, 1.0f) : 0.0f;
  if (u + v > 1.0f) {  // clamp onto the face along the diagonal
    const float s = u + v;
    u /= s;
    v /= s;
  }
  const float x = 4.0f * u, y = 4.0f * v;
  iu = std::min(int(x), 3);
  iv = std::min(int(y), 3);
  upper = (x - float(iu)) + (y - float(iv)) > 1.0f;
  if (iu + iv >= 3) {  // the last diagonal holds lower sub-triangles only (rounding on the hypotenuse)
    iu = std::min(iu, 3 - iv);
    upper = false;
  }
}

}  // namespace

OcclusionPlane makeOcclusionPlane(double d0, double d1, double d2, double d3) {
  const double d[4] = {d0, d1, d2, d3};
  double m = 0.0;
  for (double x : d) m = std::max(m, std::abs(x));
  OcclusionPlane p;
  if (!(m > 0.0) || !std::isfinite(m)) return p;
  for (int i = 0; i < 4; ++i) p.c[i] = int16_t(std::lround(std::clamp(d[i] / m, -1.0, 1.0) * 32767.0));
  return p;
}

int shadowMapCell(float u, float v) {
  int iu, iv;
  bool upper;
  locateOnFace(u, v, iu, iv, upper);
  return kRowStart[iv] + 2 * iu + (upper ? 1 : 0);
}

float shadowMapDepth(const uint8_t* probeTexels, float u, float v) {
  int iu, iv;
  bool upper;
  locateOnFace(u, v, iu, iv, upper);
  const float fu = 4.0f * u - float(iu), fv = 4.0f * v - float(iv);
  int corner[3];
  float b[3];
  if (upper) {
    corner[0] = shadowMapVertex(iu + 1, iv + 1), b[0] = fu + fv - 1.0f;
    corner[1] = shadowMapVertex(iu, iv + 1), b[1] = 1.0f - fu;
    corner[2] = shadowMapVertex(iu + 1, iv), b[2] = 1.0f - fv;
  } else {
    corner[0] = shadowMapVertex(iu, iv), b[0] = 1.0f - fu - fv;
    corner[1] = shadowMapVertex(iu + 1, iv), b[1] = fu;
    corner[2] = shadowMapVertex(iu, iv + 1), b[2] = fv;
  }
  float inv = 0.0f, sum = 0.0f;
  bool anyHit = false;
  for (int k = 0; k < 3; ++k) {
    b[k] = std::max(b[k], 0.0f);
    sum += b[k];
    const uint8_t q = probeTexels[corner[k]];
    anyHit = anyHit || q != kShadowMapNoHit;
    const float d = q == kShadowMapNoHit ? 1.0f : std::max(float(q), 0.5f) / kShadowMapScale;
    inv += b[k] / d;
  }
  if (!anyHit) return 2.0f;
  return sum > 0.0f ? sum / inv : 1.0f;
}

glm::vec2 shadowMapCellCentre(int cell) {
  cell = std::clamp(cell, 0, kShadowMapTexels - 1);
  int row = 3;
  while (kRowStart[row] > cell) --row;
  const int k = cell - kRowStart[row];
  const int iu = k / 2;
  const float off = (k & 1) ? 2.0f / 3.0f : 1.0f / 3.0f;
  return glm::vec2((float(iu) + off) / 4.0f, (float(row) + off) / 4.0f);
}

glm::vec4 biasWeights(const BaryFrame& frame, const glm::vec4& weights, const glm::vec3& normal) {
  const glm::vec3 g0 = frame.grad[0], g1 = frame.grad[1], g2 = frame.grad[2];
  const glm::vec4 gn(glm::dot(g0, normal), glm::dot(g1, normal), glm::dot(g2, normal),
                     -glm::dot(g0 + g1 + g2, normal));
  const float m =
      std::max(std::max(std::abs(gn.x), std::abs(gn.y)), std::max(std::abs(gn.z), std::abs(gn.w)));
  if (!(m > 0.0f) || !std::isfinite(m)) return weights;
  return weights + gn * (kOcclusionBias / m);
}

glm::vec4 evaluateTetOcclusion(const TetOcclusion& rec, const OcclusionPlane* planes,
                               const uint8_t* shadowMap, const BaryFrame& frame, const glm::vec4& weights,
                               const glm::vec3& normal) {
  switch (rec.kind()) {
    case kOcclusionPlanes:
      return planesVisibility(rec, planes, biasWeights(frame, weights, normal));
    case kOcclusionShadowMaps:
      return shadowMapVisibility(shadowMap, biasWeights(frame, weights, normal));
    default:
      return glm::vec4(1.0f);
  }
}

glm::vec4 occlusionVisibility(const Level& level, const LevelOcclusion& occlusion, int32_t tet,
                              const glm::vec3& local, const glm::vec3& normal) {
  if (occlusion.tets.empty() || tet < 0 || size_t(tet) >= occlusion.tets.size() ||
      size_t(tet) >= level.tets.size())
    return glm::vec4(1.0f);
  const TetOcclusion& rec = occlusion.tets[size_t(tet)];
  if (rec.kind() != kOcclusionPlanes && rec.kind() != kOcclusionShadowMaps) return glm::vec4(1.0f);
  return occlusionVisibility(level, occlusion, tet, baryFrame(level.tets[size_t(tet)], level.probes), local,
                             normal);
}

glm::vec4 occlusionVisibility(const Level& level, const LevelOcclusion& occlusion, int32_t tet,
                              const BaryFrame& frame, const glm::vec3& local, const glm::vec3& normal) {
  if (occlusion.tets.empty() || tet < 0 || size_t(tet) >= occlusion.tets.size() ||
      size_t(tet) >= level.tets.size())
    return glm::vec4(1.0f);
  const TetOcclusion& rec = occlusion.tets[size_t(tet)];
  if (rec.kind() != kOcclusionPlanes && rec.kind() != kOcclusionShadowMaps) return glm::vec4(1.0f);
  const glm::vec4 w = baryWeights(frame, local);
  const glm::vec3 n = finite3(normal) ? normal : glm::vec3(0.0f);
  const OcclusionPlane* planes = nullptr;
  const uint8_t* texels = nullptr;
  if (rec.kind() == kOcclusionPlanes) {
    if (size_t(rec.offset()) + rec.planeCount() > occlusion.planes.size()) return glm::vec4(1.0f);
    planes = occlusion.planes.data() + rec.offset();
  } else if (rec.kind() == kOcclusionShadowMaps) {
    if ((size_t(rec.offset()) + 1) * kShadowMapBlockBytes > occlusion.shadowMaps.size())
      return glm::vec4(1.0f);
    texels = occlusion.shadowMaps.data() + size_t(rec.offset()) * kShadowMapBlockBytes;
  }
  const glm::vec4 vis = evaluateTetOcclusion(rec, planes, texels, frame, w, n);
  return finite4(vis) ? vis : glm::vec4(1.0f);
}

glm::vec4 applyOcclusion(const glm::vec4& weights, const glm::vec4& visibility, float* fallback) {
  if (fallback) *fallback = 0.0f;
  glm::vec4 w, v;
  float sumW = 0.0f;
  for (int i = 0; i < 4; ++i) {
    w[i] = std::isfinite(weights[i]) && weights[i] > 0.0f ? weights[i] : 0.0f;
    v[i] = std::isfinite(visibility[i]) ? std::clamp(visibility[i], 0.0f, 1.0f) : 1.0f;
    sumW += w[i];
  }
  if (!(sumW > 0.0f) || !std::isfinite(sumW)) return glm::vec4(0.25f);
  w /= sumW;
  const glm::vec4 o = w * v;
  const float s = o.x + o.y + o.z + o.w;
  if (fallback && s < kOcclusionFallbackSum) *fallback = 1.0f - s / kOcclusionFallbackSum;
  return s > 0.0f ? o / s : w;
}

glm::vec4 probeFront(const glm::vec3 toProbe[4], const glm::vec3& normal) {
  glm::vec4 front(1.0f);
  const float nl = glm::length(normal);
  for (int i = 0; i < 4; ++i) {
    const float scale = kOcclusionFrontSine * glm::length(toProbe[i]) * nl;
    const float f = glm::dot(toProbe[i], normal) / scale;
    if (scale > 0.0f && std::isfinite(f)) front[i] = std::clamp(f, 0.0f, 1.0f);
  }
  return front;
}

glm::vec3 occludedIrradiance(const ShRgb* const probes[4], const glm::vec4& weights,
                             const glm::vec4& visibility, const glm::vec3& normal, const glm::vec4& front) {
  float f = 0.0f;
  const glm::vec4 w = applyOcclusion(weights, visibility, &f);
  float wf[4] = {w.x, w.y, w.z, w.w};
  const glm::vec3 visible = shIrradiance(shBlend(probes, wf, 4), normal);
  if (!(f > 0.0f)) return visible;
  // The unoccluded weights u, and their 8th powers renormalized: a blend dominated by the nearest probe
  // (the largest weight) in front of the surface, continuous where two weights tie.
  const glm::vec4 u = applyOcclusion(weights, glm::vec4(1.0f));
  const glm::vec4 q = fallbackLean(u, front);
  glm::vec4 p = q * q;
  p = p * p;
  p = p * p;
  const float ps = p.x + p.y + p.z + p.w;
  if (ps > 0.0f)
    p /= ps;
  else
    p = u;
  float uf[4] = {u.x, u.y, u.z, u.w}, pf[4] = {p.x, p.y, p.z, p.w};
  const glm::vec3 nearest = shIrradiance(shBlend(probes, pf, 4), normal);
  const glm::vec3 blend = shIrradiance(shBlend(probes, uf, 4), normal);
  return (1.0f - f) * visible + f * glm::min(nearest, blend);
}

glm::vec3 occludedIrradianceAt(const Level& level, int32_t tet, const glm::vec4& weights,
                               const glm::vec4& visibility, const glm::vec3& local, const glm::vec3& normal) {
  const Tet& t = level.tets[size_t(tet)];
  const ShRgb* probes[4];
  glm::vec3 toProbe[4];
  for (int i = 0; i < 4; ++i) {
    probes[i] = &level.sh[size_t(t.v[i])];
    toProbe[i] = level.probes[size_t(t.v[i])] - local;
  }
  return occludedIrradiance(probes, weights, visibility, normal, probeFront(toProbe, normal));
}

}  // namespace tetraprobe
