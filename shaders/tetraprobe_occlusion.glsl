// tetraprobe_occlusion.glsl: per-tet occlusion (runtime/occlusion.h): planes, shadow maps, the bias off a
// surface, the fallback share.
// Part of the lookup of tetraprobe.glsl, whose contract holds here too: an engine includes tetraprobe.glsl,
// which includes this file. Permissive.
#ifndef TETRAPROBE_OCCLUSION_GLSL
#define TETRAPROBE_OCCLUSION_GLSL

#include "tetraprobe_tets.glsl"

// --- occlusion: mirrors runtime/src/occlusion.cpp (evaluateTetOcclusion, biasWeights, applyOcclusion) ---
const float TETRAPROBE_OCC_BIAS = 0.03, TETRAPROBE_OCC_PLANE_HALF = 0.02, TETRAPROBE_OCC_SHADOW_HALF = 0.01,
            TETRAPROBE_OCC_FALLBACK = 1e-2, TETRAPROBE_OCC_FRONT_SINE = 0.02, TETRAPROBE_OCC_BEHIND = 1e-3;

float tetraprobeOccSmooth(float e0, float e1, float x) {  // as the CPU's smoothStep, operation for operation
  precise float t = clamp((x - e0) / (e1 - e0), 0.0, 1.0);
  precise float r = t * t * (3.0 - 2.0 * t);
  return r;
}

vec4 tetraprobeOccBias(TetraprobeBaryFrame f, vec4 w, vec3 n) {
  vec3 g0 = f.g[0], g1 = f.g[1], g2 = f.g[2];
  precise vec3 gs = g0 + g1 + g2;
  precise vec4 gn = vec4(dot(g0, n), dot(g1, n), dot(g2, n), -dot(gs, n));
  float m = max(max(abs(gn.x), abs(gn.y)), max(abs(gn.z), abs(gn.w)));
  if (!(m > 0.0) || isinf(m) || isnan(m)) return w;
  precise vec4 r = w + gn * (TETRAPROBE_OCC_BIAS / m);
  return r;
}

uint tetraprobeOccByte(uint word0, uint k) {
  return (tetraprobeOccData[word0 + k / 4u] >> (8u * (k % 4u))) & 0xFFu;
}
uint tetraprobeOccVertex(int a, int b) {
  return uint(b * 5 - b * (b - 1) / 2 + a);
}

float tetraprobeOccDepth(uint word0, float u, float v) {  // word0: the probe's first uint; > 1: nothing met
  u = (isnan(u) || isinf(u)) ? 0.0 : clamp(u, 0.0, 1.0);
  v = (isnan(v) || isinf(v)) ? 0.0 : clamp(v, 0.0, 1.0);
  if (u + v > 1.0) {
    precise float s = u + v;
    u /= s;
    v /= s;
  }
  precise float x = 4.0 * u, y = 4.0 * v;
  int iu = min(int(x), 3), iv = min(int(y), 3);
  bool upper = (x - float(iu)) + (y - float(iv)) > 1.0;
  if (iu + iv >= 3) {
    iu = min(iu, 3 - iv);
    upper = false;
  }
  precise float fu = 4.0 * u - float(iu), fv = 4.0 * v - float(iv);
  uint corner[3];
  precise float b[3];
  if (upper) {
    corner[0] = tetraprobeOccVertex(iu + 1, iv + 1);
    b[0] = fu + fv - 1.0;
    corner[1] = tetraprobeOccVertex(iu, iv + 1);
    b[1] = 1.0 - fu;
    corner[2] = tetraprobeOccVertex(iu + 1, iv);
    b[2] = 1.0 - fv;
  } else {
    corner[0] = tetraprobeOccVertex(iu, iv);
    b[0] = 1.0 - fu - fv;
    corner[1] = tetraprobeOccVertex(iu + 1, iv);
    b[1] = fu;
    corner[2] = tetraprobeOccVertex(iu, iv + 1);
    b[2] = fv;
  }
  precise float inv = 0.0, sum = 0.0;
  bool anyHit = false;
  for (int k = 0; k < 3; ++k) {
    b[k] = max(b[k], 0.0);
    sum = sum + b[k];
    uint q = tetraprobeOccByte(word0, corner[k]);
    anyHit = anyHit || q != TETRAPROBE_SHADOW_NO_HIT;
    precise float d = q == TETRAPROBE_SHADOW_NO_HIT ? 1.0 : max(float(q), 0.5) / TETRAPROBE_SHADOW_SCALE;
    inv = inv + b[k] / d;
  }
  if (!anyHit) return 2.0;
  precise float r = sum > 0.0 ? sum / inv : 1.0;
  return r;
}

