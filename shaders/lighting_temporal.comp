#version 450
// lighting_temporal.comp: lighting.comp with a temporal start, as an engine that keeps last frame's tet per
// pixel (a G-buffer channel) runs it: the pixel's point is reprojected into last frame's image, the tet
// stored there starts the walk (at most TETRAPROBE_TEMPORAL_HINT_STEPS steps, then the start bricks as
// without a hint), and the tet found is stored for the next frame. The answer is the cold lookup's either
// way. Writes E (mode 0) or albedo * E / pi (mode 1) to binding 8, a = 2 where last frame's tet holds the
// point (the hint was right), else 1.

#extension GL_GOOGLE_include_directive : require
#define TETRAPROBE_SET 0
#define TETRAPROBE_BINDING 0
#include "tetraprobe.glsl"

layout(local_size_x = 8, local_size_y = 8) in;

layout(set = 1, binding = 0, rgba32f) uniform readonly image2D gPosition;  // local frame; a = 1 on geometry
layout(set = 1, binding = 1, rgba32f) uniform readonly image2D gNormal;
layout(set = 1, binding = 2, rgba32f) uniform readonly image2D gAlbedo;
layout(set = 1, binding = 8, rgba32f) uniform writeonly image2D outColor;
// Two frames of tets, W x H each (-1: none): this frame reads half `parity` and writes the other.
layout(set = 1, binding = 9, std430) buffer PixelTets {
  int pixelTets[];
};

layout(push_constant) uniform TemporalPush {
  ivec2 size;  // pixels
  int mode;    // 0: irradiance E (W/m^2); 1: indirect outgoing radiance albedo * E / pi (W/(m^2 sr))
  int lightCount;
  vec4 eye;
  vec4 shadowInfo;
  int parity;                                 // which half of pixelTets holds last frame's tets
  layout(offset = 64) mat4 previousViewProj;  // last frame's local frame -> Vulkan clip space
};

// Enough for a point that moved a pixel or a few to reach its tet from last frame's; a hint from another
// surface (disocclusion) gives up after these steps.
const int TETRAPROBE_TEMPORAL_HINT_STEPS = 8;

void main() {
  ivec2 px = ivec2(gl_GlobalInvocationID.xy);
  if (px.x >= size.x || px.y >= size.y) return;
  int pixels = size.x * size.y, here = px.y * size.x + px.x;
  int readBase = parity * pixels, writeBase = (1 - parity) * pixels;
  vec4 p = imageLoad(gPosition, px);
  if (p.a == 0.0) {
    imageStore(outColor, px, vec4(0.0));
    pixelTets[writeBase + here] = -1;
    return;
  }
  vec4 clip = previousViewProj * vec4(p.xyz, 1.0);
  int hint = -1;
  if (clip.w > 0.0) {
    ivec2 q = ivec2(floor((clip.xy / clip.w * 0.5 + 0.5) * vec2(size)));
    if (all(greaterThanEqual(q, ivec2(0))) && all(lessThan(q, size)))
      hint = pixelTets[readBase + q.y * size.x + q.x];
  }
  vec3 n = imageLoad(gNormal, px).xyz;
  TetraprobeLocation loc = tetraprobeLocateWithin(p.xyz, hint, TETRAPROBE_TEMPORAL_HINT_STEPS);
  vec3 e = tetraprobeIrradianceLocated(loc, p.xyz, n);
  pixelTets[writeBase + here] = loc.tet;
  if (mode == 1) {
    precise vec3 l = imageLoad(gAlbedo, px).rgb * e / 3.141592653589793;
    e = l;
  }
  imageStore(outColor, px, vec4(e, loc.tet == hint ? 2.0 : 1.0));  // a = 2: last frame's tet holds the point
}
