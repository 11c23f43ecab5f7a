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

// How blind a side is by its own visibility: 1 - smoothstep(0, TETRAPROBE_FACE_BLIND_SUM, visible sum).
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
float tetraprobeFaceTrust(float blind) {  // c: the trust in a side
  return 1.0 - (1.0 - TETRAPROBE_FACE_TRUST) * blind;
}

// Tet t's visibility `vis` of its probes at x, blended near each face with the neighbour's visibility of
// the face's probes, so that both sides of a face use the same numbers.
vec4 tetraprobeFaceBlendVisibility(int t, vec4 weights, vec4 vis, vec3 x, vec3 n) {
  // The faces whose blend may change anything (faceBlendMask, set at upload); none: nothing to do.
  if (t < 0 || uint(t) >= tetraprobeOccTetCount) return vis;
  uint header = tetraprobeOccData[TETRAPROBE_OCC_RECORD_UINTS * uint(t)];
  uint flags = (header >> TETRAPROBE_OCC_FACE_MASK_SHIFT) & 15u;
  if (flags == 0u) return vis;
  ivec4 tv = tetraprobeTetVertices(t), nbs = tetraprobeTetNeighbours(t);
  bool ownData = (header & 3u) != 0u;
  vec4 o = vis;
  float ownBlind = tetraprobeFaceBlindness(weights, vis);
  float ownTrust = tetraprobeFaceTrust(ownBlind);
  precise float band =
      TETRAPROBE_FACE_BAND + (TETRAPROBE_FACE_FALLBACK_BAND - TETRAPROBE_FACE_BAND) * ownBlind;
  // The faces to consult first (cheap tests), then the costly part once per listed face: a SIMD lane group
  // runs as many iterations as its busiest pixel has faces, not four.
  int faces[4];
  int count = 0;
  for (int k = 0; k < 4; ++k) {
    int nb = nbs[k];
    if (!(weights[k] < band) || ((flags >> uint(k)) & 1u) == 0u) continue;  // a flag: nb >= 0
    if (tetraprobeOccKind(nb) ==
        0u) {  // the neighbour sees every probe: nothing to blend where this tet does too
      bool allSeen = true;
      for (int i = 0; i < 4; ++i) allSeen = allSeen && (i == k || vis[i] == 1.0);
      if (!ownData || allSeen) continue;
    }
    faces[count++] = k;
  }
  if (count == 0) return vis;
  // A probe behind the surface is not raised above the lower side's visibility (unless a side sees nothing).
  vec4 front = tetraprobeProbeFront(t, x, n);
  for (int q = 0; q < count; ++q) {
    int k = faces[q];
    int nb = nbs[k];
    bool otherData = tetraprobeOccKind(nb) != 0u;
    ivec4 nv = tetraprobeTetVertices(nb);
    precise float d = max(weights[k], 0.0) / band;
    vec4 other = vec4(1.0);
    float otherBlind = 0.0;
    precise float c = ownTrust / (ownTrust + 1.0);
    if (otherData) {
      ivec4 nn = tetraprobeTetNeighbours(nb);
      int m = 0;
      while (m < 4 && nn[m] != t) ++m;
      if (m == 4) continue;
      TetraprobeBaryFrame f = tetraprobeBaryFrame(nb);
      vec4 w = tetraprobeBaryWeights(f, x);
      d = max(d, -w[m] / band);
      if (!(d < 1.0)) continue;
      other = tetraprobeOccVisibilityInFrame(nb, f, x, n);
      otherBlind = tetraprobeFaceBlindness(w, other);
      c = ownTrust / (ownTrust + tetraprobeFaceTrust(otherBlind));
    }
    if (!(d < 1.0)) continue;
    precise float a = 1.0 - d * d * (3.0 - 2.0 * d);
    float anyBlind = max(ownBlind, otherBlind);
    for (int i = 0; i < 4; ++i) {
      if (i == k) continue;
      int j = 0;
      while (j < 4 && nv[j] != tv[i]) ++j;
      if (j == 4) continue;
      precise float target =
          min(c * vis[i] + (1.0 - c) * other[j], max(max(min(vis[i], other[j]), front[i]), anyBlind));
      precise float r = o[i] + a * (target - vis[i]);
      o[i] = r;
    }
  }
  return clamp(o, 0.0, 1.0);
}

// The visibility the lookup uses at located point loc (local x, normal n): its tet's, blended near faces
// with the neighbours' inside the hull (shadeLocated, runtime/shade.h).
vec4 tetraprobeLookupVisibility(TetraprobeLocation loc, vec3 x, vec3 n) {
  vec4 vis = tetraprobeOccVisibility(loc.tet, x, n);
  if (loc.outerCell < 0) vis = tetraprobeFaceBlendVisibility(loc.tet, loc.weights, vis, x, n);
  return vis;
}

#endif  // TETRAPROBE_FACE_BLEND_GLSL