// The occlusion kind tet t stores (0 none, 1 planes, 2 shadow maps; 0 past the records).
uint tetraprobeOccKind(int t) {
  return (t >= 0 && uint(t) < tetraprobeOccTetCount)
             ? (tetraprobeOccData[TETRAPROBE_OCC_RECORD_UINTS * uint(t)] & 3u)
             : 0u;
}

// Per-probe visibility of tet t's probes from local point x with surface normal n, `frame` being t's
// tetraprobeBaryFrame (occlusionVisibility with the frame given).
vec4 tetraprobeOccVisibilityInFrame(int t, TetraprobeBaryFrame frame, vec3 x, vec3 n) {
  if (tetraprobeOccTetCount == 0u || t < 0 || uint(t) >= tetraprobeOccTetCount) return vec4(1.0);
  uint header = tetraprobeOccData[TETRAPROBE_OCC_RECORD_UINTS * uint(t)];
  uint kind = header & 3u, count = (header >> 2) & 3u, offset = header >> TETRAPROBE_OCC_OFFSET_SHIFT;
  if (!(kind == TETRAPROBE_OCC_KIND_PLANES && tetraprobeUsePlanes) &&
      !(kind == TETRAPROBE_OCC_KIND_SHADOW_MAPS && tetraprobeUseShadowMaps))
    return vec4(1.0);
  vec4 w = tetraprobeBaryWeights(frame, x);
  if (isnan(n.x) || isnan(n.y) || isnan(n.z) || isinf(n.x) || isinf(n.y) || isinf(n.z)) n = vec3(0.0);
  w = tetraprobeOccBias(frame, w, n);
  vec4 vis = vec4(1.0);
  if (tetraprobeUsePlanes && kind == TETRAPROBE_OCC_KIND_PLANES) {
    if (count == 0u) return vec4(1.0);
    uint block = tetraprobeOccPlaneOffset + offset;  // the cells word, then the planes
    uint cells = tetraprobeOccData[block];
    float s[3] = float[3](1.0, 1.0, 1.0);
    for (uint k = 0u; k < count; ++k) {
      // Four snorm16 (OcclusionPlane::value): sign-extended, times the float nearest 1/32767 (exactly the
      // CPU's 1.0f / 32767.0f, bits 0x38000100).
      uint o = block + 1u + TETRAPROBE_OCC_PLANE_UINTS * k;
      int a = int(tetraprobeOccData[o]), b = int(tetraprobeOccData[o + 1u]);
      vec4 c = vec4(ivec4(bitfieldExtract(a, 0, 16), bitfieldExtract(a, 16, 16), bitfieldExtract(b, 0, 16),
                          bitfieldExtract(b, 16, 16))) *
               TETRAPROBE_OCC_PLANE_UNIT;
      precise float d = c.x * w.x + c.y * w.y + c.z * w.z + c.w * w.w;
      s[k] = tetraprobeOccSmooth(-TETRAPROBE_OCC_PLANE_HALF, TETRAPROBE_OCC_PLANE_HALF, d);
    }
    precise vec4 acc = vec4(0.0);
    for (uint cell = 0u; cell < (1u << count); ++cell) {
      precise float wt = 1.0;
      for (uint k = 0u; k < count; ++k) wt = wt * ((((cell >> k) & 1u) != 0u) ? s[k] : 1.0 - s[k]);
      uint mask = (cells >> (4u * cell)) & 15u;
      for (int i = 0; i < 4; ++i) acc[i] = acc[i] + ((((mask >> uint(i)) & 1u) != 0u) ? wt : 0.0);
    }
    vis = clamp(acc, 0.0, 1.0);
  } else if (tetraprobeUseShadowMaps) {
    uint block = tetraprobeOccShadowOffset + TETRAPROBE_SHADOW_BLOCK_UINTS * offset;
    for (int i = 0; i < 4; ++i) {
      int j0 = i == 0 ? 1 : 0, j1 = i <= 1 ? 2 : 1, j2 = i <= 2 ? 3 : 2;
      float a = max(w[j0], 0.0), b = max(w[j1], 0.0), c = max(w[j2], 0.0);
      precise float sum = a + b + c;
      precise float u = sum > 0.0 ? b / sum : 1.0 / 3.0, v = sum > 0.0 ? c / sum : 1.0 / 3.0;
      float depth = tetraprobeOccDepth(block + TETRAPROBE_SHADOW_PROBE_UINTS * uint(i), u, v);
      if (depth > 1.0) continue;
      precise float f = 1.0 - w[i];
      precise float lo = depth - TETRAPROBE_OCC_SHADOW_HALF, hi = depth + TETRAPROBE_OCC_SHADOW_HALF;
      vis[i] = 1.0 - tetraprobeOccSmooth(lo, hi, f);
    }
  }
  if (any(isnan(vis)) || any(isinf(vis))) return vec4(1.0);
  return vis;
}

