#version 450
// gbuffer.frag: writes local position (a = 1 marks geometry), flat normal, albedo and emission to RGBA32F targets.

layout(location = 0) in vec3 inLocalPos;
layout(location = 1) flat in vec3 inNormal;
layout(location = 2) flat in vec3 inAlbedo;
layout(location = 3) flat in vec3 inEmission;

layout(location = 0) out vec4 outPosition;
layout(location = 1) out vec4 outNormal;
layout(location = 2) out vec4 outAlbedo;
layout(location = 3) out vec4 outEmission;

void main() {
  outPosition = vec4(inLocalPos, 1.0);
  outNormal = vec4(inNormal, 1.0);
  outAlbedo = vec4(inAlbedo, 1.0);
  outEmission = vec4(inEmission, 1.0);
}
