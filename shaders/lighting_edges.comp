#version 450
// lighting_edges.comp: pass 3 of the half-resolution lookup (tetraprobe_upsample.glsl): the full lookup at the
// pixels pass 2 (lighting_upsample.comp) listed, where no half-resolution sample lies on the pixel's surface.
// Dispatched indirectly, one invocation a listed pixel; writes a = 3. Mode 1 multiplies by albedo / pi.

#extension GL_GOOGLE_include_directive : require
#define TETRAPROBE_SET 0
#define TETRAPROBE_BINDING 0
#include "tetraprobe.glsl"

layout(local_size_x = 64) in;

layout(set = 1, binding = 0, rgba32f) uniform readonly image2D gPosition;  // local frame; a = 1 on geometry
layout(set = 1, binding = 1, rgba32f) uniform readonly image2D gNormal;
layout(set = 1, binding = 2, rgba32f) uniform readonly image2D gAlbedo;
layout(set = 1, binding = 6, rgba32f) uniform writeonly image2D outColor;
layout(set = 1, binding = 7, std430) readonly buffer EdgePixels {
  uvec4 dispatch;
  uint count;
  uint pixels[];
}
edges;

layout(push_constant) uniform LightingPush {
  ivec2 size;  // pixels
  int mode;    // 0: irradiance E (W/m^2); 1: indirect outgoing radiance albedo * E / pi (W/(m^2 sr))
};

void main() {
  uint i = gl_GlobalInvocationID.x;
  if (i >= edges.count) return;
  ivec2 px = ivec2(int(edges.pixels[i] & 0xffffu), int(edges.pixels[i] >> 16));
  vec3 e = tetraprobeIrradiance(imageLoad(gPosition, px).xyz, imageLoad(gNormal, px).xyz);
  if (mode == 1) {
    precise vec3 l = imageLoad(gAlbedo, px).rgb * e / 3.141592653589793;
    e = l;
  }
  imageStore(outColor, px, vec4(e, 3.0));
}
