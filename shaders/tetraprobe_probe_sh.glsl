// tetraprobe_probe_sh.glsl: the probes' half-precision SH blended with a tet's weights, over the variant's
// coefficients.
// Part of the lookup of tetraprobe.glsl, whose contract holds here too: an engine includes tetraprobe.glsl,
// which includes this file. Permissive.
#ifndef TETRAPROBE_PROBE_SH_GLSL
#define TETRAPROBE_PROBE_SH_GLSL

#include "tetraprobe_sh.glsl"
#include "tetraprobe_tets.glsl"

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
  ivec4 v = tetraprobeTetVertices(t);
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
  ivec4 v = tetraprobeTetVertices(t);
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

#endif  // TETRAPROBE_PROBE_SH_GLSL
