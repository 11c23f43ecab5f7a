#version 450
// lighting_upsample.comp: pass 2 of the half-resolution lookup (tetraprobe_upsample.glsl): every pixel takes
// its block's E (the representative) or the depth- and normal-weighted mean of the four half-resolution
// samples around it; where none lies on its surface, the pixel is appended to a list that pass 3
// (lighting_edges.comp) looks up at full resolution, so no lane here pays for the lookup (a GPU runs both
// sides of a branch some lanes take). Output a: 0 background, 1 interpolated, 2 copied (the representative);
// pass 3 writes 3. Mode 1 multiplies by albedo / pi.

#extension GL_GOOGLE_include_directive : require
#include "tetraprobe_upsample.glsl"

layout(local_size_x = 8, local_size_y = 8) in;

layout(set = 1, binding = 0, rgba32f) uniform readonly image2D gPosition;  // local frame; a = 1 on geometry
layout(set = 1, binding = 1, rgba32f) uniform readonly image2D gNormal;
layout(set = 1, binding = 2, rgba32f) uniform readonly image2D gAlbedo;
layout(set = 1, binding = 5, rgba32f) uniform readonly image2D halfE;  // lighting_half.comp's output
layout(set = 1, binding = 6, rgba32f) uniform writeonly image2D outColor;
// The pixels pass 3 looks up: dispatch.x counts its 64-wide workgroups (vkCmdDispatchIndirect), count the
// pixels (x | y << 16). Reset to (0, 1, 1, 0) before this pass.
layout(set = 1, binding = 7, std430) buffer EdgePixels {
  uvec4 dispatch;  // x, y, z workgroups of pass 3; w unused
  uint count;
  uint pixels[];
}
edges;

layout(push_constant) uniform LightingPush {
  ivec2 size;  // pixels
  int mode;    // 0: irradiance E (W/m^2); 1: indirect outgoing radiance albedo * E / pi (W/(m^2 sr))
  int unused;
  vec4 eye;  // camera position (local frame); w: radians per pixel
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
  ivec2 h0 = px >> 1;
  ivec2 halfSize = (size + 1) >> 1;
  vec4 own = imageLoad(halfE, h0);
  vec3 e;
  float code;
  if (int(own.a) - 1 == tetraprobeHalfIndexOf(px)) {
    e = own.rgb;
    code = 2.0;
  } else {
    ivec2 side = 2 * (px & 1) - 1;  // towards the neighbouring blocks nearest the pixel
    float footprint = distance(p.xyz, eye.xyz) * eye.w;
    vec3 sum = vec3(0.0);
    float weights = 0.0, lo = 3.4e38, hi = 0.0;
    for (int c = 0; c < 4; ++c) {
      ivec2 h = h0 + ivec2((c & 1) * side.x, (c >> 1) * side.y);
      if (any(lessThan(h, ivec2(0))) || any(greaterThanEqual(h, halfSize))) continue;
      vec4 s = c == 0 ? own : imageLoad(halfE, h);
      int k = int(s.a) - 1;
      if (k < 0) continue;
      ivec2 q = 2 * h + tetraprobeHalfOffset(k);
      float w = tetraprobeUpsampleWeight(p.xyz, n, imageLoad(gPosition, q).xyz, imageLoad(gNormal, q).xyz,
                                         footprint, length(vec2(q - px)));
      sum += w * s.rgb;
      weights += w;
      if (w > 0.0) {
        float y = dot(s.rgb, vec3(0.2126, 0.7152, 0.0722));
        lo = min(lo, y);
        hi = max(hi, y);
      }
    }
    if (!(weights >= TETRAPROBE_UPSAMPLE_MIN_WEIGHT) ||
        hi > TETRAPROBE_UPSAMPLE_MAX_SPREAD * max(lo, 1e-3 * hi)) {  // pass 3 writes this pixel
      uint i = atomicAdd(edges.count, 1u);
      if ((i & 63u) == 0u) atomicAdd(edges.dispatch.x, 1u);
      edges.pixels[i] = uint(px.x) | (uint(px.y) << 16);
      return;
    }
    e = sum / weights;
    code = 1.0;
  }
  if (mode == 1) {
    precise vec3 l = imageLoad(gAlbedo, px).rgb * e / 3.141592653589793;
    e = l;
  }
  imageStore(outColor, px, vec4(e, code));
}
