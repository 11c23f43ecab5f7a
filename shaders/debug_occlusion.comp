#version 450
// debug_occlusion.comp: colours each pixel by the occlusion kind its lookup used and marks the all-occluded fallback.

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

// Legend (render.h, RenderMode::kOcclusion): kind none grey, planes blue, shadow maps green; the fallback
// (no probe of the tet visible after the face blend: tetraprobeOccApply's share > 0) red, mixed in by its share from 50 %.
const vec3 kNone = vec3(0.5), kPlanes = vec3(0.15, 0.35, 1.0), kShadowMaps = vec3(0.2, 0.9, 0.25),
           kFallback = vec3(1.0, 0.05, 0.05);

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
  vec3 c = kNone;
  if (loc.tet >= 0 && tetraprobeOccTetCount != 0u) {  // as tetraprobeIrradiance: the hull tet outside too
    uint kind = tetraprobeOccKind(loc.tet);
    c = kind == TETRAPROBE_OCC_KIND_PLANES        ? kPlanes
        : kind == TETRAPROBE_OCC_KIND_SHADOW_MAPS ? kShadowMaps
                                                  : kNone;
    float fallback = 0.0;
    tetraprobeOccApply(loc.weights, tetraprobeLookupVisibility(loc, p.xyz, n), fallback);
    if (fallback > 0.0) c = mix(c, kFallback, 0.5 + 0.5 * fallback);
  }
  imageStore(outColor, px, vec4(c * (0.6 + 0.4 * facing), 1.0));
}
