#version 450
// direct.comp: adds direct light from point, spot and sun lights (shadow-mapped) and emission to the indirect image.

layout(local_size_x = 8, local_size_y = 8) in;

layout(set = 1, binding = 0, rgba32f) uniform readonly image2D gPosition;  // local frame; a = 1 on geometry
layout(set = 1, binding = 1, rgba32f) uniform readonly image2D gNormal;
layout(set = 1, binding = 2, rgba32f) uniform readonly image2D gAlbedo;
layout(set = 1, binding = 3, rgba32f) uniform image2D color;  // in: albedo * E / pi; out: + direct + emission
layout(set = 1, binding = 4, rgba32f) uniform readonly image2D gEmission;

// One light (render/src/renderer.cpp: GpuLight, 64 bytes).
struct Light {
  vec4 position;   // xyz: local frame, metres (point, spot); w: type 0 point, 1 spot, 2 directional
  vec4 direction;  // xyz: unit direction the light travels (spot, directional); w: cos(outer cone)
  vec4 intensity;  // rgb: W/sr (point, spot) or W/m^2 at normal incidence (directional); w: cos(inner cone)
  ivec4 shadow;    // x: first shadow-map layer (point, spot: 6 cube faces +X -X +Y -Y +Z -Z; sun: 1), -1 none
};
layout(std430, set = 2, binding = 0) readonly buffer Lights {
  Light lights[];
};
// Per shadow-map layer: local frame -> the layer's clip space (x, y in [-1, 1] -> uv, depth 0..1).
layout(std430, set = 2, binding = 1) readonly buffer ShadowMatrices {
  mat4 shadowViewProj[];
};
layout(set = 2, binding = 2) uniform sampler2DArrayShadow shadowMaps;  // compare LESS_OR_EQUAL, linear

layout(push_constant) uniform DirectPush {
  ivec2 size;       // pixels
  int mode;         // unused here
  int lightCount;   // entries of lights[]
  vec4 eye;         // unused here
  vec4 shadowInfo;  // x: texels per shadow-map side; y: half-width of the sun's box, metres
};

const float kPi = 3.141592653589793;

// Fraction of the 3x3 bilinear PCF taps of `layer` around local point q that see the light.
float shadowVisibility(int layer, vec3 q) {
  vec4 clip = shadowViewProj[layer] * vec4(q, 1.0);
  if (!(clip.w > 0.0)) return 1.0;
  vec3 ndc = clip.xyz / clip.w;
  vec2 uv = ndc.xy * 0.5 + 0.5;
  if (any(lessThan(uv, vec2(0.0))) || any(greaterThan(uv, vec2(1.0))) || ndc.z > 1.0) return 1.0;
  float ref = ndc.z - 1e-5;
  float texel = 1.0 / shadowInfo.x;
  float sum = 0.0;
  for (int dy = -1; dy <= 1; ++dy)
    for (int dx = -1; dx <= 1; ++dx)
      sum += texture(shadowMaps, vec4(uv + vec2(dx, dy) * texel, float(layer), ref));
  return sum / 9.0;
}

// The cube face whose 90-degree frustum holds direction d (light to point): +X -X +Y -Y +Z -Z.
int cubeFace(vec3 d) {
  vec3 a = abs(d);
  if (a.x >= a.y && a.x >= a.z) return d.x >= 0.0 ? 0 : 1;
  if (a.y >= a.z) return d.y >= 0.0 ? 2 : 3;
  return d.z >= 0.0 ? 4 : 5;
}

void main() {
  ivec2 px = ivec2(gl_GlobalInvocationID.xy);
  if (px.x >= size.x || px.y >= size.y) return;
  vec4 p = imageLoad(gPosition, px);
  if (p.a == 0.0) return;  // background stays 0
  vec3 n = imageLoad(gNormal, px).xyz;
  vec3 albedo = imageLoad(gAlbedo, px).rgb;
  vec3 e = vec3(0.0);  // direct irradiance, W/m^2
  for (int i = 0; i < lightCount; ++i) {
    Light l = lights[i];
    int type = int(l.position.w);
    vec3 toLight;
    float falloff;
    if (type == 2) {
      toLight = -l.direction.xyz;
      falloff = 1.0;
    } else {
      vec3 d = l.position.xyz - p.xyz;
      float r2 = dot(d, d);
      if (!(r2 > 0.0)) continue;
      toLight = d * inversesqrt(r2);
      falloff = 1.0 / r2;
      if (type == 1) {  // as the bake's spotFactor: smoothstep in the cosine between the cones
        float c = dot(l.direction.xyz, -toLight);
        float e0 = l.direction.w, e1 = l.intensity.w;
        falloff *= e1 > e0 ? smoothstep(e0, e1, c) : (c >= e0 ? 1.0 : 0.0);
      }
    }
    float cosTheta = dot(n, toLight);
    if (cosTheta <= 0.0 || falloff <= 0.0) continue;
    float vis = 1.0;
    if (l.shadow.x >= 0) {
      // Normal offset: the point moved one and a half shadow-map texels off its surface.
      if (type == 2) {
        vis = shadowVisibility(l.shadow.x, p.xyz + n * (3.0 * shadowInfo.y / shadowInfo.x));
      } else {
        vec3 a = abs(p.xyz - l.position.xyz);
        float depth = max(a.x, max(a.y, a.z));  // a cube face's frustum is 2 x depth wide at that depth
        vec3 q = p.xyz + n * (3.0 * depth / shadowInfo.x);
        vis = shadowVisibility(l.shadow.x + cubeFace(q - l.position.xyz), q);
      }
    }
    e += l.intensity.rgb * (cosTheta * falloff * vis);
  }
  vec3 indirect = imageLoad(color, px).rgb;
  precise vec3 outgoing = indirect + albedo * e / kPi + imageLoad(gEmission, px).rgb;
  imageStore(color, px, vec4(outgoing, 1.0));
}