// Per-probe visibility of tet t's probes from local point x with surface normal n (occlusionVisibility).
vec4 tetraprobeOccVisibility(int t, vec3 x, vec3 n) {
  if (tetraprobeOccKind(t) == 0u) return vec4(1.0);
  return tetraprobeOccVisibilityInFrame(t, tetraprobeBaryFrame(t), x, n);
}

// applyOcclusion: weights * visibility renormalized (the sanitized weights when nothing is visible);
// `fallback` = the fallback's share, 1 - s / TETRAPROBE_OCC_FALLBACK below it, else 0.
vec4 tetraprobeOccApply(vec4 weights, vec4 visibility, out float fallback) {
  fallback = 0.0;
  precise vec4 w, v;
  precise float sumW = 0.0;
  for (int i = 0; i < 4; ++i) {
    w[i] = (!isnan(weights[i]) && !isinf(weights[i]) && weights[i] > 0.0) ? weights[i] : 0.0;
    v[i] = (!isnan(visibility[i]) && !isinf(visibility[i])) ? clamp(visibility[i], 0.0, 1.0) : 1.0;
    sumW = sumW + w[i];
  }
  if (!(sumW > 0.0) || isinf(sumW)) return vec4(0.25);
  w = w / sumW;
  precise vec4 o = w * v;
  precise float s = o.x + o.y + o.z + o.w;
  if (s < TETRAPROBE_OCC_FALLBACK) fallback = 1.0 - s / TETRAPROBE_OCC_FALLBACK;
  return s > 0.0 ? o / s : w;
}

// probeFront (runtime/occlusion.h): per probe of tet t, 1 when it lies in front of the surface at x (rising at
// least TETRAPROBE_OCC_FRONT_SINE above its plane), 0 on or behind it, linear between; 1 for a zero normal.
vec4 tetraprobeProbeFront(int t, vec3 x, vec3 n) {
  ivec4 v = tetraprobeTetVertices(t);
  vec4 front = vec4(1.0);
  float nl = length(n);
  for (int i = 0; i < 4; ++i) {
    precise vec3 d = tetraprobeProbePosition(v[i]) - x;
    precise float scale = TETRAPROBE_OCC_FRONT_SINE * length(d) * nl;
    precise float f = tetraprobeDot(d, n) / scale;
    if (scale > 0.0 && !isnan(f) && !isinf(f)) front[i] = clamp(f, 0.0, 1.0);
  }
  return front;
}

#endif  // TETRAPROBE_OCCLUSION_GLSL
