#version 450
// lighting_grid_texture.comp: lighting_grid.comp with the SH L2 grid in seven 3D textures read with hardware
// trilinear filtering (what an engine's irradiance volume does), timed against the tet lookup by
// `tetraprobe bench render`. Texture j holds floats 4j..4j+3 of a node's 27 (coefficient-major, then r, g, b;
// the 28th is 0); texel (i, j, k) is node i + dims.x * (j + dims.y * k). The filter's weights have the
// device's sub-texel precision (8 bits on lavapipe), so values differ from lighting_grid.comp's by that.

#extension GL_GOOGLE_include_directive : require
#include "tetraprobe_sh.glsl"

layout(local_size_x = 8, local_size_y = 8) in;

layout(set = 3, binding = 0) uniform sampler3D gridTextures[7];  // linear filter, clamp to edge
// Header (48 bytes, as lighting_grid.comp's): node (0, 0, 0), node spacing, nodes per axis.
layout(std430, set = 3, binding = 1) readonly buffer GridHeader {
  vec4 gridMin;  // xyz: local frame, metres
  vec4 gridStep;
  ivec4 gridDims;
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
  // Node coordinates to texture coordinates: node i's texel centre is (i + 0.5) / dims; outside the lattice
  // the clamp-to-edge sampler continues the nearest face, as lighting_grid.comp's clamp does.
  vec3 tc = ((p - gridMin.xyz) / gridStep.xyz + 0.5) / vec3(gridDims.xyz);
  float f[28];
  for (int j = 0; j < 7; ++j) {
    vec4 t = textureLod(gridTextures[j], tc, 0.0);
    f[4 * j] = t.x;
    f[4 * j + 1] = t.y;
    f[4 * j + 2] = t.z;
    f[4 * j + 3] = t.w;
  }
  vec3 c[9];
  for (int i = 0; i < 9; ++i) c[i] = vec3(f[3 * i], f[3 * i + 1], f[3 * i + 2]);
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
