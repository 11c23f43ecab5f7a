// tetraprobe_tets.glsl: the located point, probe positions, a tet's barycentric weights, the start grid
// (runtime/query.h).
// Part of the lookup of tetraprobe.glsl, whose contract holds here too: an engine includes tetraprobe.glsl,
// which includes this file. Permissive.
#ifndef TETRAPROBE_TETS_GLSL
#define TETRAPROBE_TETS_GLSL

#include "tetraprobe_layout.glsl"
#include "tetraprobe_variant.glsl"

// The CPU query's constants (runtime/lookup_constants.h: kLookupInsideEps, kLookupCycleAcceptEps,
// kLookupMaxHintSteps).
#ifndef TETRAPROBE_INSIDE_EPS
#define TETRAPROBE_INSIDE_EPS 1e-6
#endif
#ifndef TETRAPROBE_CYCLE_ACCEPT_EPS
#define TETRAPROBE_CYCLE_ACCEPT_EPS 1e-4
#endif
#ifndef TETRAPROBE_MAX_HINT_STEPS
#define TETRAPROBE_MAX_HINT_STEPS 256
#endif

struct TetraprobeLocation {
  int tet;        // containing tet, or the outer cell's hull tet; -1 for an empty level
  vec4 weights;   // weights of tetraprobeTetVertices(tet)[0..3]: non-negative, sum to 1
  bool inside;    // the point lies in the tet (no weight below -TETRAPROBE_INSIDE_EPS)
  int outerCell;  // outside the hull: the outer cell holding the point (weights: its triangle's, on the
                  // hull tet's probes, 0 on the fourth); -1 inside
};

// The `width`-bit field (1..32) at bit `bit` of the tet record starting at uint `base` (gpu_tets.h getBits),
// without a branch: the next word is always read (the zero tail keeps that in the buffer) and shifted in by
// two steps, so a field that does not straddle gets nothing from it.
uint tetraprobeTetField(uint base, uint bit, uint mask) {
  uint w = base + (bit >> 5u), s = bit & 31u;
  return ((tetraprobeTetData[w] >> s) | ((tetraprobeTetData[w + 1u] << 1u) << (31u - s))) & mask;
}

uint tetraprobeTetMask(uint width) {
  return width >= 32u ? 0xffffffffu : (1u << width) - 1u;
}

// The packing: the specialization constants when set (folded by the driver), else the buffer's header.
uint tetraprobeTetVb() {
  return tetraprobeSpecTetVertexBits != 0u ? tetraprobeSpecTetVertexBits : tetraprobeTetVertexBits;
}
uint tetraprobeTetNb() {
  return tetraprobeSpecTetNeighbourBits != 0u ? tetraprobeSpecTetNeighbourBits : tetraprobeTetNeighbourBits;
}
uint tetraprobeTetBase(int t) {
  return uint(t) * (tetraprobeSpecTetStride != 0u ? tetraprobeSpecTetStride : tetraprobeTetStride);
}

// Tet t's four probe indices (tetraprobe::Tet::v).
ivec4 tetraprobeTetVertices(int t) {
  uint base = tetraprobeTetBase(t), vb = tetraprobeTetVb(), mask = tetraprobeTetMask(vb);
  return ivec4(int(tetraprobeTetField(base, 0u, mask)), int(tetraprobeTetField(base, vb, mask)),
               int(tetraprobeTetField(base, 2u * vb, mask)), int(tetraprobeTetField(base, 3u * vb, mask)));
}

// The tet across tet t's face opposite v[i] (tetraprobe::Tet::n), -1 on the hull.
int tetraprobeTetNeighbour(int t, int i) {
  uint nb = tetraprobeTetNb();
  return int(tetraprobeTetField(tetraprobeTetBase(t), 4u * tetraprobeTetVb() + uint(i) * nb,
                                tetraprobeTetMask(nb))) -
         1;
}

ivec4 tetraprobeTetNeighbours(int t) {
  return ivec4(tetraprobeTetNeighbour(t, 0), tetraprobeTetNeighbour(t, 1), tetraprobeTetNeighbour(t, 2),
               tetraprobeTetNeighbour(t, 3));
}

// Probe p's position (local frame, metres).
vec3 tetraprobeProbePosition(int p) {
  return uintBitsToFloat(uvec3(tetraprobeProbeData[TETRAPROBE_POSITION_UINTS * p],
                               tetraprobeProbeData[TETRAPROBE_POSITION_UINTS * p + 1],
                               tetraprobeProbeData[TETRAPROBE_POSITION_UINTS * p + 2]));
}

// tetraprobe::BaryFrame (level.h): w_i = dot(g[i], X - origin) for i = 0..2, w_3 = 1 - the others, from the
// tet's probe positions, operation for operation as baryFrame() / baryWeights() (runtime/src/bary_frame.cpp).
struct TetraprobeBaryFrame {
  vec3 origin;
  vec3 g[3];
};

vec3 tetraprobeCross(vec3 a, vec3 b) {
  precise vec3 c = vec3(a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x);
  return c;
}
float tetraprobeDot(vec3 a, vec3 b) {
  precise float d = (a.x * b.x + a.y * b.y) + a.z * b.z;
  return d;
}

