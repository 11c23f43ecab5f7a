// tetraprobe_outer_cells.glsl: the answer outside the probe hull (runtime/outer_cells.h): the extruded hull
// triangles, their cubic's smallest root, the walk across the cells.
// Part of the lookup of tetraprobe.glsl, whose contract holds here too: an engine includes tetraprobe.glsl,
// which includes this file. Permissive.
#ifndef TETRAPROBE_OUTER_CELLS_GLSL
#define TETRAPROBE_OUTER_CELLS_GLSL

#include "tetraprobe_tets.glsl"

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
  ivec4 tv = tetraprobeTetVertices(t);
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

#endif  // TETRAPROBE_OUTER_CELLS_GLSL
