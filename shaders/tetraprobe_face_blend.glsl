// tetraprobe_face_blend.glsl: the face blend (runtime/face_blend.h) and the visibility the lookup uses
// (tetraprobeLookupVisibility).
// Part of the lookup of tetraprobe.glsl, whose contract holds here too: an engine includes tetraprobe.glsl,
// which includes this file. Permissive.
#ifndef TETRAPROBE_FACE_BLEND_GLSL
#define TETRAPROBE_FACE_BLEND_GLSL

#include "tetraprobe_occlusion.glsl"

// --- face blend: mirrors runtime/src/face_blend.cpp (faceBlendVisibility; formulas in face_blend.h) ---
const float TETRAPROBE_FACE_BAND = 0.15, TETRAPROBE_FACE_TRUST = 0.1, TETRAPROBE_FACE_FALLBACK_BAND = 0.3,
            TETRAPROBE_FACE_BLIND_SUM = 0.05;
const int TETRAPROBE_FACE_MAX_TETS = 48;

// How blind a tet is by its own visibility: 1 - smoothstep(0, TETRAPROBE_FACE_BLIND_SUM, visible sum).
float tetraprobeFaceBlindness(vec4 weights, vec4 vis) {
  precise float sumW = 0.0, sumWV = 0.0;
  for (int i = 0; i < 4; ++i) {
    float w = (!isnan(weights[i]) && !isinf(weights[i]) && weights[i] > 0.0) ? weights[i] : 0.0;
    float v = (!isnan(vis[i]) && !isinf(vis[i])) ? clamp(vis[i], 0.0, 1.0) : 1.0;
    sumW = sumW + w;
    sumWV = sumWV + w * v;
  }
  if (!(sumW > 0.0) || isinf(sumW)) return 0.0;
  precise float t = clamp(sumWV / sumW / TETRAPROBE_FACE_BLIND_SUM, 0.0, 1.0);
  precise float r = 1.0 - t * t * (3.0 - 2.0 * t);
  return r;
}
float tetraprobeFaceTrust(float blind) {  // tau: the trust in a tet
  precise float r = 1.0 - (1.0 - TETRAPROBE_FACE_TRUST) * blind;
  return r;
}

// The slot of tet m's vertex (of mv) that tet s (sv) does not hold: m's vertex off their shared face; 4 when
// there is none (offFaceSlot in face_blend.cpp).
int tetraprobeOffFaceSlot(ivec4 mv, ivec4 sv) {
  int j = 0;
  while (j < 4 && (mv[j] == sv.x || mv[j] == sv.y || mv[j] == sv.z || mv[j] == sv.w)) ++j;
  return j;
}

// omega of tet s (frame f, weights w at the point) for band `band`: 1 inside s, fading to 0 as its weights below
// 0 sum to -band, each past face counted in the thinner of s and the tet across it (`thinner`, the first
// pass) or in s's own units (the blind pass).
float tetraprobeFaceReach(int s, TetraprobeBaryFrame f, vec4 w, float band, bool thinner) {
  ivec4 sv = tetraprobeTetVertices(s), sn = tetraprobeTetNeighbours(s);
  precise float d = 0.0;
  for (int g = 0; g < 4; ++g) {
    if (!(w[g] < 0.0)) continue;
    precise float ratio = 1.0;
    int m = sn[g];
    if (thinner && m >= 0) {
      ivec4 mv = tetraprobeTetVertices(m);
      int j = tetraprobeOffFaceSlot(mv, sv);
      if (j < 4) {
        precise float wq = tetraprobeBaryWeights(f, tetraprobeProbePosition(mv[j]))[g];
        if (wq < 0.0 && -1.0 / wq > 1.0) ratio = -1.0 / wq;
      }
    }
    d = d + -w[g] * ratio / band;
  }
  if (!(d < 1.0)) return 0.0;  // beyond the band, or not finite
  precise float omega = 1.0 - d * d * (3.0 - 2.0 * d);
  return omega;
}