TetraprobeBaryFrame tetraprobeBaryFrame(int t) {
  ivec4 v = tetraprobeTetVertices(t);
  vec3 p3 = tetraprobeProbePosition(v.w);
  precise vec3 e0 = tetraprobeProbePosition(v.x) - p3, e1 = tetraprobeProbePosition(v.y) - p3,
               e2 = tetraprobeProbePosition(v.z) - p3;
  vec3 c0 = tetraprobeCross(e1, e2), c1 = tetraprobeCross(e2, e0), c2 = tetraprobeCross(e0, e1);
  precise float inv = 1.0 / tetraprobeDot(e0, c0);
  TetraprobeBaryFrame f;
  f.origin = p3;
  precise vec3 g0 = c0 * inv, g1 = c1 * inv, g2 = c2 * inv;
  f.g[0] = g0;
  f.g[1] = g1;
  f.g[2] = g2;
  return f;
}

vec4 tetraprobeBaryWeights(TetraprobeBaryFrame f, vec3 x) {
  precise vec3 d = x - f.origin;
  precise vec4 w;
  w[0] = tetraprobeDot(f.g[0], d);
  w[1] = tetraprobeDot(f.g[1], d);
  w[2] = tetraprobeDot(f.g[2], d);
  w[3] = ((1.0 - w[0]) - w[1]) - w[2];
  return w;
}

// Raw barycentric weights of local point p in tet t (may be negative outside).
vec4 tetraprobeWeights(int t, vec3 p) {
  return tetraprobeBaryWeights(tetraprobeBaryFrame(t), p);
}

// Index of the smallest weight (the first one on ties).
int tetraprobeMinIndex(vec4 w) {
  int m = 0;
  for (int i = 1; i < 4; ++i)
    if (w[i] < w[m]) m = i;
  return m;
}

// Clamps to >= 0 and renormalizes; a degenerate sum (all clamped away, or non-finite) gives equal weights.
TetraprobeLocation tetraprobeFinish(int t, vec4 w, bool inside) {
  precise vec4 c;
  for (int i = 0; i < 4; ++i) c[i] = w[i] > 0.0 ? w[i] : 0.0;  // NaN -> 0
  precise float s = c[0] + c[1] + c[2] + c[3];
  TetraprobeLocation loc;
  loc.tet = t;
  loc.inside = inside;
  loc.outerCell = -1;
  if (!(s > 0.0) || isinf(s)) {
    loc.weights = vec4(0.25);
    loc.inside = false;
  } else {
    loc.weights = c / s;
  }
  return loc;
}

// Upper corner of the start grid.
vec3 tetraprobeGridMax() {
  return tetraprobeGridMin + tetraprobeGridCellSize * vec3(tetraprobeGridDims);
}

// A point with a defined answer for any input: NaN components go to the grid's centre, +-Inf to its
// bounds, and points absurdly far away are pulled radially to 1e6 grid diagonals from the centre.
vec3 tetraprobeSanitize(vec3 x) {
  vec3 lo = tetraprobeGridMin, hi = tetraprobeGridMax();
  vec3 centre = 0.5 * (lo + hi);
  for (int a = 0; a < 3; ++a) {
    if (isnan(x[a])) x[a] = centre[a];
    if (isinf(x[a])) x[a] = x[a] > 0.0 ? hi[a] : lo[a];
  }
  float maxRadius = 1e6 * (length(hi - lo) + 1.0);
  vec3 d = x - centre;
  float far = max(max(abs(d.x), abs(d.y)), abs(d.z));
  if (far > maxRadius) {
    vec3 dir = d / far;  // scaled first: |d|^2 could overflow
    x = centre + dir * (maxRadius / length(dir));
  }
  return x;
}

// The start-grid cell's tet for local point p (cells clamped to the grid).
int tetraprobeStartCellTet(vec3 p) {
  ivec3 dims = tetraprobeGridDims;
  vec3 f = floor((p - tetraprobeGridMin) / tetraprobeGridCellSize);
  ivec3 c = ivec3(clamp(f, vec3(0.0), vec3(dims - 1)));  // clamp in float: no overflowing int conversion
  return tetraprobeStartTet[c.x + dims.x * (c.y + dims.y * c.z)];
}

#ifdef TETRAPROBE_DEBUG_SCAN_FALLBACK
// Every tet scanned: the one whose smallest weight is largest (ties: lowest index). O(tets): debug only.
TetraprobeLocation tetraprobeScanAll(vec3 x) {
  int best = -1;
  float bestMin = 0.0;
  vec4 bestW = vec4(0.25);
  for (int t = 0; t < tetraprobeTetCount; ++t) {
    vec4 w = tetraprobeWeights(t, x);
    float m = w[tetraprobeMinIndex(w)];
    if (best < 0 || m > bestMin) {
      best = t;
      bestMin = m;
      bestW = w;
    }
  }
  return tetraprobeFinish(best, bestW, bestMin >= -TETRAPROBE_INSIDE_EPS);
}
#endif

#endif  // TETRAPROBE_TETS_GLSL
