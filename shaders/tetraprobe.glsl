// tetraprobe.glsl: per-pixel irradiance from a level's tetrahedral SH probes (locate tet, blend, evaluate).
// Permissive. The GLSL twin of tetraprobe::ProbeQuery (runtime/query.h): same walk, same weights, same SH.
//
// Contract
// - Positions are in the level's LOCAL frame: local = world - Level::origin (metres; the engine subtracts the
//   origin, in double, before the value reaches float). Normals are unit vectors in the same (world) axes.
// - tetraprobeIrradiance(localPos, normal) returns irradiance E in W/m^2 (RGB). Lambertian outgoing radiance
//   is albedo * E / pi. E can be slightly negative where the L2 projection rings; clamp if you need to.
// - tetraprobeLocate(localPos, hint) is ProbeQuery::locate: a walk from `hint` (a tet index, e.g. last
//   frame's tet of the object; at most TETRAPROBE_MAX_HINT_STEPS steps, used when it ends inside), else from
//   the tet named by the start brick's sub-cell holding localPos (runtime/start_bricks.h: one hash search
//   and one load; that tet holds the sub-cell's centre, so the walk takes a step or a few; for an absent
//   cell, the start-grid cell's tet; at most tetraprobeMaxWalkSteps). Each step
//   computes the four barycentric weights; when none is below -TETRAPROBE_INSIDE_EPS the point is inside
//   (within that tolerance of a face, the neighbour is taken if it holds the point better); otherwise the walk
//   moves to the neighbour opposite the most negative weight (the first one on ties). Leaving through a hull
//   face (neighbour -1; only when the point is beyond the face's plane) continues across the outer cells
//   (runtime/outer_cells.h) to the one whose extruded hull triangle holds the point: a continuous answer
//   outside the hull that does not depend on the hint (loc.outerCell names the cell). A cycle answers
//   with the visited tet holding the point best, if within TETRAPROBE_CYCLE_ACCEPT_EPS. A walk that fails
//   (its step bound, or a cycle with no tet that close) answers with the visited tet holding the point best,
//   clamped; an outer-cell walk that fails, with the visited cell holding it best. There is no O(tets) scan
//   in what ships: TETRAPROBE_DEBUG_SCAN_FALLBACK (a debug build only) compiles the CPU's scans of every tet
//   and outer cell in after a failed walk, to compare against. An empty level gives tet -1 and E = 0.
//   The CPU evaluates weights in double, the GPU in float: inside the hull both give the same field (up to
//   rounding), outside too (the outer cells' answer does not depend on the hull face the walk leaves by).
// - Bindings: the five read-only storage buffers of tetraprobe_layout.glsl in set TETRAPROBE_SET at bindings
//   TETRAPROBE_BINDING + 0..5 (defaults 0 and 0..5; define the macros before including to move them).
//   Upload them with tetraprobe::uploadLevelBuffers and bind with tetraprobe::writeLevelDescriptors
//   (runtime/vulkan_upload.h).
// - Variants: five specialization constants, constant_id TETRAPROBE_SPEC_ID + 0..4 (default 0..4), turn off
//   what a level does not use (SH band 2, plane or shadow-map occlusion, outer cells, the cell grid); the
//   driver then compiles that code out. Unspecialized, everything is on (right for any level). Specialize
//   with tetraprobe::shaderSpecialization(tetraprobe::shaderVariantFor(level, ...)) (runtime/vulkan_upload.h,
//   runtime/shader_variant.h).
// - Including: the shader that includes this file needs `#extension GL_GOOGLE_include_directive : require`
//   (glslangValidator) or shaderc, with this folder on the include path (CMake target tetraprobe_shaders).
#ifndef TETRAPROBE_GLSL
#define TETRAPROBE_GLSL

#include "tetraprobe_layout.glsl"
#include "tetraprobe_sh.glsl"

