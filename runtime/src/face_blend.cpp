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

// How blind a side is at the point by its own visibility: 1 - smoothstep(0, kFaceBlendBlindSum, s) with s
// the visible weight sum applyOcclusion computes (weights sanitized and normalized, visibility clamped): 1
// where it sees none of its probes, 0 from s = kFaceBlendBlindSum on. Gentler than the fallback's share
// (1 - s / 0.01), so float rounding of s moves the band, cap and trust it drives five times less.
inline float blindness(const glm::vec4& weights, const glm::vec4& visibility) {
  float sumW = 0.0f, sumWV = 0.0f;
  for (int i = 0; i < 4; ++i) {
    const float w = std::isfinite(weights[i]) && weights[i] > 0.0f ? weights[i] : 0.0f;
    const float v = std::isfinite(visibility[i]) ? std::clamp(visibility[i], 0.0f, 1.0f) : 1.0f;
    sumW += w;
    sumWV += w * v;
  }
  if (!(sumW > 0.0f) || !std::isfinite(sumW)) return 0.0f;
  const float t = std::clamp(sumWV / sumW / kFaceBlendBlindSum, 0.0f, 1.0f);
  return 1.0f - t * t * (3.0f - 2.0f * t);
}

// c of the header: the trust in a side of blindness b.
inline float trust(float blind) {
  return 1.0f - (1.0f - kFaceBlendFallbackTrust) * blind;
}

// False when tet's occlusion data leaves its probe i at visibility exactly 1.0f wherever it is evaluated
// (occlusionVisibility), so the blend cannot move it: no data; planes whose every cell sees the probe, with
// at most one plane (the cells' weights 1 - t and t then sum to exactly 1 in float; with more planes the sum
// of products may round below 1); shadow maps whose map of the probe meets nothing.
bool mayHide(const LevelOcclusion& occlusion, int32_t tet, int i) {
  if (size_t(tet) >= occlusion.tets.size()) return false;
  const TetOcclusion& rec = occlusion.tets[size_t(tet)];
  if (rec.kind() == kOcclusionPlanes) {
    const uint32_t count = rec.planeCount();
    if (count == 0) return false;
    if (count > 1 || size_t(rec.offset()) + count > occlusion.planes.size()) return true;
    return ((rec.cells >> i) & 1u) == 0 || ((rec.cells >> (4 + i)) & 1u) == 0;
  }
  if (rec.kind() == kOcclusionShadowMaps) {
    if ((size_t(rec.offset()) + 1) * kShadowMapBlockBytes > occlusion.shadowMaps.size()) return true;
    const uint8_t* map = occlusion.shadowMaps.data() + size_t(rec.offset()) * kShadowMapBlockBytes +
                         size_t(i) * kShadowMapTexels;
    for (int b = 0; b < kShadowMapLatticeVertices; ++b)
      if (map[b] != kShadowMapNoHit) return true;
    return false;
  }
  return false;
}

}  // namespace

bool faceBlendFaceFlag(const Level& level, const LevelOcclusion& occlusion, int32_t tet, int k) {
  if (size_t(tet) >= level.tets.size()) return false;
  const Tet& t = level.tets[size_t(tet)];
  const int32_t nb = t.n[k];
  if (nb < 0 || size_t(nb) >= level.tets.size()) return false;
  const Tet& tn = level.tets[size_t(nb)];
  for (int i = 0; i < 4; ++i) {
    if (i == k) continue;
    if (mayHide(occlusion, tet, i)) return true;
    for (int j = 0; j < 4; ++j)
      if (tn.v[j] == t.v[i] && mayHide(occlusion, nb, j)) return true;
  }
  return false;
}

uint32_t faceBlendMask(const Level& level, const LevelOcclusion& occlusion, int32_t tet) {
  uint32_t mask = 0;
  for (int k = 0; k < 4; ++k) mask |= faceBlendFaceFlag(level, occlusion, tet, k) ? 1u << k : 0u;
  return mask;
}

