#version 450
// lighting_debug_scan.comp: shaders/lighting.comp built with TETRAPROBE_DEBUG_SCAN_FALLBACK (the CPU's O(tets)
// scans after a failed walk), for the tests that compare it with the shipping build and show the SPIR-V check
// can find a scan.

#extension GL_GOOGLE_include_directive : require
#define TETRAPROBE_DEBUG_SCAN_FALLBACK
#include "tetraprobe.glsl"

layout(local_size_x = 8, local_size_y = 8) in;

layout(set = 1, binding = 0, rgba32f) uniform readonly image2D gPosition;
layout(set = 1, binding = 1, rgba32f) uniform readonly image2D gNormal;
layout(set = 1, binding = 2, rgba32f) uniform readonly image2D gAlbedo;
layout(set = 1, binding = 3, rgba32f) uniform writeonly image2D outColor;

layout(push_constant) uniform LightingPush {
  ivec2 size;
  int mode;
};

void main() {
  ivec2 px = ivec2(gl_GlobalInvocationID.xy);
  if (px.x >= size.x || px.y >= size.y) return;
  vec4 p = imageLoad(gPosition, px);
  if (p.a == 0.0) {
    imageStore(outColor, px, vec4(0.0));
    return;
  }
  vec3 n = imageLoad(gNormal, px).xyz;
  vec3 e = tetraprobeIrradiance(p.xyz, n);
  if (mode == 1) {
    precise vec3 l = imageLoad(gAlbedo, px).rgb * e / 3.141592653589793;
    e = l;
  }
  imageStore(outColor, px, vec4(e, 1.0));
}