// The shader variant (tetraprobe::ShaderSpecConstant, runtime/shader_variant.h; defaults: the generic one).
#ifndef TETRAPROBE_SPEC_ID
#define TETRAPROBE_SPEC_ID 0
#endif
layout(constant_id = TETRAPROBE_SPEC_ID + 0) const int tetraprobeShOrder = 2;  // 1: coefficients 0..3 only
layout(constant_id = TETRAPROBE_SPEC_ID + 1) const bool tetraprobeUsePlanes = true;
layout(constant_id = TETRAPROBE_SPEC_ID + 2) const bool tetraprobeUseShadowMaps = true;
layout(constant_id = TETRAPROBE_SPEC_ID + 3) const bool tetraprobeUseOuterCells = true;
layout(constant_id = TETRAPROBE_SPEC_ID + 4) const bool tetraprobeUseCellGrid = true;

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

// Outer cells (runtime/lookup_constants.h: kLookupMaxOuterSteps, kLookupOuterMaxT, kGpuOuterNegligible,
// kGpuOuterZeroRoot; the root solver's thresholds in float: a term below TETRAPROBE_OUTER_NEGLIGIBLE of the
// others is dropped, roots within TETRAPROBE_OUTER_ZERO_ROOT * scale below 0 count as 0, none beyond
// TETRAPROBE_OUTER_MAX_T * scale).
#ifndef TETRAPROBE_MAX_OUTER_STEPS
#define TETRAPROBE_MAX_OUTER_STEPS 1024
#endif
#ifndef TETRAPROBE_OUTER_NEGLIGIBLE
#define TETRAPROBE_OUTER_NEGLIGIBLE 1e-6
#endif
#ifndef TETRAPROBE_OUTER_ZERO_ROOT
#define TETRAPROBE_OUTER_ZERO_ROOT 1e-6
#endif
#ifndef TETRAPROBE_OUTER_MAX_T
#define TETRAPROBE_OUTER_MAX_T 1e4
#endif

struct TetraprobeLocation {
  int tet;        // containing tet, or the outer cell's hull tet; -1 for an empty level
  vec4 weights;   // weights of tetraprobeTets[tet].v[0..3]: non-negative, sum to 1
  bool inside;    // the point lies in the tet (no weight below -TETRAPROBE_INSIDE_EPS)
  int outerCell;  // outside the hull: the outer cell holding the point (weights: its triangle's, on the
                  // hull tet's probes, 0 on the fourth); -1 inside
};

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
  ivec4 v = tetraprobeTets[t].v;
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

// --- outer cells (runtime/outer_cells.h): the answer outside the hull ---------------------------------

// The outer cell on face f of hull tet t (binary search over the (tet, face) order), or -1.
int tetraprobeFindOuterCell(int t, int f) {
  int lo = 0, hi = tetraprobeOuterCellCount;
  while (lo < hi) {
    int mid = lo + (hi - lo) / 2;
    ivec2 key = ivec2(tetraprobeOuterCells[mid].v.w, tetraprobeOuterCells[mid].link.w);
    if (key.x < t || (key.x == t && key.y < f))
      lo = mid + 1;
    else
      hi = mid;
  }
  return lo < tetraprobeOuterCellCount && tetraprobeOuterCells[lo].v.w == t &&
                 tetraprobeOuterCells[lo].link.w == f
             ? lo
             : -1;
}

// decodeOctNormal (runtime/oct_normal.h): two int16 in units of 2^-15, unfolded below the equator; exact up
// to the normalize (every value a multiple of 2^-15 in [-1, 1]), so the C++ decode agrees to a few ulp.
vec3 tetraprobeOctDecode(uint code) {
  vec2 e = vec2(float(int(code << 16u) >> 16), float(int(code) >> 16)) * (1.0 / 32768.0);
  float z = 1.0 - abs(e.x) - abs(e.y);
  if (z < 0.0) e = (1.0 - abs(e.yx)) * sign(e);
  return normalize(vec3(e, z));
}

// Unit vertex normal i (0..2) of outer cell k.
vec3 tetraprobeOuterNormal(int k, int i) {
  return tetraprobeOctDecode(tetraprobeOuterCells[k].n[i]);
}

// x strictly beyond the plane of cell k's hull triangle (outward winding).
bool tetraprobeBeyondHullFace(int k, vec3 x) {
  vec3 p0 = tetraprobeProbePosition(tetraprobeOuterCells[k].v.x);
  vec3 p1 = tetraprobeProbePosition(tetraprobeOuterCells[k].v.y);
  vec3 p2 = tetraprobeProbePosition(tetraprobeOuterCells[k].v.z);
  return dot(cross(p1 - p0, p2 - p0), x - p0) > 0.0;
}