glm::vec4 faceBlendVisibility(const Level& level, const LevelOcclusion& occlusion, int32_t tet,
                              const glm::vec4& weights, const glm::vec4& visibility, const glm::vec3& local,
                              const glm::vec3& normal, FaceBlendFaces faces) {
  const Tet& t = level.tets[size_t(tet)];
  const bool ownData = kindOf(occlusion, tet) != kOcclusionNone;
  glm::vec4 out = visibility;
  const float ownBlind = blindness(weights, visibility);
  const float ownTrust = trust(ownBlind);
  const float band = kFaceBlendBand + (kFaceBlendFallbackBand - kFaceBlendBand) * ownBlind;
  // A probe behind the surface (probeFront) is never seen from it: the neighbour may not raise its visibility
  // above the lower of the two sides' (a symmetric cap, so both sides still agree on the face).
  glm::vec3 toProbe[4];
  for (int i = 0; i < 4; ++i) toProbe[i] = level.probes[size_t(t.v[i])] - local;
  const glm::vec4 front = probeFront(toProbe, normal);
  for (int k = 0; k < 4; ++k) {
    const int32_t nb = t.n[k];
    if (!(weights[k] < band) || nb < 0 || size_t(nb) >= level.tets.size()) continue;
    // Both sides see the face's probes at exactly 1 everywhere: the blend cannot change them.
    if (faces == kFaceBlendFlaggedFaces && !faceBlendFaceFlag(level, occlusion, tet, k)) continue;
    const bool otherData = kindOf(occlusion, nb) != kOcclusionNone;
    if (!otherData) {
      // The neighbour sees every probe (trust 1): nothing to blend where this tet does too.
      bool allSeen = true;
      for (int i = 0; i < 4; ++i) allSeen = allSeen && (i == k || visibility[i] == 1.0f);
      if (!ownData || allSeen) continue;
    }
    const Tet& tn = level.tets[size_t(nb)];
    float x = std::max(weights[k], 0.0f) / band;
    glm::vec4 other(1.0f);
    float otherBlind = 0.0f;
    float c = ownTrust / (ownTrust + 1.0f);
    if (otherData) {
      int m = 0;
      while (m < 4 && tn.n[m] != tet) ++m;
      if (m == 4) continue;
      const BaryFrame frame = baryFrame(tn, level.probes);
      const glm::vec4 w = baryWeights(frame, local);
      x = std::max(x, -w[m] / band);
      if (!(x < 1.0f)) continue;  // beyond the band, or not finite
      other = occlusionVisibility(level, occlusion, nb, frame, local, normal);
      otherBlind = blindness(w, other);
      c = ownTrust / (ownTrust + trust(otherBlind));
    }
    if (!(x < 1.0f)) continue;
    const float a = 1.0f - x * x * (3.0f - 2.0f * x);
    const float anyBlind = std::max(ownBlind, otherBlind);
    for (int i = 0; i < 4; ++i) {
      if (i == k) continue;
      int j = 0;
      while (j < 4 && tn.v[j] != t.v[i]) ++j;
      if (j == 4) continue;
      const float target =
          std::min(c * visibility[i] + (1.0f - c) * other[j],
                   std::max(std::max(std::min(visibility[i], other[j]), front[i]), anyBlind));
      out[i] += a * (target - visibility[i]);
    }
  }
  return glm::clamp(out, 0.0f, 1.0f);
}

glm::vec4 lookupVisibility(const Level& level, const LevelOcclusion& occlusion, const Location& loc,
                           const glm::vec4& visibility, const glm::vec3& local, const glm::vec3& normal) {
  if (occlusion.empty() || loc.tet < 0 || size_t(loc.tet) >= level.tets.size() || loc.outerCell >= 0)
    return visibility;
  return faceBlendVisibility(level, occlusion, loc.tet, loc.weights, visibility, local, normal);
}

}  // namespace tetraprobe
