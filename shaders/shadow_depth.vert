#version 450
// shadow_depth.vert: depth-only transform of the triangle soup into one shadow-map layer (a light's view).

layout(location = 0) in vec3 inPosition;  // level local frame, metres

layout(push_constant) uniform ShadowPush {
  mat4 lightViewProj;  // local frame -> the layer's clip space (depth 0..1, no y flip)
};

void main() {
  gl_Position = lightViewProj * vec4(inPosition, 1.0);
}
