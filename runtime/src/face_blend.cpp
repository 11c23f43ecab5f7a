// Blending the occlusion visibility of a tet's face probes with its face neighbours' near shared faces, so
// per-tet occlusion data leaves no seam on the faces. Contract and formulas:
// runtime/include/tetraprobe/runtime/face_blend.h.
#include "tetraprobe/runtime/face_blend.h"

#include <algorithm>
#include <cmath>

#include "tetraprobe/runtime/occlusion.h"

namespace tetraprobe {
namespace {

inline OcclusionKind kindOf(const LevelOcclusion& occlusion, int32_t tet) {
  return size_t(tet) < occlusion.tets.size() ? occlusion.tets[size_t(tet)].kind() : kOcclusionNone;
}

// c of the header: the trust in a tet's visibility at a point where, by that visibility alone, the
// all-occluded fallback has share f.
inline float trust(float fallback) {
  return 1.0f - (1.0f - kFaceBlendFallbackTrust) * std::clamp(fallback, 0.0f, 1.0f);
}

}  // namespace

glm::vec4 faceBlendVisibility(const Level& level, const LevelOcclusion& occlusion, int32_t tet,
                              const glm::vec4& weights, const glm::vec4& visibility, const glm::vec3& local,
                              const glm::vec3& normal) {
  const Tet& t = level.tets[size_t(tet)];
  const bool ownData = kindOf(occlusion, tet) != kOcclusionNone;
  glm::vec4 out = visibility;
  float ownFallback = 0.0f;
  applyOcclusion(weights, visibility, &ownFallback);
  const float ownTrust = trust(ownFallback);
  for (int k = 0; k < 4; ++k) {
    const int32_t nb = t.n[k];
    if (!(weights[k] < kFaceBlendBand) || nb < 0 || size_t(nb) >= level.tets.size()) continue;
    const bool otherData = kindOf(occlusion, nb) != kOcclusionNone;
    if (!otherData) {
      // The neighbour sees every probe (trust 1): nothing to blend where this tet does too.
      bool allSeen = true;
      for (int i = 0; i < 4; ++i) allSeen = allSeen && (i == k || visibility[i] == 1.0f);
      if (!ownData || allSeen) continue;
    }
    const Tet& tn = level.tets[size_t(nb)];
    float x = std::max(weights[k], 0.0f) / kFaceBlendBand;
    glm::vec4 other(1.0f);
    float c = ownTrust / (ownTrust + 1.0f);
    if (otherData) {
      int m = 0;
      while (m < 4 && tn.n[m] != tet) ++m;
      if (m == 4) continue;
      const BaryFrame frame = baryFrame(tn, level.probes);
      const glm::vec4 w = baryWeights(frame, local);
      x = std::max(x, -w[m] / kFaceBlendBand);
      if (!(x < 1.0f)) continue;  // beyond the band, or not finite
      other = occlusionVisibility(level, occlusion, nb, frame, local, normal);
      float otherFallback = 0.0f;
      applyOcclusion(w, other, &otherFallback);
      c = ownTrust / (ownTrust + trust(otherFallback));
    }
    if (!(x < 1.0f)) continue;
    const float a = 1.0f - x * x * (3.0f - 2.0f * x);
    for (int i = 0; i < 4; ++i) {
      if (i == k) continue;
      int j = 0;
      while (j < 4 && tn.v[j] != t.v[i]) ++j;
      if (j == 4) continue;
      out[i] += a * ((c * visibility[i] + (1.0f - c) * other[j]) - visibility[i]);
    }
  }
  return glm::clamp(out, 0.0f, 1.0f);
}

glm::vec4 lookupVisibility(const Level& level, const LevelOcclusion& occlusion, int32_t tet,
                           const glm::vec4& weights, bool insideHull, const glm::vec3& local,
                           const glm::vec3& normal) {
  if (occlusion.empty() || tet < 0 || size_t(tet) >= level.tets.size()) return glm::vec4(1.0f);
  const glm::vec4 vis = occlusionVisibility(level, occlusion, tet, local, normal);
  if (!insideHull || !nearFace(weights)) return vis;
  return faceBlendVisibility(level, occlusion, tet, weights, vis, local, normal);
}

}  // namespace tetraprobe
