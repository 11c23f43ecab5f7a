// tetraprobe_locate.glsl: point location (ProbeQuery::locate): the start bricks (runtime/start_bricks.h), the
// walk, tetraprobeLocate.
// Part of the lookup of tetraprobe.glsl, whose contract holds here too: an engine includes tetraprobe.glsl,
// which includes this file. Permissive.
#ifndef TETRAPROBE_LOCATE_GLSL
#define TETRAPROBE_LOCATE_GLSL

#include "tetraprobe_outer_cells.glsl"

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
  // Start tets packed at the tets' neighbour width (tetraprobeTetNb) from tetraprobeCellBrickOffset.
  uint e = uint(dim * dim * dim * brick + s.x + dim * (s.y + dim * s.z)), nb = tetraprobeTetNb();
  uint bit = e * nb, w = uint(tetraprobeCellBrickOffset) + (bit >> 5u), sh = bit & 31u;
  uint v = (uint(tetraprobeCellData[w]) >> sh) | ((uint(tetraprobeCellData[w + 1u]) << 1u) << (31u - sh));
  return int(v & tetraprobeTetMask(nb));
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
    int next = tetraprobeTetNeighbour(cur, m);
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
        if (tetraprobeTetNeighbour(cur, i) >= 0 && (mi < 0 || w[i] < w[mi])) mi = i;
      if (mi < 0 || w[mi] >= -TETRAPROBE_INSIDE_EPS) {
        loc = tetraprobeFinish(cur, w, true);
        return true;
      }
      next = tetraprobeTetNeighbour(cur, mi);
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

// tetraprobeLocate with the hint's walk bounded by hintSteps (> 0) instead of TETRAPROBE_MAX_HINT_STEPS: for
// hints that are usually right or far off, such as last frame's tet of a pixel (a disoccluded pixel's hint
// belongs to another surface; a short budget gives it up quickly). The answer does not depend on the budget
// beyond the choice between two tets holding a point on their shared face.
TetraprobeLocation tetraprobeLocateWithin(vec3 localPos, int hint, int hintSteps) {
  if (tetraprobeTetCount <= 0) return TetraprobeLocation(-1, vec4(0.0), false, -1);
  vec3 x = tetraprobeSanitize(localPos);
  TetraprobeLocation loc;
  int exitFace = -1;
  // A hint gets a short budget, then the start grid the full one, then the scan.
  if (hint >= 0 && hint < tetraprobeTetCount && tetraprobeWalk(x, hint, hintSteps, loc, exitFace) &&
      exitFace < 0)
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

TetraprobeLocation tetraprobeLocate(vec3 localPos, int hint) {
  return tetraprobeLocateWithin(localPos, hint, TETRAPROBE_MAX_HINT_STEPS);
}

#endif  // TETRAPROBE_LOCATE_GLSL