float tetraprobeHorner(vec4 c, float t) {
  return ((c.w * t + c.z) * t + c.y) * t + c.x;
}

// Real roots of a t^2 + b t + c (a != 0) without cancellation, sorted; false when there are none.
bool tetraprobeQuadraticRoots(float a, float b, float c, out vec2 r) {
  r = vec2(0.0);
  float disc = b * b - 4.0 * a * c;
  if (disc < 0.0 || isinf(disc) || isnan(disc)) return false;
  float q = -0.5 * (b + (b < 0.0 ? -sqrt(disc) : sqrt(disc)));
  if (q == 0.0) return true;
  r = vec2(q / a, c / q);
  if (r.x > r.y) r = r.yx;
  return true;
}

// A root in [lo, hi] (f(lo), f(hi) of opposite signs): Newton steps kept in the bracket, else bisection.
float tetraprobeRefineRoot(vec4 c, float lo, float hi) {
  float flo = tetraprobeHorner(c, lo);
  float t = 0.5 * (lo + hi);
  for (int it = 0; it < 100; ++it) {
    float f = tetraprobeHorner(c, t);
    if (f == 0.0) return t;
    if ((f < 0.0) == (flo < 0.0)) {
      lo = t;
      flo = f;
    } else {
      hi = t;
    }
    if (hi - lo <= 4.0 * 1.1920929e-7 * max(abs(lo), abs(hi))) break;
    float df = (3.0 * c.w * t + 2.0 * c.z) * t + c.y;
    float next = df != 0.0 ? t - f / df : lo - 1.0;
    if (!(next > lo && next < hi)) next = 0.5 * (lo + hi);
    if (next == t) break;
    t = next;
  }
  return t;
}

float tetraprobePolish(vec4 c, float t) {
  for (int it = 0; it < 3; ++it) {
    float f = tetraprobeHorner(c, t), df = (3.0 * c.w * t + 2.0 * c.z) * t + c.y;
    if (f == 0.0 || df == 0.0) break;
    float next = t - f / df;
    if (isnan(next) || isinf(next) || !(abs(tetraprobeHorner(c, next)) < abs(f))) break;
    t = next;
  }
  return t;
}

// smallestNonNegativeRoot (outer_cells.h) in float: c = (c0, c1, c2, c3), solved in tau = t / scale.
bool tetraprobeSmallestRoot(vec4 coef, float scale, out float t) {
  t = 0.0;
  if (any(isnan(coef)) || any(isinf(coef))) return false;
  if (!(scale > 0.0) || isinf(scale)) scale = 1.0;
  if (coef.x == 0.0) return true;
  vec4 c = vec4(coef.x / (scale * scale * scale), coef.y / (scale * scale), coef.z / scale, coef.w);
  vec4 m = abs(c);
  int degree = 3;
  if (m.w <= TETRAPROBE_OUTER_NEGLIGIBLE * (m.x + m.y + m.z)) degree = 2;
  if (degree == 2 && m.z <= TETRAPROBE_OUTER_NEGLIGIBLE * (m.x + m.y)) degree = 1;
  if (degree == 1 && m.y <= TETRAPROBE_OUTER_NEGLIGIBLE * m.x) degree = 0;
  float tau = -1.0;
  if (degree == 1) {
    tau = tetraprobePolish(c, -c.x / c.y);
  } else if (degree == 2) {
    vec2 r;
    if (tetraprobeQuadraticRoots(c.z, c.y, c.x, r)) {
      float r0 = tetraprobePolish(c, r.x), r1 = tetraprobePolish(c, r.y);
      tau = r0 >= -TETRAPROBE_OUTER_ZERO_ROOT ? r0 : r1;
    }
  } else if (degree == 3) {
    if ((tetraprobeHorner(c, -TETRAPROBE_OUTER_ZERO_ROOT) < 0.0) != (c.x < 0.0)) {
      tau = 0.0;
    } else {
      float knots[4];
      int k = 0;
      knots[k++] = 0.0;
      vec2 crit;
      if (tetraprobeQuadraticRoots(3.0 * c.w, 2.0 * c.z, c.y, crit)) {
        if (crit.x > knots[k - 1] && crit.x < TETRAPROBE_OUTER_MAX_T) knots[k++] = crit.x;
        if (crit.y > knots[k - 1] && crit.y < TETRAPROBE_OUTER_MAX_T) knots[k++] = crit.y;
      }
      knots[k++] = TETRAPROBE_OUTER_MAX_T;
      float flo = c.x;
      for (int i = 0; i + 1 < k; ++i) {
        float lo = knots[i], hi = knots[i + 1], fhi = tetraprobeHorner(c, hi);
        if (flo == 0.0) {
          tau = lo;
          break;
        }
        if ((flo < 0.0) != (fhi < 0.0)) {
          tau = tetraprobeRefineRoot(c, lo, hi);
          break;
        }
        flo = fhi;
      }
    }
  }
  if (!(tau >= -TETRAPROBE_OUTER_ZERO_ROOT) || !(tau <= TETRAPROBE_OUTER_MAX_T)) return false;
  t = max(tau, 0.0) * scale;
  return true;
}

