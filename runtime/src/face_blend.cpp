// The face blend: each probe's visibility as a partition of unity over the tets around the point that hold
// the probe, so per-tet occlusion data leaves no seam on faces, edges or corners. Contract and formulas:
// runtime/include/tetraprobe/runtime/face_blend.h.
#include "tetraprobe/runtime/face_blend.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include <glm/geometric.hpp>

#include "tetraprobe/runtime/occlusion.h"

namespace tetraprobe {
namespace {

inline OcclusionKind kindOf(const LevelOcclusion& occlusion, int32_t tet) {
  return size_t(tet) < occlusion.tets.size() ? occlusion.tets[size_t(tet)].kind() : kOcclusionNone;
}

inline bool validTet(const Level& level, int32_t t) {
  return t >= 0 && size_t(t) < level.tets.size();
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

// tau of the header: the trust in a tet of blindness b.
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

// The slot of tet m's vertex that tet s does not hold (m and s sharing a face: m's vertex off that face); 4
// when there is none.
int offFaceSlot(const Tet& m, const Tet& s) {
  int j = 0;
  while (j < 4 && (m.v[j] == s.v[0] || m.v[j] == s.v[1] || m.v[j] == s.v[2] || m.v[j] == s.v[3])) ++j;
  return j;
}

// The slot of probe p in tet t; 4 when t does not hold it.
int slotOf(const Tet& t, int32_t p) {
  int slot = 0;
  while (slot < 4 && t.v[slot] != p) ++slot;
  return slot;
}

// omega_S of the header for tet s (frame f, weights wS at the point), with band `band`; each face's depth in
// the thinner tet's units (the first pass) or in S's own (the blind pass).
float reach(const Level& level, int32_t s, const BaryFrame& f, const glm::vec4& wS, float band,
            bool thinner) {
  const Tet& t = level.tets[size_t(s)];
  float d = 0.0f;
  for (int g = 0; g < 4; ++g) {
    if (!(wS[g] < 0.0f)) continue;
    // The height ratio H_S / H_M over face g: M's vertex off the face lies at S's weight -H_M / H_S.
    float ratio = 1.0f;
    const int32_t m = t.n[g];
    if (thinner && validTet(level, m)) {
      const Tet& tm = level.tets[size_t(m)];
      const int j = offFaceSlot(tm, t);
      if (j < 4) {
        const float wq = baryWeights(f, level.probes[size_t(tm.v[j])])[g];
        if (wq < 0.0f && -1.0f / wq > 1.0f) ratio = -1.0f / wq;
      }
    }
    d += -wS[g] * ratio / band;
  }
  if (!(d < 1.0f)) return 0.0f;  // beyond the band, or not finite
  return 1.0f - d * d * (3.0f - 2.0f * d);
}

// One pass of the blend with band `band`: the sums of the header for each of tet's probes, over the tets
// the search below finds.
struct Sums {
  glm::vec4 num{0.0f}, den{0.0f}, softMin{1.0f};
  int count[4] = {0, 0, 0, 0};  // tets besides the point's own that hold the probe (omega > 0)
  bool allOne[4] = {true, true, true, true};
  float maxBlind = 0.0f;
};

Sums blendPass(const Level& level, const LevelOcclusion& occlusion, int32_t tet, const BaryFrame& ownFrame,
               const glm::vec4& weights, const glm::vec4& visibility, const glm::vec3& local,
               const glm::vec3& normal, float band, uint32_t probes, bool thinner) {
  const Tet& t = level.tets[size_t(tet)];
  Sums s;
  const float ownBlind = blindness(weights, visibility);
  const float ownTrust = trust(ownBlind);
  s.maxBlind = ownBlind;
  for (int i = 0; i < 4; ++i) {
    s.num[i] = ownTrust * visibility[i];
    s.den[i] = ownTrust;
    s.softMin[i] = visibility[i];
    s.allOne[i] = visibility[i] == 1.0f;
  }
  // Breadth first from the point's tet across faces. A tet U that reaches the point (omega > 0; the point's
  // own tet first) puts its neighbour M across face k on the list when M holds one of the blended probes and
  // may reach the point: the point lies within a band of the face on U's side, in the thinner tet's units
  // (first pass: w_U,k < band, a test on weights U has) or in M's (blind pass: w_U,k < band H_M / H_U, where
  // M's vertex off the face lies at w_U,k = -H_M / H_U); beyond, omega_M is 0. So only tets near the point's
  // faces, edges and corners are framed. tried[] holds every tet listed.
  int32_t tried[kFaceBlendMaxTets];
  int n = 0, head = 1;
  tried[n++] = tet;
  int32_t u = tet;
  BaryFrame fu = ownFrame;
  glm::vec4 wu = baryWeights(fu, local);  // raw, as every other tet's
  for (;;) {
    const Tet& tu = level.tets[size_t(u)];
    for (int k = 0; k < 4; ++k) {
      const int32_t m = tu.n[k];
      if (!validTet(level, m) || (thinner && !(wu[k] < band))) continue;
      bool seen = false;
      for (int q = 0; q < n && !seen; ++q) seen = tried[q] == m;
      if (seen) continue;
      const Tet& tm = level.tets[size_t(m)];
      bool holds = false;
      for (int i = 0; i < 4; ++i)
        if ((probes >> i) & 1u)
          for (int j = 0; j < 4; ++j) holds = holds || tm.v[j] == t.v[i];
      if (!holds) continue;
      if (!thinner) {
        const int j = offFaceSlot(tm, tu);
        if (j < 4 && !(wu[k] < band * -baryWeights(fu, level.probes[size_t(tm.v[j])])[k])) continue;
      }
      if (n == kFaceBlendMaxTets) return s;  // the list is full: what was found so far
      tried[n++] = m;
    }
    // The next listed tet that reaches the point: its sums, then its neighbours.
    bool found = false;
    while (head < n && !found) {
      const int32_t nb = tried[head++];
      const Tet& tn = level.tets[size_t(nb)];
      const BaryFrame f = baryFrame(tn, level.probes);
      const glm::vec4 w = baryWeights(f, local);
      const float omega = reach(level, nb, f, w, band, thinner);
      if (!(omega > 0.0f)) continue;
      const glm::vec4 v = kindOf(occlusion, nb) == kOcclusionNone
                              ? glm::vec4(1.0f)
                              : occlusionVisibility(level, occlusion, nb, f, local, normal);
      const float blind = blindness(w, v);
      const float wt = omega * trust(blind);
      s.maxBlind = std::max(s.maxBlind, omega * blind);
      for (int i = 0; i < 4; ++i) {
        if (((probes >> i) & 1u) == 0) continue;
        const int slot = slotOf(tn, t.v[i]);
        if (slot == 4) continue;
        const float vj = v[slot];
        s.num[i] += wt * vj;
        s.den[i] += wt;
        s.softMin[i] = std::min(s.softMin[i], omega * vj + (1.0f - omega));
        s.allOne[i] = s.allOne[i] && vj == 1.0f;
        ++s.count[i];
      }
      u = nb;
      fu = f;
      wu = w;
      found = true;
    }
    if (!found) break;
  }
  return s;
}

glm::vec4 resolve(const Sums& s, const glm::vec4& visibility, const glm::vec4& front, uint32_t probes) {
  glm::vec4 out = visibility;
  for (int i = 0; i < 4; ++i) {
    if (((probes >> i) & 1u) == 0 || s.count[i] == 0) continue;  // unchanged: the tet's own value
    if (s.allOne[i]) {
      out[i] = 1.0f;  // every tet sees it at exactly 1: the sum of weights would round
      continue;
    }
    const float avg = s.num[i] / s.den[i];
    out[i] = std::min(avg, std::max(std::max(s.softMin[i], front[i]), s.maxBlind));
  }
  return glm::clamp(out, 0.0f, 1.0f);
}

// The breadth-first walk over the tets holding probe t.v[i] (across the faces that hold it), stopping when
// `stop` says so; false when it ran past kFaceBlendStarTets (the caller then assumes the worst).
template <class Stop>
bool walkStar(const Level& level, int32_t tet, int i, Stop stop) {
  const int32_t p = level.tets[size_t(tet)].v[i];
  int32_t star[kFaceBlendStarTets];
  int n = 0;
  star[n++] = tet;
  for (int head = 0; head < n; ++head) {
    const Tet& u = level.tets[size_t(star[head])];
    const int slot = slotOf(u, p);
    if (slot == 4) continue;
    if (stop(star[head], slot)) return true;
    for (int k = 0; k < 4; ++k) {
      if (k == slot || !validTet(level, u.n[k])) continue;  // face k holds p unless k is p's own slot
      bool seen = false;
      for (int q = 0; q < n && !seen; ++q) seen = star[q] == u.n[k];
      if (seen) continue;
      if (n == kFaceBlendStarTets) return false;
      star[n++] = u.n[k];
    }
  }
  return true;
}

}  // namespace

bool faceBlendProbeFlag(const Level& level, const LevelOcclusion& occlusion, int32_t tet, int i) {
  if (!validTet(level, tet) || i < 0 || i > 3) return false;
  bool hides = false;
  const bool complete = walkStar(level, tet, i, [&](int32_t s, int slot) {
    hides = mayHide(occlusion, s, slot);
    return hides;
  });
  return hides || !complete;
}

bool faceBlendMayReach(const Level& level, int32_t tet, const glm::dvec3& lo, const glm::dvec3& hi) {
  if (!validTet(level, tet)) return false;
  const Tet& t = level.tets[size_t(tet)];
  glm::dvec3 p[4];
  for (int i = 0; i < 4; ++i) p[i] = glm::dvec3(level.probes[size_t(t.v[i])]);
  // w_g(x) = a_g . x + b_g, the tet's barycentric weights in double.
  const glm::dvec3 e0 = p[0] - p[3], e1 = p[1] - p[3], e2 = p[2] - p[3];
  const glm::dvec3 c0 = glm::cross(e1, e2), c1 = glm::cross(e2, e0), c2 = glm::cross(e0, e1);
  const double det = glm::dot(e0, c0);
  if (!(std::abs(det) > 0.0) || !std::isfinite(det)) return true;
  glm::dvec3 a[4] = {c0 / det, c1 / det, c2 / det, glm::dvec3(0.0)};
  double b[4];
  for (int g = 0; g < 3; ++g) b[g] = -glm::dot(a[g], p[3]);
  a[3] = -(a[0] + a[1] + a[2]);
  b[3] = 1.0 - (b[0] + b[1] + b[2]);
  // The region sum_g max(0, -w_g) < band: the 15 half-spaces -sum_{g in P} w_g <= band.
  const double band = 1.01 * double(kFaceBlendFallbackBand);
  glm::dvec3 hn[15];
  double hr[15];
  for (int m = 1; m < 16; ++m) {
    hn[m - 1] = glm::dvec3(0.0);
    hr[m - 1] = band;
    for (int g = 0; g < 4; ++g)
      if ((m >> g) & 1) hn[m - 1] -= a[g], hr[m - 1] += b[g];
  }
  // The box against each half-space: wholly outside when its corner lowest along the normal is.
  for (int q = 0; q < 15; ++q) {
    double lowest = 0.0;
    for (int k = 0; k < 3; ++k) lowest += hn[q][k] * (hn[q][k] >= 0.0 ? lo[k] : hi[k]);
    if (lowest > hr[q]) return false;
  }
  // The region's own box, from its vertices (three of the planes meeting inside all 15).
  glm::dvec3 rlo(std::numeric_limits<double>::infinity()), rhi = -rlo;
  for (int i = 0; i < 15; ++i)
    for (int j = i + 1; j < 15; ++j)
      for (int k = j + 1; k < 15; ++k) {
        const glm::dvec3 jk = glm::cross(hn[j], hn[k]);
        const double d = glm::dot(hn[i], jk);
        if (!(std::abs(d) > 1e-9 * glm::length(hn[i]) * glm::length(hn[j]) * glm::length(hn[k]))) continue;
        const glm::dvec3 x =
            (hr[i] * jk + hr[j] * glm::cross(hn[k], hn[i]) + hr[k] * glm::cross(hn[i], hn[j])) / d;
        bool inside = std::isfinite(x.x) && std::isfinite(x.y) && std::isfinite(x.z);
        for (int q = 0; q < 15 && inside; ++q)
          inside = glm::dot(hn[q], x) <= hr[q] + 1e-9 * (1.0 + std::abs(hr[q]));
        if (!inside) continue;
        rlo = glm::min(rlo, x);
        rhi = glm::max(rhi, x);
      }
  if (!(rlo.x <= rhi.x)) return true;  // no vertex found (rounding on a near-flat tet): keep it
  for (int k = 0; k < 3; ++k)
    if (rhi[k] < lo[k] || rlo[k] > hi[k]) return false;
  return true;
}

std::vector<uint8_t> faceBlendMasks(const Level& level, const LevelOcclusion& occlusion) {
  std::vector<uint32_t> held(level.probes.size(), 0);
  std::vector<uint8_t> hides(level.probes.size(), 0), masks(level.tets.size(), 0);
  for (size_t t = 0; t < level.tets.size(); ++t)
    for (int i = 0; i < 4; ++i) {
      const size_t p = size_t(level.tets[t].v[i]);
      if (p >= held.size()) continue;
      ++held[p];
      hides[p] = hides[p] || mayHide(occlusion, int32_t(t), i);
    }
  for (size_t t = 0; t < level.tets.size(); ++t)
    for (int i = 0; i < 4; ++i) {
      const size_t p = size_t(level.tets[t].v[i]);
      if (p < held.size() && (hides[p] || held[p] > uint32_t(kFaceBlendStarTets)))
        masks[t] |= uint8_t(1u << i);
    }
  return masks;
}

std::vector<int32_t> faceBlendStar(const Level& level, int32_t tet, int i) {
  std::vector<int32_t> out;
  if (!validTet(level, tet) || i < 0 || i > 3) return out;
  walkStar(level, tet, i, [&](int32_t s, int) {
    out.push_back(s);
    return false;
  });
  return out;
}

uint32_t faceBlendMask(const Level& level, const LevelOcclusion& occlusion, int32_t tet) {
  uint32_t mask = 0;
  for (int i = 0; i < 4; ++i) mask |= faceBlendProbeFlag(level, occlusion, tet, i) ? 1u << i : 0u;
  return mask;
}

glm::vec4 faceBlendVisibility(const Level& level, const LevelOcclusion& occlusion, int32_t tet,
                              const glm::vec4& weights, const glm::vec4& visibility, const glm::vec3& local,
                              const glm::vec3& normal, FaceBlendProbes which) {
  const uint32_t probes = which == kFaceBlendFlaggedProbes ? faceBlendMask(level, occlusion, tet) : 15u;
  if (probes == 0u) return visibility;
  const Tet& t = level.tets[size_t(tet)];
  glm::vec3 toProbe[4];
  for (int i = 0; i < 4; ++i) toProbe[i] = level.probes[size_t(t.v[i])] - local;
  const glm::vec4 front = probeFront(toProbe, normal);
  const BaryFrame frame = baryFrame(t, level.probes);  // the tet's own, for both passes
  glm::vec4 out = resolve(blendPass(level, occlusion, tet, frame, weights, visibility, local, normal,
                                    kFaceBlendBand, probes, true),
                          visibility, front, probes);
  // Where that still sees nothing, a wider band in each reaching tet's own units, blended in by the
  // blindness b: a larger neighbour's sight reaches through the whole of a small blind tet.
  const float blind = blindness(weights, out);
  if (blind > 0.0f) {
    const float band = kFaceBlendBand + (kFaceBlendFallbackBand - kFaceBlendBand) * blind;
    const glm::vec4 wide = resolve(
        blendPass(level, occlusion, tet, frame, weights, visibility, local, normal, band, probes, false),
        visibility, front, probes);
    out = out + blind * (wide - out);
  }
  return out;
}

glm::vec4 lookupVisibility(const Level& level, const LevelOcclusion& occlusion, const Location& loc,
                           const glm::vec4& visibility, const glm::vec3& local, const glm::vec3& normal) {
  if (occlusion.empty() || loc.tet < 0 || size_t(loc.tet) >= level.tets.size() || loc.outerCell >= 0)
    return visibility;
  return faceBlendVisibility(level, occlusion, loc.tet, loc.weights, visibility, local, normal);
}

}  // namespace tetraprobe
