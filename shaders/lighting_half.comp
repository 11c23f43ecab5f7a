#version 450
// lighting_half.comp: pass 1 of the half-resolution lookup (tetraprobe_upsample.glsl): one tet lookup per 2x2
// block of the G-buffer, at the block's representative pixel; stores E and the pick (k + 1, 0: no geometry).

#extension GL_GOOGLE_include_directive : require
#define TETRAPROBE_SET 0
#define TETRAPROBE_BINDING 0
#include "tetraprobe.glsl"
#include "tetraprobe_upsample.glsl"

layout(local_size_x = 8, local_size_y = 8) in;

layout(set = 1, binding = 0, rgba32f) uniform readonly image2D gPosition;  // local frame; a = 1 on geometry
layout(set = 1, binding = 1, rgba32f) uniform readonly image2D gNormal;
layout(set = 1, binding = 5, rgba32f) uniform writeonly image2D halfE;  // ceil(W/2) x ceil(H/2)

layout(push_constant) uniform LightingPush {
  ivec2 size;  // full-resolution pixels
};

void main() {
  ivec2 h = ivec2(gl_GlobalInvocationID.xy);
  if (2 * h.x >= size.x || 2 * h.y >= size.y) return;
  bvec4 geometry;
  for (int k = 0; k < 4; ++k) {
    ivec2 px = 2 * h + tetraprobeHalfOffset(k);
    geometry[k] = px.x < size.x && px.y < size.y && imageLoad(gPosition, px).a != 0.0;
  }
  int k = tetraprobeHalfPick(geometry);
  if (k < 0) {
    imageStore(halfE, h, vec4(0.0));
    return;
  }
  ivec2 px = 2 * h + tetraprobeHalfOffset(k);
  vec3 e = tetraprobeIrradiance(imageLoad(gPosition, px).xyz, imageLoad(gNormal, px).xyz);
  imageStore(halfE, h, vec4(e, float(k + 1)));
}
