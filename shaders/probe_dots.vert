#version 450
// probe_dots.vert: expands each probe into a screen-space quad (6 vertices per instance) coloured by its kind.

layout(std430, set = 0, binding = 0) readonly buffer Probes {
  vec4 probes[];  // xyz: local frame, metres; w: LevelProbeKind as a float, -1 = not recorded
};

layout(push_constant) uniform DotsPush {
  mat4 viewProj;     // local frame -> Vulkan clip space (y down, depth 0..1), as the G-buffer's
  vec2 radius;       // dot radius in NDC units (x, y)
  float brightness;  // 1 for visible probes, less for the pass drawing hidden ones
  float pad;
};

layout(location = 0) out vec2 outCorner;  // -1..1 across the quad
layout(location = 1) flat out vec3 outColor;

// Legend (render.h, RenderMode::kProbes), by LevelProbeKind: user white, surface green, volume cyan, open
// light blue, filler blue, shell orange, dilated magenta, hole red, refinement yellow, grid grey; unknown
// (the level records no kinds) white.
vec3 kindColor(int kind) {
  const vec3 table[10] = vec3[10](vec3(1.0), vec3(0.1, 0.85, 0.1), vec3(0.0, 0.85, 0.85),
                                  vec3(0.45, 0.65, 1.0), vec3(0.1, 0.25, 1.0), vec3(1.0, 0.5, 0.0),
                                  vec3(1.0, 0.0, 1.0), vec3(1.0, 0.0, 0.0), vec3(1.0, 1.0, 0.0), vec3(0.6));
  return kind >= 0 && kind < 10 ? table[kind] : vec3(1.0);
}

void main() {
  const vec2 corners[6] =
      vec2[6](vec2(-1, -1), vec2(1, -1), vec2(1, 1), vec2(-1, -1), vec2(1, 1), vec2(-1, 1));
  vec4 probe = probes[gl_InstanceIndex];
  vec2 corner = corners[gl_VertexIndex % 6];
  vec4 clip = viewProj * vec4(probe.xyz, 1.0);
  clip.xy += corner * radius * clip.w;
  gl_Position = clip;
  outCorner = corner;
  outColor = kindColor(int(probe.w)) * brightness;
}