// outerCellWeights (outer_cells.h): the extrusion t and raw barycentrics of x in cell k (xyz, for v.xyz);
// `valid` false when no root t >= 0 exists (b is then the projection's, to steer a walk).
vec3 tetraprobeOuterWeights(int k, vec3 x, out bool valid) {
  vec3 p0 = tetraprobeProbePosition(tetraprobeOuterCells[k].v.x);
  vec3 p1 = tetraprobeProbePosition(tetraprobeOuterCells[k].v.y);
  vec3 p2 = tetraprobeProbePosition(tetraprobeOuterCells[k].v.z);
  vec3 n0 = tetraprobeOuterNormal(k, 0), n1 = tetraprobeOuterNormal(k, 1), n2 = tetraprobeOuterNormal(k, 2);
  precise vec3 a = p0 - p2, ad = n0 - n2, b = p1 - p2, bd = n1 - n2, y = x - p2;
  precise vec3 axb = cross(a, b), mixed = cross(a, bd) + cross(ad, b), adxbd = cross(ad, bd);
  precise vec4 c =
      vec4(dot(axb, y), dot(mixed, y) - dot(axb, n2), dot(adxbd, y) - dot(mixed, n2), -dot(adxbd, n2));
  float edge = max(max(length(a), length(b)), length(p0 - p1));
  float t;
  valid = tetraprobeSmallestRoot(c, length(y) + edge, t);
  if (!valid) t = 0.0;
  precise vec3 q0 = p0 + t * n0, q1 = p1 + t * n1, q2 = p2 + t * n2;
  precise vec3 e1 = q0 - q2, e2 = q1 - q2, yq = x - q2, nrm = cross(e1, e2);
  float nn = dot(nrm, nrm);
  if (!(nn > 0.0) || isinf(nn)) {
    valid = false;
    return vec3(1.0 / 3.0);
  }
  precise float b0 = dot(cross(yq, e2), nrm) / nn, b1 = dot(cross(e1, yq), nrm) / nn;
  return vec3(b0, b1, 1.0 - b0 - b1);
}

// Cell k's answer: its triangle weights (negatives clamped, renormalized) on the hull tet's probes.
TetraprobeLocation tetraprobeFinishOuter(int k, vec3 b) {
  int t = tetraprobeOuterCells[k].v.w;
  ivec4 tv = tetraprobeTets[t].v;
  vec4 w = vec4(0.0);
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 4; ++j)
      if (tv[j] == tetraprobeOuterCells[k].v[i]) w[j] = b[i];
  TetraprobeLocation loc = tetraprobeFinish(t, w, false);
  loc.inside = false;
  loc.outerCell = k;
  return loc;
}

#ifdef TETRAPROBE_DEBUG_SCAN_FALLBACK
// Every outer cell with a root: the one whose smallest barycentric is largest (ties: lowest index). O(cells):
// debug only.
bool tetraprobeOuterScan(vec3 x, out TetraprobeLocation loc) {
  int best = -1;
  float bestMin = 0.0;
  vec3 bestB = vec3(0.0);
  for (int k = 0; k < tetraprobeOuterCellCount; ++k) {
    bool valid;
    vec3 b = tetraprobeOuterWeights(k, x, valid);
    float m = min(min(b.x, b.y), b.z);
    if (valid && (best < 0 || m > bestMin)) {
      best = k;
      bestMin = m;
      bestB = b;
    }
  }
  if (best >= 0) loc = tetraprobeFinishOuter(best, bestB);
  return best >= 0;
}
#endif

