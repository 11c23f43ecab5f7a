#version 450
// probe_dots.frag: a round dot with a dark rim, in the probe kind's colour.

layout(location = 0) in vec2 inCorner;
layout(location = 1) flat in vec3 inColor;

layout(location = 0) out vec4 outColor;

void main() {
  float r = length(inCorner);
  if (r > 1.0) discard;
  outColor = vec4(r > 0.7 ? inColor * 0.2 : inColor, 1.0);
}
