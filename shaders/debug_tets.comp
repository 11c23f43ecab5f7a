#version 450
// debug_tets.comp: colours each pixel by the tet (or outer cell) holding its surface point, with dark tet-face lines.

#extension GL_GOOGLE_include_directive : require
#define TETRAPROBE_SET 0
#define TETRAPROBE_BINDING 0
#include "tetraprobe.glsl"

layout(local_size_x = 8, local_size_y = 8) in;

layout(set = 1, binding = 0, rgba32f) uniform readonly image2D gPosition;  // local frame; a = 1 on geometry
layout(set = 1, binding = 1, rgba32f) uniform readonly image2D gNormal;
layout(set = 1, binding = 3, rgba32f) uniform writeonly image2D outColor;  // display colour (linear RGB)

layout(push_constant) uniform DebugPush {
  ivec2 size;  // pixels
  int mode;    // unused here
  int lightCount;
  vec4 eye;  // xyz: camera position, local frame; w: radians per pixel (vertical)
};

// A bright colour from an index (integer hash -> hue), the same on every run and driver.
vec3 indexColor(uint i) {
  i ^= i >> 16;
  i *= 0x7feb352du;
  i ^= i >> 15;
  i *= 0x846ca68bu;
  i ^= i >> 16;
  float h = float(i & 0xFFFFu) / 65536.0;
  vec3 rgb = clamp(abs(fract(h + vec3(0.0, 2.0 / 3.0, 1.0 / 3.0)) * 6.0 - 3.0) - 1.0, 0.0, 1.0);
  float v = 0.55 + 0.45 * float((i >> 16) & 0xFFu) / 255.0;
  return mix(vec3(1.0), rgb, 0.75) * v;
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
  float facing = abs(dot(n, normalize(eye.xyz - p.xyz)));
  TetraprobeLocation loc = tetraprobeLocate(p.xyz, -1);
  vec3 c;
  if (loc.tet < 0) {
    c = vec3(0.3);  // empty level
  } else if (loc.outerCell >= 0) {
    c = indexColor(uint(loc.outerCell) + 0x9e3779b9u) * 0.35;  // outside the hull: dark
  } else {
    c = indexColor(uint(loc.tet));
    // Distance to the nearest face: w_i / |grad w_i| (w_3's gradient is minus the sum of the others').
    TetraprobeBaryFrame f = tetraprobeBaryFrame(loc.tet);
    vec4 w = tetraprobeBaryWeights(f, p.xyz);
    vec3 g0 = f.g[0], g1 = f.g[1], g2 = f.g[2];
    vec4 g = vec4(length(g0), length(g1), length(g2), length(g0 + g1 + g2));
    vec4 dist = max(w, 0.0) / max(g, vec4(1e-20));
    float d = min(min(dist.x, dist.y), min(dist.z, dist.w));
    float pixel = eye.w * length(eye.xyz - p.xyz) / max(facing, 0.2);  // one pixel on the surface, metres
    if (d < 0.75 * pixel) c *= 0.15;
  }
  imageStore(outColor, px, vec4(c * (0.6 + 0.4 * facing), 1.0));
}
