// tetraprobe.glsl: per-pixel irradiance from a level's tetrahedral SH probes (locate tet, blend, evaluate).
// Permissive. The GLSL twin of tetraprobe::ProbeQuery (runtime/query.h): same walk, same weights, same SH.
//
// Contract
// - Positions are in the level's LOCAL frame: local = world - Level::origin (metres; the engine subtracts the
//   origin, in double, before the value reaches float). Normals are unit vectors in the same (world) axes.
// - tetraprobeIrradiance(localPos, normal) returns irradiance E in W/m^2 (RGB). Lambertian outgoing radiance
//   is albedo * E / pi. E can be slightly negative where the L2 projection rings; clamp if you need to.
// - tetraprobeLocate(localPos, hint) is ProbeQuery::locate: a walk from `hint` (a tet index, e.g. last
//   frame's tet of the object; at most TETRAPROBE_MAX_HINT_STEPS steps, used when it ends inside), else from
//   the tet named by the start brick's sub-cell holding localPos (runtime/start_bricks.h: one hash search
//   and one load; that tet holds the sub-cell's centre, so the walk takes a step or a few; for an absent
//   cell, the start-grid cell's tet; at most tetraprobeMaxWalkSteps). Each step
//   computes the four barycentric weights; when none is below -TETRAPROBE_INSIDE_EPS the point is inside
//   (within that tolerance of a face, the neighbour is taken if it holds the point better); otherwise the walk
//   moves to the neighbour opposite the most negative weight (the first one on ties). Leaving through a hull
//   face (neighbour -1; only when the point is beyond the face's plane) continues across the outer cells
//   (runtime/outer_cells.h) to the one whose extruded hull triangle holds the point: a continuous answer
//   outside the hull that does not depend on the hint (loc.outerCell names the cell). A cycle answers
//   with the visited tet holding the point best, if within TETRAPROBE_CYCLE_ACCEPT_EPS. A walk that fails
//   (its step bound, or a cycle with no tet that close) answers with the visited tet holding the point best,
//   clamped; an outer-cell walk that fails, with the visited cell holding it best. There is no O(tets) scan
//   in what ships: TETRAPROBE_DEBUG_SCAN_FALLBACK (a debug build only) compiles the CPU's scans of every tet
//   and outer cell in after a failed walk, to compare against. An empty level gives tet -1 and E = 0.
//   The CPU evaluates weights in double, the GPU in float: inside the hull both give the same field (up to
//   rounding), outside too (the outer cells' answer does not depend on the hull face the walk leaves by).
// - tetraprobeLocateWithin(localPos, hint, hintSteps) bounds the hint's walk by hintSteps instead, and
//   tetraprobeIrradianceLocated(loc, localPos, normal) shades an already located point: an engine that keeps
//   each pixel's tet for the next frame locates with the reprojected pixel's old tet as the hint, shades, and
//   stores loc.tet (shaders/lighting_temporal.comp; docs/rendering.md, "Temporal start").
// - Bindings: the five read-only storage buffers of tetraprobe_layout.glsl in set TETRAPROBE_SET at bindings
//   TETRAPROBE_BINDING + 0..5 (defaults 0 and 0..5; define the macros before including to move them).
//   Upload them with tetraprobe::uploadLevelBuffers and bind with tetraprobe::writeLevelDescriptors
//   (runtime/vulkan_upload.h).
// - Variants: eight specialization constants, constant_id TETRAPROBE_SPEC_ID + 0..7 (default 0..7): 0..4 turn
//   off what a level does not use (SH band 2, plane or shadow-map occlusion, outer cells, the cell grid); the
//   driver then compiles that code out; 5..7 give the level's tet packing (runtime/gpu_tets.h), so the tet
//   records' shifts fold. Unspecialized, everything is on and the packing is read from the buffer (right for
//   any level). Specialize
//   with tetraprobe::shaderSpecialization(tetraprobe::shaderVariantFor(level, ...)) (runtime/vulkan_upload.h,
//   runtime/shader_variant.h).
// - Including: the shader that includes this file needs `#extension GL_GOOGLE_include_directive : require`
//   (glslangValidator) or shaderc, with this folder on the include path (CMake target tetraprobe_shaders).
#ifndef TETRAPROBE_GLSL
#define TETRAPROBE_GLSL