// One pass of the blend: per probe of tet t, the weighted visibility sums over the tets around the point
// that hold it and reach it, found breadth first from t (face_blend.cpp, blendPass).
struct TetraprobeBlendSums {
  vec4 num, den, softMin;
  ivec4 count;
  bvec4 allOne;
  float maxBlind;
};
TetraprobeBlendSums tetraprobeFaceBlendPass(int t, ivec4 tv, TetraprobeBaryFrame ownFrame, vec4 weights,
                                            vec4 vis, vec3 x, vec3 n, float band, uint probes, bool thinner) {
  TetraprobeBlendSums s;
  float ownBlind = tetraprobeFaceBlindness(weights, vis);
  float ownTrust = tetraprobeFaceTrust(ownBlind);
  s.maxBlind = ownBlind;
  for (int i = 0; i < 4; ++i) {
    precise float num = ownTrust * vis[i];
    s.num[i] = num;
    s.den[i] = ownTrust;
    s.softMin[i] = vis[i];
    s.allOne[i] = vis[i] == 1.0;
    s.count[i] = 0;
  }
  // Breadth first across faces: a tet that reaches the point lists its neighbour M across face k when M holds
  // a blended probe and may reach the point (face_blend.cpp, blendPass).
  int tried[TETRAPROBE_FACE_MAX_TETS];
  int count = 0, head = 1;
  tried[count++] = t;
  int u = t;
  TetraprobeBaryFrame fu = ownFrame;
  vec4 wu = tetraprobeBaryWeights(ownFrame, x);
  for (;;) {
    ivec4 uv = tetraprobeTetVertices(u), un = tetraprobeTetNeighbours(u);
    for (int k = 0; k < 4; ++k) {
      int m = un[k];
      if (m < 0 || (thinner && !(wu[k] < band))) continue;
      bool seen = false;
      for (int q = 0; q < count && !seen; ++q) seen = tried[q] == m;
      if (seen) continue;
      ivec4 mv = tetraprobeTetVertices(m);
      bool holds = false;
      for (int i = 0; i < 4; ++i)
        if (((probes >> uint(i)) & 1u) != 0u)
          for (int j = 0; j < 4; ++j) holds = holds || mv[j] == tv[i];
      if (!holds) continue;
      if (!thinner) {
        int j = tetraprobeOffFaceSlot(mv, uv);
        if (j < 4) {
          float far = tetraprobeBaryWeights(fu, tetraprobeProbePosition(mv[j]))[k];
          precise float limit = band * -far;
          if (!(wu[k] < limit)) continue;
        }
      }
      if (count == TETRAPROBE_FACE_MAX_TETS) return s;  // the list is full: what was found so far
      tried[count++] = m;
    }
    // The next listed tet that reaches the point: its sums, then its neighbours.
    bool found = false;
    while (head < count && !found) {
      int nb = tried[head++];
      ivec4 nv = tetraprobeTetVertices(nb);
      TetraprobeBaryFrame f = tetraprobeBaryFrame(nb);
      vec4 w = tetraprobeBaryWeights(f, x);
      float omega = tetraprobeFaceReach(nb, f, w, band, thinner);
      if (!(omega > 0.0)) continue;
      vec4 v = tetraprobeOccKind(nb) == 0u ? vec4(1.0) : tetraprobeOccVisibilityInFrame(nb, f, x, n);
      float blind = tetraprobeFaceBlindness(w, v);
      precise float wt = omega * tetraprobeFaceTrust(blind);
      precise float ob = omega * blind;
      s.maxBlind = max(s.maxBlind, ob);
      for (int i = 0; i < 4; ++i) {
        if (((probes >> uint(i)) & 1u) == 0u) continue;
        int slot = 0;
        while (slot < 4 && nv[slot] != tv[i]) ++slot;
        if (slot == 4) continue;
        float vj = v[slot];
        precise float num = s.num[i] + wt * vj;
        precise float den = s.den[i] + wt;
        precise float soft = omega * vj + (1.0 - omega);
        s.num[i] = num;
        s.den[i] = den;
        s.softMin[i] = min(s.softMin[i], soft);
        s.allOne[i] = s.allOne[i] && vj == 1.0;
        s.count[i] += 1;
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

vec4 tetraprobeFaceBlendResolve(TetraprobeBlendSums s, vec4 vis, vec4 front, uint probes) {
  vec4 o = vis;
  for (int i = 0; i < 4; ++i) {
    if (((probes >> uint(i)) & 1u) == 0u || s.count[i] == 0) continue;
    if (s.allOne[i]) {
      o[i] = 1.0;
      continue;
    }
    precise float avg = s.num[i] / s.den[i];
    o[i] = min(avg, max(max(s.softMin[i], front[i]), s.maxBlind));
  }
  return clamp(o, 0.0, 1.0);
}

// Tet t's visibility `vis` of its probes at x, each blended over the tets around x that hold the probe, so
// that every tet holding x uses the same numbers (faces, edges and corners alike).
vec4 tetraprobeFaceBlendVisibility(int t, TetraprobeBaryFrame frame, vec4 weights, vec4 vis, vec3 x, vec3 n,
                                   uint probes) {
  ivec4 tv = tetraprobeTetVertices(t);
  vec4 front = tetraprobeProbeFront(t, x, n);
  vec4 o = tetraprobeFaceBlendResolve(
      tetraprobeFaceBlendPass(t, tv, frame, weights, vis, x, n, TETRAPROBE_FACE_BAND, probes, true), vis,
      front, probes);
  // Where that still sees nothing, a wider band in each reaching tet's own units, blended in by the blindness.
  float blind = tetraprobeFaceBlindness(weights, o);
  if (blind > 0.0) {
    precise float band =
        TETRAPROBE_FACE_BAND + (TETRAPROBE_FACE_FALLBACK_BAND - TETRAPROBE_FACE_BAND) * blind;
    vec4 wide = tetraprobeFaceBlendResolve(
        tetraprobeFaceBlendPass(t, tv, frame, weights, vis, x, n, band, probes, false), vis, front, probes);
    precise vec4 r = o + blind * (wide - o);
    o = r;
  }
  return o;
}

// The probes of tet t whose blend may change anything (faceBlendMask, set at upload; 0 for none).
uint tetraprobeFaceBlendProbes(int t) {
  if (t < 0 || uint(t) >= tetraprobeOccTetCount) return 0u;
  uint header = tetraprobeOccData[TETRAPROBE_OCC_RECORD_UINTS * uint(t)];
  return (header >> TETRAPROBE_OCC_PROBE_MASK_SHIFT) & 15u;
}

// The visibility the lookup uses at located point loc (local x, normal n): its tet's, blended with the
// tets' around it inside the hull (shadeLocated, runtime/shade.h).
vec4 tetraprobeLookupVisibility(TetraprobeLocation loc, vec3 x, vec3 n) {
  uint probes = loc.outerCell < 0 ? tetraprobeFaceBlendProbes(loc.tet) : 0u;
  if (probes == 0u) return tetraprobeOccVisibility(loc.tet, x, n);
  // The tet's frame once, for its own data and the blend.
  TetraprobeBaryFrame frame = tetraprobeBaryFrame(loc.tet);
  vec4 vis =
      tetraprobeOccKind(loc.tet) == 0u ? vec4(1.0) : tetraprobeOccVisibilityInFrame(loc.tet, frame, x, n);
  return tetraprobeFaceBlendVisibility(loc.tet, frame, loc.weights, vis, x, n, probes);
}

#endif  // TETRAPROBE_FACE_BLEND_GLSL
