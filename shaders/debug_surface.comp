#version 450
// debug_surface.comp: plain grey shading of the G-buffer (brighter facing the camera), the backdrop of debug overlays.

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
  imageStore(outColor, px, vec4(vec3(0.12 + 0.23 * facing), 1.0));
}
