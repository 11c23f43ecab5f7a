// tetraprobe.glsl: per-pixel irradiance from a level's tetrahedral SH probes (locate tet, blend, evaluate).
// Permissive. The GLSL twin of tetraprobe::ProbeQuery (runtime/query.h): same walk, same weights, same SH.
//
// Contract
// - Positions are in the level's LOCAL frame: local = world - Level::origin (metres; the engine subtracts the
//   origin, in double, before the value reaches float). Normals are unit vectors in the same (world) axes.
// - tetraprobeIrradiance(localPos, normal) returns irradiance E in W/m^2 (RGB). Lambertian outgoing radiance
//   is albedo * E / pi. E can be slightly negative where the L2 projection rings; clamp if you need to.
// - tetraprobeLocate(localPos, hint) is ProbeQuery::locate: a walk from `hint` (a tet index, e.g. last
//   frame's tet of the object; at most TETRAPROBE_MAX_HINT_STEPS steps), else from the start-grid cell holding
//   localPos (clamped to the grid; at most tetraprobeMaxWalkSteps), else a scan of every tet. Each step
//   computes the four barycentric weights; when none is below -TETRAPROBE_INSIDE_EPS the point is inside
//   (within that tolerance of a face, the neighbour is taken if it holds the point better); otherwise the walk
//   moves to the neighbour opposite the most negative weight (the first one on ties). Leaving through a hull
//   face (neighbour -1) ends it outside the hull: weights clamped to >= 0 and renormalized. A cycle answers
//   with the visited tet holding the point best, if within TETRAPROBE_CYCLE_ACCEPT_EPS. Define
//   TETRAPROBE_NO_SCAN_FALLBACK to skip the O(tets) scan (the answer is then the walk's best tet, clamped).
//   An empty level gives tet -1 and E = 0.
//   The CPU evaluates weights in double, the GPU in float: inside the hull both give the same field (up to
//   rounding); outside, a tie float cannot resolve can send the two walks out through different hull faces.
// - Bindings: the three read-only storage buffers of tetraprobe_layout.glsl in set TETRAPROBE_SET at bindings
//   TETRAPROBE_BINDING + 0, 1, 2 (defaults 0 and 0,1,2; define the macros before including to move them).
//   Upload them with tetraprobe::uploadLevelBuffers and bind with tetraprobe::writeLevelDescriptors
//   (runtime/vulkan_upload.h).
// - Including: the shader that includes this file needs `#extension GL_GOOGLE_include_directive : require`
//   (glslangValidator) or shaderc, with this folder on the include path (CMake target tetraprobe_shaders).
#ifndef TETRAPROBE_GLSL
#define TETRAPROBE_GLSL

#include "tetraprobe_layout.glsl"
#include "tetraprobe_sh.glsl"

// The CPU query's constants (runtime/src/query.cpp: kInsideEps, kCycleAcceptEps, kMaxHintSteps).
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
  int tet;       // containing tet, or the hull tet the answer was clamped in; -1 for an empty level
  vec4 weights;  // weights of tetraprobeTets[tet].v[0..3]: non-negative, sum to 1
  bool inside;   // the point lies in the tet (no weight below -TETRAPROBE_INSIDE_EPS)
};

// Raw barycentric weights of local point p in tet t (may be negative outside): the row formula of
// tetraprobe::Tet, summed in the CPU's order.
vec4 tetraprobeWeights(int t, vec3 p) {
  precise vec4 w;
  for (int i = 0; i < 3; ++i) {
    vec4 r = tetraprobeTets[t].row[i];
    w[i] = r.x * p.x + r.y * p.y + r.z * p.z + r.w;
  }
  w[3] = 1.0 - w[0] - w[1] - w[2];
  return w;
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

// Every tet scanned: the one whose smallest weight is largest (ties: lowest index). The walk's fallback.
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

// One walk from tet `cur` (ProbeQuery's walk()): false when it runs out of steps, or cycles (float rows can
// leave sliver faces' planes slightly apart) without any visited tet holding x within
// TETRAPROBE_CYCLE_ACCEPT_EPS; a cycle otherwise answers with the visited tet holding x best. On false, `loc`
// is that best visited tet, clamped (used only with TETRAPROBE_NO_SCAN_FALLBACK).
bool tetraprobeWalk(vec3 x, int cur, int maxSteps, out TetraprobeLocation loc) {
  int saved = cur;  // Brent's cycle detection: a checkpoint moved at powers of two
  int power = 1, lam = 0;
  int best = -1;
  float bestMin = 0.0;
  vec4 bestW = vec4(0.0);
  loc = TetraprobeLocation(-1, vec4(0.0), false);
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
    if (next < 0) {  // left through a hull face: outside the hull
      loc = tetraprobeFinish(cur, w, false);
      return true;
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
  if (tetraprobeTetCount <= 0) return TetraprobeLocation(-1, vec4(0.0), false);
  vec3 x = tetraprobeSanitize(localPos);
  TetraprobeLocation loc;
  // A hint gets a short budget, then the start grid the full one, then the scan.
  if (hint >= 0 && hint < tetraprobeTetCount && tetraprobeWalk(x, hint, TETRAPROBE_MAX_HINT_STEPS, loc)) return loc;
  if (tetraprobeWalk(x, tetraprobeStartCellTet(x), tetraprobeMaxWalkSteps, loc)) return loc;
#ifdef TETRAPROBE_NO_SCAN_FALLBACK
  return loc;
#else
  return tetraprobeScanAll(x);
#endif
}

// Blends the 9 RGB coefficients of tet t's probes with weights w (probe 0 first, as shBlend does).
void tetraprobeBlendSh(int t, vec4 w, out vec3 c[9]) {
  ivec4 v = tetraprobeTets[t].v;
  for (int i = 0; i < 9; ++i) c[i] = vec3(0.0);
  for (int k = 0; k < 4; ++k) {
    int base = 27 * v[k];
    for (int i = 0; i < 9; ++i) {
      int o = base + 3 * i;
      precise vec3 s = c[i] + vec3(tetraprobeSh[o], tetraprobeSh[o + 1], tetraprobeSh[o + 2]) * w[k];
      c[i] = s;
    }
  }
}

// Irradiance E in W/m^2 at local position localPos on a surface with unit normal `normal`.
vec3 tetraprobeIrradiance(vec3 localPos, vec3 normal) {
  TetraprobeLocation loc = tetraprobeLocate(localPos, -1);
  if (loc.tet < 0) return vec3(0.0);
  vec3 c[9];
  tetraprobeBlendSh(loc.tet, loc.weights, c);
  return tetraprobeShIrradiance(c, normal);
}

#endif  // TETRAPROBE_GLSL