// ProbeQuery::outerLocate: walk the outer cells from `cur` across the edge opposite the most negative
// barycentric to the cell whose extruded triangle holds x. A cycle, a missing link or the bound (where the
// CPU scans every cell) answers with the visited cell with a root that holds x best, else keeps `loc` (the
// clamped hull tet); with TETRAPROBE_DEBUG_SCAN_FALLBACK, the scan of every cell as on the CPU.
void tetraprobeOuterLocate(vec3 x, int cur, inout TetraprobeLocation loc) {
  int saved = cur;
  int power = 1, lam = 0;
  int best = -1;
  float bestMin = 0.0;
  vec3 bestB = vec3(0.0);
  for (int step = 0; step < TETRAPROBE_MAX_OUTER_STEPS && cur >= 0; ++step) {
    bool valid;
    vec3 b = tetraprobeOuterWeights(cur, x, valid);
    int m = b.y < b.x ? 1 : 0;
    if (b.z < b[m]) m = 2;
    if (valid && b[m] >= -TETRAPROBE_INSIDE_EPS) {
      loc = tetraprobeFinishOuter(cur, b);
      return;
    }
    if (valid && (best < 0 || b[m] > bestMin)) {
      best = cur;
      bestMin = b[m];
      bestB = b;
    }
    cur = tetraprobeOuterCells[cur].link[m];
    if (cur == saved) break;
    if (++lam == power) {
      saved = cur;
      power *= 2;
      lam = 0;
    }
  }
#ifdef TETRAPROBE_DEBUG_SCAN_FALLBACK
  TetraprobeLocation scanned;
  if (tetraprobeOuterScan(x, scanned)) loc = scanned;
#else
  if (best >= 0) loc = tetraprobeFinishOuter(best, bestB);
#endif
}

// --- the start bricks (runtime/start_bricks.h): the walk's start ---------------------------------------

// tetraprobe::cellHash.
uint tetraprobeCellHash(ivec3 k) {
  uint h = uint(k.x) * 0x8DA6B343u ^ uint(k.y) * 0xD8163841u ^ uint(k.z) * 0xCB1AB31Fu;
  h ^= h >> 16;
  h *= 0x7FEB352Du;
  h ^= h >> 15;
  h *= 0x846CA68Bu;
  h ^= h >> 16;
  return h;
}

// The start tet of the brick sub-cell holding local point x (a tet holding x or a few steps from it), or -1
// (no bricks, or x's cell is absent: x is outside every tet up to rounding).
int tetraprobeCellStartTet(vec3 x) {
  if (tetraprobeCellMaxProbe == 0u) return -1;
  vec3 g = (x - tetraprobeCellMin) / tetraprobeCellSize;
  vec3 f = floor(g);
  if (!(all(greaterThanEqual(f, vec3(-2e9))) && all(lessThanEqual(f, vec3(2e9))))) return -1;  // also NaN
  ivec3 key = ivec3(f);
  uint h = tetraprobeCellHash(key) & tetraprobeCellSlotMask;
  int brick = -1;
  for (uint p = 0u; p < tetraprobeCellMaxProbe; ++p) {
    int b = TETRAPROBE_CELL_SLOT_INTS * int(h);
    if (tetraprobeCellData[b] == TETRAPROBE_EMPTY_LEAF) break;
    if (tetraprobeCellData[b] == key.x && tetraprobeCellData[b + 1] == key.y &&
        tetraprobeCellData[b + 2] == key.z) {
      brick = tetraprobeCellData[b + 3];
      break;
    }
    h = (h + 1u) & tetraprobeCellSlotMask;
  }
  if (brick < 0) return -1;
  int dim = tetraprobeCellBrickDim;
  ivec3 s = ivec3(clamp((g - f) * float(dim), vec3(0.0), vec3(float(dim - 1))));
  int base = tetraprobeCellBrickOffset + dim * dim * dim * brick;
  return tetraprobeCellData[base + s.x + dim * (s.y + dim * s.z)];
}

