#version 450
// lighting_nearest.comp: lighting.comp's full-screen pass with the nearest probe's SH in place of the tet
// lookup: the `nearest` method of `tetraprobe eval`, timed against the tet pass. Mirrors
// tetraprobe::NearestProbe::nearest (eval/nearest_probe.h): the same bucket grid, searched in shells of cells
// around the pixel's cell until no unvisited shell can hold a nearer probe (ties: lowest index).

#extension GL_GOOGLE_include_directive : require
#include "tetraprobe_sh.glsl"

layout(local_size_x = 8, local_size_y = 8) in;

// Header (32 bytes, tetraprobe::NearestHeader in render/src/renderer.cpp), then in `words`: the bucket
// prefix sums (cells + 1), the probe order (probeCount), the positions (3 floats each, local frame, metres)
// and the SH (27 floats each: 9 RGB coefficients), each array starting where the previous ends.
layout(std430, set = 0, binding = 0) readonly buffer NearestBuckets {
  vec4 bucketMin;    // xyz: the grid's lower corner (local frame); w: the cell size, metres
  ivec4 bucketDims;  // xyz: cells per axis, each >= 1; w: probe count, >= 1
  uint words[];
};

layout(set = 1, binding = 0, rgba32f) uniform readonly image2D gPosition;  // local frame; a = 1 on geometry
layout(set = 1, binding = 1, rgba32f) uniform readonly image2D gNormal;
layout(set = 1, binding = 2, rgba32f) uniform readonly image2D gAlbedo;
layout(set = 1, binding = 3, rgba32f) uniform writeonly image2D outColor;

layout(push_constant) uniform LightingPush {
  ivec2 size;  // pixels
  int mode;    // 0: irradiance E (W/m^2); 1: indirect outgoing radiance albedo * E / pi (W/(m^2 sr))
};

int nearestProbe(vec3 q) {
  ivec3 dims = bucketDims.xyz;
  float cell = bucketMin.w;
  int cells = dims.x * dims.y * dims.z;
  int orderAt = cells + 1, posAt = orderAt + bucketDims.w;
  ivec3 c = clamp(ivec3(floor((q - bucketMin.xyz) / cell)), ivec3(0), dims - 1);
  vec3 boxLo = bucketMin.xyz, boxHi = bucketMin.xyz + vec3(dims) * cell;
  float outside = length(max(max(boxLo - q, q - boxHi), vec3(0.0)));
  float best = 1.0 / 0.0;
  int bestIdx = -1;
  int maxR = max(dims.x, max(dims.y, dims.z));
  for (int r = 0; r <= maxR; ++r) {
    if (bestIdx >= 0 && max(float(r - 1) * cell, outside) > sqrt(best)) break;
    ivec3 lo = max(c - r, ivec3(0)), hi = min(c + r, dims - 1);
    for (int z = lo.z; z <= hi.z; ++z)
      for (int y = lo.y; y <= hi.y; ++y)
        for (int x = lo.x; x <= hi.x; ++x) {
          if (max(abs(x - c.x), max(abs(y - c.y), abs(z - c.z))) != r) continue;
          int cellIndex = x + dims.x * (y + dims.y * z);
          for (uint k = words[cellIndex]; k < words[cellIndex + 1]; ++k) {
            int i = int(words[orderAt + int(k)]);
            vec3 p = vec3(uintBitsToFloat(words[posAt + 3 * i]), uintBitsToFloat(words[posAt + 3 * i + 1]),
                          uintBitsToFloat(words[posAt + 3 * i + 2]));
            vec3 d = p - q;
            float d2 = dot(d, d);
            if (d2 < best || (d2 == best && i < bestIdx)) {
              best = d2;
              bestIdx = i;
            }
          }
        }
  }
  return bestIdx;
}

void main() {
  ivec2 px = ivec2(gl_GlobalInvocationID.xy);
  if (px.x >= size.x || px.y >= size.y) return;
  vec4 p = imageLoad(gPosition, px);
  if (p.a == 0.0) {
    imageStore(outColor, px, vec4(0.0));
    return;
  }
  vec3 n = imageLoad(gNormal, px).xyz;
  int i = nearestProbe(p.xyz);
  int shAt = (bucketDims.x * bucketDims.y * bucketDims.z + 1) + 4 * bucketDims.w + 27 * i;
  vec3 c[9];
  for (int k = 0; k < 9; ++k)
    c[k] = vec3(uintBitsToFloat(words[shAt + 3 * k]), uintBitsToFloat(words[shAt + 3 * k + 1]),
                uintBitsToFloat(words[shAt + 3 * k + 2]));
  vec3 e = tetraprobeShIrradiance(c, n);
  if (mode == 1) e = imageLoad(gAlbedo, px).rgb * e / 3.141592653589793;
  imageStore(outColor, px, vec4(e, 1.0));
}
