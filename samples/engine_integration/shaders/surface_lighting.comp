#version 450
// surface_lighting.comp: the engine's per-pixel indirect light, as a compute pass over its G-buffer's
// surface points. It includes the installed tetraprobe.glsl (TETRAPROBE_SHADER_DIR) with the level's six
// buffers in set 0, bindings 0..5, and is specialized with the level's variant (constant_id 0..7).
// Set 1: binding 0 the points (two vec4 a pixel: local position with w = 1 on geometry, 0 on sky; normal),
// binding 1 the irradiance out (vec4 a pixel, w = 1 where shaded).
#extension GL_GOOGLE_include_directive : require
#define TETRAPROBE_SET 0
#define TETRAPROBE_BINDING 0
#include "tetraprobe.glsl"

layout(local_size_x = 64) in;

layout(std430, set = 1, binding = 0) readonly buffer SurfacePoints {
  vec4 points[];
};
layout(std430, set = 1, binding = 1) writeonly buffer SurfaceIrradiance {
  vec4 irradiance[];
};

layout(push_constant) uniform Push {
  uint count;
};

void main() {
  uint i = gl_GlobalInvocationID.x;
  if (i >= count) return;
  vec4 p = points[2 * i];
  if (p.w == 0.0) {
    irradiance[i] = vec4(0.0);
    return;
  }
  irradiance[i] = vec4(tetraprobeIrradiance(p.xyz, points[2 * i + 1].xyz), 1.0);
}