// One walk from tet `cur` (ProbeQuery's walk()): false when it runs out of steps, or cycles (float rows can
// leave sliver faces' planes slightly apart) without any visited tet holding x within
// TETRAPROBE_CYCLE_ACCEPT_EPS; a cycle otherwise answers with the visited tet holding x best. On false, `loc`
// is that best visited tet, clamped (the shipping answer; the CPU scans instead).
// When the walk leaves through a hull face, exitFace is that face (the point is beyond its plane).
bool tetraprobeWalk(vec3 x, int cur, int maxSteps, out TetraprobeLocation loc, out int exitFace) {
  exitFace = -1;
  int saved = cur;  // Brent's cycle detection: a checkpoint moved at powers of two
  int power = 1, lam = 0;
  int best = -1;
  float bestMin = 0.0;
  vec4 bestW = vec4(0.0);
  loc = TetraprobeLocation(-1, vec4(0.0), false, -1);
  for (int step = 0; step < maxSteps; ++step) {
    vec4 w = tetraprobeWeights(cur, x);
    int m = tetraprobeMinIndex(w);
    int next = tetraprobeTets[cur].n[m];
    if (w[m] >= -TETRAPROBE_INSIDE_EPS || isnan(w[m])) {
      // Inside within tolerance; a point that close to a face may be more inside the neighbour.
      if (w[m] < 0.0 && next >= 0) {
        vec4 wn = tetraprobeWeights(next, x);
        if (wn[tetraprobeMinIndex(wn)] > w[m]) {
          loc = tetraprobeFinish(next, wn, true);
          return true;
        }
      }
      loc = tetraprobeFinish(cur, w, true);
      return true;
    }
    if (next < 0) {
      // A hull face: outside the hull if x is beyond its plane (from the probe positions; the rows cannot
      // tell within their rounding), else step across the most negative interior face, or stop here.
      int cell = tetraprobeUseOuterCells ? tetraprobeFindOuterCell(cur, m) : -1;
      if (cell < 0 || tetraprobeBeyondHullFace(cell, x)) {
        loc = tetraprobeFinish(cur, w, false);
        exitFace = m;
        return true;
      }
      int mi = -1;
      for (int i = 0; i < 4; ++i)
        if (tetraprobeTets[cur].n[i] >= 0 && (mi < 0 || w[i] < w[mi])) mi = i;
      if (mi < 0 || w[mi] >= -TETRAPROBE_INSIDE_EPS) {
        loc = tetraprobeFinish(cur, w, true);
        return true;
      }
      next = tetraprobeTets[cur].n[mi];
      m = mi;
    }
    if (best < 0 || w[m] > bestMin) {
      best = cur;
      bestMin = w[m];
      bestW = w;
    }
    cur = next;
    if (cur == saved) {  // a cycle: `best` is the best tet on it
      loc = tetraprobeFinish(best, bestW, bestMin >= -TETRAPROBE_INSIDE_EPS);
      return bestMin >= -TETRAPROBE_CYCLE_ACCEPT_EPS;
    }
    if (++lam == power) {
      saved = cur;
      power *= 2;
      lam = 0;
    }
  }
  loc = tetraprobeFinish(best, bestW, false);
  return false;
}

TetraprobeLocation tetraprobeLocate(vec3 localPos, int hint) {
  if (tetraprobeTetCount <= 0) return TetraprobeLocation(-1, vec4(0.0), false, -1);
  vec3 x = tetraprobeSanitize(localPos);
  TetraprobeLocation loc;
  int exitFace = -1;
  // A hint gets a short budget, then the start grid the full one, then the scan.
  if (hint >= 0 && hint < tetraprobeTetCount &&
      tetraprobeWalk(x, hint, TETRAPROBE_MAX_HINT_STEPS, loc, exitFace) && exitFace < 0)
    return loc;
  // The start brick names the start (the coarse start grid where the cell is absent).
  int start = tetraprobeUseCellGrid ? tetraprobeCellStartTet(x) : -1;
  if (start < 0) start = tetraprobeStartCellTet(x);
  bool walked = tetraprobeWalk(x, start, tetraprobeMaxWalkSteps, loc, exitFace);
  if (!walked) {
    // The walk's best tet, clamped (loc). Never seen on the levels tested (docs/rendering.md#variants).
#ifdef TETRAPROBE_DEBUG_SCAN_FALLBACK
    loc = tetraprobeScanAll(x);
    TetraprobeLocation outer;
    if (!loc.inside && tetraprobeOuterScan(x, outer)) loc = outer;
#endif
    return loc;
  }
  if (exitFace < 0 || !tetraprobeUseOuterCells) return loc;
  // Outside the hull: continue across the outer cells from the face the walk left through.
  int cell = tetraprobeFindOuterCell(loc.tet, exitFace);
  if (cell >= 0) tetraprobeOuterLocate(x, cell, loc);
  return loc;
}

