#version 450
// lighting_grid.comp: lighting.comp's full-screen pass with a regular SH L2 grid (trilinear) in place of the
// tet lookup: the `grid` method of `tetraprobe eval`, timed against the tet pass. Mirrors
// tetraprobe::GridVolume::irradiance (eval/grid_volume.h) up to float rounding.

#extension GL_GOOGLE_include_directive : require
#include "tetraprobe_sh.glsl"

layout(local_size_x = 8, local_size_y = 8) in;

// Header (48 bytes, tetraprobe::kGridHeaderBytes), then 27 floats per node (9 RGB coefficients, x fastest:
// node i + dims.x * (j + dims.y * k) at gridMin + (i, j, k) * gridStep, local frame, metres).
layout(std430, set = 0, binding = 0) readonly buffer GridVolume {
  vec4 gridMin;    // xyz: node (0, 0, 0)
  vec4 gridStep;   // xyz: node spacing per axis
  ivec4 gridDims;  // xyz: nodes per axis, each >= 2
  float gridSh[];
};

layout(set = 1, binding = 0, rgba32f) uniform readonly image2D gPosition;  // local frame; a = 1 on geometry
layout(set = 1, binding = 1, rgba32f) uniform readonly image2D gNormal;
layout(set = 1, binding = 2, rgba32f) uniform readonly image2D gAlbedo;
layout(set = 1, binding = 3, rgba32f) uniform writeonly image2D outColor;

layout(push_constant) uniform LightingPush {
  ivec2 size;  // pixels
  int mode;    // 0: irradiance E (W/m^2); 1: indirect outgoing radiance albedo * E / pi (W/(m^2 sr))
};

vec3 gridIrradiance(vec3 p, vec3 n) {
  vec3 u = clamp((p - gridMin.xyz) / gridStep.xyz, vec3(0.0), vec3(gridDims.xyz - 1));
  ivec3 i0 = min(ivec3(u), gridDims.xyz - 2);
  vec3 f = u - vec3(i0);
  vec3 c[9];
  for (int i = 0; i < 9; ++i) c[i] = vec3(0.0);
  for (int corner = 0; corner < 8; ++corner) {
    ivec3 o = ivec3(corner & 1, (corner >> 1) & 1, corner >> 2);
    vec3 t = mix(vec3(1.0) - f, f, vec3(o));
    float w = t.x * t.y * t.z;
    ivec3 q = i0 + o;
    int base = 27 * (q.x + gridDims.x * (q.y + gridDims.y * q.z));
    for (int i = 0; i < 9; ++i)
      c[i] += w * vec3(gridSh[base + 3 * i], gridSh[base + 3 * i + 1], gridSh[base + 3 * i + 2]);
  }
  return tetraprobeShIrradiance(c, n);
}

void main() {
  ivec2 px = ivec2(gl_GlobalInvocationID.xy);
  if (px.x >= size.x || px.y >= size.y) return;
  vec4 p = imageLoad(gPosition, px);
  if (p.a == 0.0) {
    imageStore(outColor, px, vec4(0.0));
    return;
  }
  vec3 n = imageLoad(gNormal, px).xyz;
  vec3 e = gridIrradiance(p.xyz, n);
  if (mode == 1) e = imageLoad(gAlbedo, px).rgb * e / 3.141592653589793;
  imageStore(outColor, px, vec4(e, 1.0));
}
