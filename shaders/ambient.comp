#version 450
// ambient.comp: lighting.comp's full-screen pass with a constant in place of the lookup (same G-buffer reads
// and writes): the floor any per-pixel lighting pass pays, timed by `tetraprobe bench render`.

layout(local_size_x = 8, local_size_y = 8) in;

layout(set = 1, binding = 0, rgba32f) uniform readonly image2D gPosition;  // local frame; a = 1 on geometry
layout(set = 1, binding = 1, rgba32f) uniform readonly image2D gNormal;
layout(set = 1, binding = 2, rgba32f) uniform readonly image2D gAlbedo;
layout(set = 1, binding = 3, rgba32f) uniform writeonly image2D outColor;

layout(push_constant) uniform LightingPush {
  ivec2 size;  // pixels
  int mode;    // 0: irradiance E (W/m^2); 1: indirect outgoing radiance albedo * E / pi (W/(m^2 sr))
};

const vec3 kAmbientE = vec3(1.0);  // W/m^2 on every surface

void main() {
  ivec2 px = ivec2(gl_GlobalInvocationID.xy);
  if (px.x >= size.x || px.y >= size.y) return;
  vec4 p = imageLoad(gPosition, px);
  if (p.a == 0.0) {
    imageStore(outColor, px, vec4(0.0));
    return;
  }
  vec3 e = kAmbientE;
  if (mode == 1) e = imageLoad(gAlbedo, px).rgb * e / 3.141592653589793;
  imageStore(outColor, px, vec4(e, 1.0));
}
