#version 450
// point_lookup.comp: tetraprobeIrradiance at a list of points (test harness for run-time SH updates).
#extension GL_GOOGLE_include_directive : require
#define TETRAPROBE_SET 0
#define TETRAPROBE_BINDING 0
#include "tetraprobe.glsl"

layout(local_size_x = 64) in;

struct PointNormal {
  vec4 position;  // xyz: level local frame, metres
  vec4 normal;    // xyz: unit normal
};
layout(std430, set = 1, binding = 0) readonly buffer Points {
  PointNormal points[];
};
layout(std430, set = 1, binding = 1) writeonly buffer Irradiance {
  vec4 irradiance[];  // xyz: E in W/m^2
};
layout(push_constant) uniform Push {
  uint count;
};

void main() {
  uint i = gl_GlobalInvocationID.x;
  if (i >= count) return;
  irradiance[i] = vec4(tetraprobeIrradiance(points[i].position.xyz, points[i].normal.xyz), 0.0);
}