// The coefficients the variant reads: 4 (L1) or 9 (L2).
const int tetraprobeShCount = tetraprobeShOrder >= 2 ? 9 : 4;

// tetraprobeShIrradiance (tetraprobe_sh.glsl) over the variant's coefficients: the same sum in the same
// order, without the terms an L1 level holds as 0.
vec3 tetraprobeShIrradianceVariant(vec3 c[9], vec3 n) {
  precise float y[9];
  TETRAPROBE_SH_BASIS(y, n);
  precise vec3 e = vec3(0.0);
  for (int i = 0; i < tetraprobeShCount; ++i) e += c[i] * (y[i] * tetraprobeShCosineLobe(i));
  return e;
}

// Coefficient i of probe p: three binary16 values times the probe's power-of-two scale (tetraprobe::ShHalf,
// runtime/sh_half.h: 14 uints a probe from 3 * tetraprobeProbeCount, the scale in the high half of the
// last). Exact in float, so these are the floats decodeShHalf gives the CPU.
float tetraprobeShScale(int p) {
  return unpackHalf2x16(tetraprobeProbeData[TETRAPROBE_POSITION_UINTS * tetraprobeProbeCount +
                                            TETRAPROBE_SH_UINTS * p + TETRAPROBE_SH_SCALE_UINT])
      .y;
}
vec3 tetraprobeProbeSh(int p, int i, float scale) {
  int base = TETRAPROBE_POSITION_UINTS * tetraprobeProbeCount + TETRAPROBE_SH_UINTS * p;
  int j = 3 * i;  // halves j, j + 1, j + 2; half k lives in uint k / 2, low bits for even k
  vec2 a = unpackHalf2x16(tetraprobeProbeData[base + (j >> 1)]);
  vec2 b = unpackHalf2x16(tetraprobeProbeData[base + (j >> 1) + 1]);
  vec3 h = (j & 1) == 0 ? vec3(a.x, a.y, b.x) : vec3(a.y, b.x, b.y);
  return h * scale;
}

// Blends the RGB coefficients of tet t's probes with weights w (probe 0 first, as shBlend does): the first
// tetraprobeShCount; the others are 0.
void tetraprobeBlendSh(int t, vec4 w, out vec3 c[9]) {
  ivec4 v = tetraprobeTets[t].v;
  for (int i = 0; i < 9; ++i) c[i] = vec3(0.0);
  for (int k = 0; k < 4; ++k) {
    float scale = tetraprobeShScale(v[k]);
    for (int i = 0; i < tetraprobeShCount; ++i) {
      vec3 sh = tetraprobeProbeSh(v[k], i, scale);
      precise vec3 s = c[i] + sh * w[k];
      c[i] = s;
    }
  }
}

