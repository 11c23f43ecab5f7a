#version 450
#extension GL_GOOGLE_include_directive : require
// engine_include.frag: an engine-style fragment shader using tetraprobe.glsl with moved bindings (build check).

#define TETRAPROBE_SET 2
#define TETRAPROBE_BINDING 5
#include "tetraprobe.glsl"

layout(location = 0) in vec3 inLocalPos;
layout(location = 1) in vec3 inNormal;
layout(location = 0) out vec4 outColor;

void main() {
  outColor = vec4(tetraprobeIrradiance(inLocalPos, normalize(inNormal)), 1.0);
}