// The lookup by idea, each file including what it uses (include guards make the order safe):
#include "tetraprobe_face_blend.glsl"   // the face blend: tetraprobeLookupVisibility
#include "tetraprobe_layout.glsl"       // the buffers (tetraprobe::gpu_layout.h)
#include "tetraprobe_locate.glsl"       // start bricks and the walk: tetraprobeLocate
#include "tetraprobe_occlusion.glsl"    // per-tet occlusion
#include "tetraprobe_outer_cells.glsl"  // outside the hull
#include "tetraprobe_probe_sh.glsl"     // the probes' SH, blended
#include "tetraprobe_sh.glsl"           // the SH basis and irradiance (runtime/sh.h)
#include "tetraprobe_tets.glsl"         // locations, probe positions, barycentric weights
#include "tetraprobe_variant.glsl"      // specialization constants
// Not included here: tetraprobe_upsample.glsl, the rules of the half-resolution lookup (an engine option).

// Irradiance E in W/m^2 at local position localPos on a surface with unit normal `normal`. The level's
// occlusion (if any) drops the probes the point cannot see, inside the hull and (through the hull tet of the
// outer cell) outside it, blended near faces with the neighbour's (tetraprobeFaceBlendVisibility); a point
// that sees none blends into min(blend dominated by the nearest probe in front of the surface, unoccluded
// blend) per channel. Mirrors
// ProbeQuery::irradiance and occludedIrradiance (runtime/occlusion.h).
vec3 tetraprobeIrradianceLocated(TetraprobeLocation loc, vec3 localPos, vec3 normal);
vec3 tetraprobeIrradiance(vec3 localPos, vec3 normal) {
  return tetraprobeIrradianceLocated(tetraprobeLocate(localPos, -1), localPos, normal);
}

// tetraprobeIrradiance at a point already located (loc = tetraprobeLocate(localPos, hint) or
// tetraprobeLocateWithin): for an engine that starts the walk from a hint, such as last frame's tet of the
// pixel (loc.tet is the tet to keep for the next frame).
vec3 tetraprobeIrradianceLocated(TetraprobeLocation loc, vec3 localPos, vec3 normal) {
  if (loc.tet < 0) return vec3(0.0);
  vec4 w = loc.weights;
  vec3 c[9];
  if (!(tetraprobeUsePlanes || tetraprobeUseShadowMaps)) {  // a variant without occlusion: one blend
    tetraprobeBlendSh(loc.tet, w, c);
    return tetraprobeShIrradianceVariant(c, normal);
  }
  float fallback = 0.0;
  if (tetraprobeOccTetCount != 0u) {  // outside the hull too: the hull tet's occlusion (see ProbeQuery)
    w = tetraprobeOccApply(w, tetraprobeLookupVisibility(loc, localPos, normal), fallback);
  }
  // The all-occluded fallback's two blends (nearest-dominated p, unoccluded u) come from the same pass over
  // the probes' SH as the occluded one (a GPU may run both sides of the branch below).
  float unused;
  vec4 u = tetraprobeOccApply(loc.weights, vec4(1.0), unused);
  // The front factors only matter where the fallback runs (p is not used elsewhere): skip their fetches.
  vec4 front = fallback > 0.0 ? tetraprobeProbeFront(loc.tet, localPos, normal) : vec4(1.0);
  vec4 q = u * max(front, vec4(TETRAPROBE_OCC_BEHIND));
  vec4 p = q * q;
  p = p * p;
  p = p * p;
  float ps = p.x + p.y + p.z + p.w;
  p = ps > 0.0 ? p / ps : u;
  vec3 cp[9], cu[9];
  tetraprobeBlendSh3(loc.tet, w, p, u, c, cp, cu);
  vec3 e = tetraprobeShIrradianceVariant(c, normal);
  if (fallback > 0.0) {
    vec3 nearest = tetraprobeShIrradianceVariant(cp, normal);
    vec3 blend = tetraprobeShIrradianceVariant(cu, normal);
    e = (1.0 - fallback) * e + fallback * min(nearest, blend);
  }
  return e;
}

#endif  // TETRAPROBE_GLSL