// tetraprobeBlendSh with three weight vectors in one pass over the probes' SH (each coefficient read once):
// cw with w, cp with p, cu with u, each sum in tetraprobeBlendSh's order (the same bits).
void tetraprobeBlendSh3(int t, vec4 w, vec4 p, vec4 u, out vec3 cw[9], out vec3 cp[9], out vec3 cu[9]) {
  ivec4 v = tetraprobeTets[t].v;
  for (int i = 0; i < 9; ++i) cw[i] = cp[i] = cu[i] = vec3(0.0);
  for (int k = 0; k < 4; ++k) {
    float scale = tetraprobeShScale(v[k]);
    for (int i = 0; i < tetraprobeShCount; ++i) {
      vec3 sh = tetraprobeProbeSh(v[k], i, scale);
      precise vec3 sw = cw[i] + sh * w[k], sp = cp[i] + sh * p[k], su = cu[i] + sh * u[k];
      cw[i] = sw;
      cp[i] = sp;
      cu[i] = su;
    }
  }
}

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
  uint header = tetraprobeOccData[TETRAPROBE_OCC_RECORD_UINTS * uint(t)],
       cells = tetraprobeOccData[TETRAPROBE_OCC_RECORD_UINTS * uint(t) + 1u];
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
    float s[3] = float[3](1.0, 1.0, 1.0);
    for (uint k = 0u; k < count; ++k) {
      // Four snorm16 (OcclusionPlane::value): sign-extended, times the float nearest 1/32767 (exactly the
      // CPU's 1.0f / 32767.0f, bits 0x38000100).
      uint o = tetraprobeOccPlaneOffset + TETRAPROBE_OCC_PLANE_UINTS * (offset + k);
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
  ivec4 v = tetraprobeTets[t].v;
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
  ivec4 tv = tetraprobeTets[t].v, nbs = tetraprobeTets[t].n;
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
    ivec4 nv = tetraprobeTets[nb].v;
    precise float d = max(weights[k], 0.0) / band;
    vec4 other = vec4(1.0);
    float otherBlind = 0.0;
    precise float c = ownTrust / (ownTrust + 1.0);
    if (otherData) {
      ivec4 nn = tetraprobeTets[nb].n;
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

// Irradiance E in W/m^2 at local position localPos on a surface with unit normal `normal`. The level's
// occlusion (if any) drops the probes the point cannot see, inside the hull and (through the hull tet of the
// outer cell) outside it, blended near faces with the neighbour's (tetraprobeFaceBlendVisibility); a point
// that sees none blends into min(blend dominated by the nearest probe in front of the surface, unoccluded
// blend) per channel. Mirrors
// ProbeQuery::irradiance and occludedIrradiance (runtime/occlusion.h).
vec3 tetraprobeIrradiance(vec3 localPos, vec3 normal) {
  TetraprobeLocation loc = tetraprobeLocate(localPos, -1);
  if (loc.tet < 0) return vec3(0.0);
  vec4 w = loc.weights;
  vec3 c[9];
  if (!(tetraprobeUsePlanes || tetraprobeUseShadowMaps)) {  // a variant without occlusion: one blend
    tetraprobeBlendSh(loc.tet, w, c);
    return tetraprobeShIrradianceVariant(c, normal);
  }
  float fallback = 0.0;
  if (tetraprobeOccTetCount != 0u) {  // outside the hull too: the hull tet's occlusion (see ProbeQuery)
    w = tetraprobeOccApply(w, tetraprobeLookupVisibility(loc, localPos, normal), fallback);
  }
  // The all-occluded fallback's two blends (nearest-dominated p, unoccluded u) come from the same pass over
  // the probes' SH as the occluded one (a GPU may run both sides of the branch below).
  float unused;
  vec4 u = tetraprobeOccApply(loc.weights, vec4(1.0), unused);
  // The front factors only matter where the fallback runs (p is not used elsewhere): skip their fetches.
  vec4 front = fallback > 0.0 ? tetraprobeProbeFront(loc.tet, localPos, normal) : vec4(1.0);
  vec4 q = u * max(front, vec4(TETRAPROBE_OCC_BEHIND));
  vec4 p = q * q;
  p = p * p;
  p = p * p;
  float ps = p.x + p.y + p.z + p.w;
  p = ps > 0.0 ? p / ps : u;
  vec3 cp[9], cu[9];
  tetraprobeBlendSh3(loc.tet, w, p, u, c, cp, cu);
  vec3 e = tetraprobeShIrradianceVariant(c, normal);
  if (fallback > 0.0) {
    vec3 nearest = tetraprobeShIrradianceVariant(cp, normal);
    vec3 blend = tetraprobeShIrradianceVariant(cu, normal);
    e = (1.0 - fallback) * e + fallback * min(nearest, blend);
  }
  return e;
}

#endif  // TETRAPROBE_GLSL
