#version 450
// gbuffer.vert: transforms level-local triangle-soup vertices; passes local position, flat normal, albedo, emission.

layout(location = 0) in vec3 inPosition;  // level local frame, metres
layout(location = 1) in vec3 inNormal;    // the triangle's unit normal (same on its three vertices)
layout(location = 2) in vec3 inAlbedo;    // the triangle's albedo (linear RGB)
layout(location = 3) in vec3 inEmission;  // the triangle's emitted radiance, W/(m^2 sr), front face

layout(push_constant) uniform GbufferPush {
  mat4 viewProj;  // local frame -> Vulkan clip space (y down, depth 0..1)
};

layout(location = 0) out vec3 outLocalPos;
layout(location = 1) flat out vec3 outNormal;
layout(location = 2) flat out vec3 outAlbedo;
layout(location = 3) flat out vec3 outEmission;

void main() {
  outLocalPos = inPosition;
  outNormal = inNormal;
  outAlbedo = inAlbedo;
  outEmission = inEmission;
  gl_Position = viewProj * vec4(inPosition, 1.0);
}
