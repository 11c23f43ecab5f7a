// Per-tet probe occlusion against light leaking through walls (Killzone Shadow Fall style, Valient 2014):
// each tet stores nothing, up to three splitting planes, or one 16-byte shadow map per probe. At run time
// the probes a shading point cannot see drop out of the barycentric interpolation. Permissive: standard
// library and GLM only. Built by tetraprobe::buildOcclusion (occlusion/build_occlusion.h); layout and
// selection rule in docs/occlusion.md.
//
// Everything is evaluated in the tet's barycentric frame: the weights w (w_i of probe tet.v[i], from the
// tet's float BaryFrame of level.h, computed from its probe positions as the GPU does) are all the data a lookup needs besides the records below, so the GPU evaluates it
// with the weights it already has. Records are flat, fixed-size and pointer-free (std430-ready):
//   TetOcclusion   8 bytes per tet   (uvec2)
//   OcclusionPlane 8 bytes per plane (4 x snorm16; uvec2)
//   shadow maps    64 bytes per tet that has them (4 probes x 16 bytes: 15 lattice depths + 1 pad; uint[16])
//
// Bias (surfaces must not shadow themselves): a shading point with normal n is moved along n by
//   delta = kOcclusionBias / max_i |grad(w_i) . n|   (grad w_i = BaryFrame::grad[i], grad w_3 = -sum of the others)
// i.e. no barycentric coordinate changes by more than kOcclusionBias (3 % of the tet's extent along n).
// A zero normal (volumes, dynamic objects) means no bias.
//
// Soft falloff: planes blend the visibility of the cells on either side over a band of half-width
// kOcclusionPlaneFalloff (in units of the plane's largest probe distance, see OcclusionPlane); shadow maps
// fade over a band of half-width kOcclusionShadowFalloff (fraction of the probe-to-face distance) centred
// on the interpolated depth. Visibility is a smoothstep of those, continuous in the point.
#pragma once

#include <cstdint>
#include <vector>

#include <glm/common.hpp>
#include <glm/vec2.hpp>
#include <glm/vec3.hpp>
#include <glm/vec4.hpp>

#include "tetraprobe/runtime/level.h"
#include "tetraprobe/runtime/occlusion_data.h"

namespace tetraprobe {

inline constexpr float kOcclusionBias = 0.03f;           // barycentric normal offset (see above)
inline constexpr float kOcclusionPlaneFalloff = 0.02f;   // half-width, plane units
inline constexpr float kOcclusionShadowFalloff = 0.01f;  // half-width, fraction of probe-to-face distance
inline constexpr float kOcclusionFallbackSum = 1e-2f;    // applyOcclusion: visible weight below which the
                                                         // fallback (occludedIrradiance) is blended in

// Sub-triangle of a face's 4x4 subdivision. The face opposite probe i has corners A, B, C = the other three
// tet vertices in increasing slot order; (u, v) are the barycentrics of B and C (A gets 1-u-v). Row r (v in
// [r/4, (r+1)/4)) holds 7, 5, 3, 1 sub-triangles for r = 0..3, numbered along u, "lower" (pointing down in v)
// before "upper": index = {0, 7, 12, 15}[r] + 2 floor(4u) + upper. Points outside the face are clamped onto
// it.
int shadowMapCell(float u, float v);
// The (u, v) centre of sub-triangle `cell` (0..15): the point shadowMapCell maps back to `cell`.
glm::vec2 shadowMapCellCentre(int cell);

// Interpolated depth (fraction of the way to the face, see above) of one probe's 16 bytes at face point
// (u, v), clamped onto the face; > 1 (2.0) when none of the sub-triangle's corners met geometry.
float shadowMapDepth(const uint8_t* probeTexels, float u, float v);

// Barycentric weights moved by the bias rule above for unit or non-unit normal n (zero: unchanged).
// `frame`: the tet's baryFrame (level.h), whose gradients the rule uses.
glm::vec4 biasWeights(const BaryFrame& frame, const glm::vec4& weights, const glm::vec3& normal);

// The single-tet kernel (what the GLSL mirrors). `planes` points at the tet's first plane, `shadowMap` at
// its 64-byte block (either may be null when the kind does not use it). `weights` are the raw barycentric
// weights of the point (may be slightly outside [0,1]); `normal` as in biasWeights. Returns per-probe
// visibility in [0, 1] (1 = visible) for tet.v[0..3].
glm::vec4 evaluateTetOcclusion(const TetOcclusion& rec, const OcclusionPlane* planes,
                               const uint8_t* shadowMap, const BaryFrame& frame, const glm::vec4& weights,
                               const glm::vec3& normal);

// Per-probe visibility of tet.v[0..3] seen from local-frame point `local` (metres, relative to level.origin)
// on a surface with normal `normal` (world = local frame orientation; any length; zero for volumes). Every
// probe is visible (vec4(1)) when `occlusion` is empty, `tet` is out of range, or the tet stores nothing.
// Never throws; finite for finite input.
glm::vec4 occlusionVisibility(const Level& level, const LevelOcclusion& occlusion, int32_t tet,
                              const glm::vec3& local, const glm::vec3& normal);

// The same with the tet's frame given (`frame` must be baryFrame(level.tets[tet], level.probes)), for callers
// shading many points of one tet (ProbeQuery::irradianceBatch): the same result, bit for bit.
glm::vec4 occlusionVisibility(const Level& level, const LevelOcclusion& occlusion, int32_t tet,
                              const BaryFrame& frame, const glm::vec3& local, const glm::vec3& normal);

// Weights after occlusion: weights * visibility, renormalized to sum to 1. Non-finite or negative weights
// count as 0 and the rest are renormalized first (none left: 0.25 each); visibility is clamped to [0, 1],
// non-finite counts as 1. `fallback` (optional) gets the share of the fallback in the answer: with s the
// visible weight sum, 0 when s >= kOcclusionFallbackSum = k, else 1 - s/k (1 when every probe is occluded);
// when s == 0 the returned weights are the sanitized input weights (their share is then 0). The result is
// always finite, non-negative and sums to 1.
glm::vec4 applyOcclusion(const glm::vec4& weights, const glm::vec4& visibility, float* fallback = nullptr);

// Per probe, whether it lies in front of the surface at a shading point: with d_i = probe i - point,
//   front_i = clamp(dot(d_i, n) / (kOcclusionFrontSine |d_i| |n|), 0, 1)
// 1 once the direction to the probe rises kOcclusionFrontSine (sine of its elevation, ~1 deg) above the
// surface plane, 0 on or behind it, linear between (continuous in the point). 1 when n or d_i is zero
// (volumes, a probe at the point) or the result is not finite. `toProbe[i]` = d_i, any frame that n shares.
inline constexpr float kOcclusionFrontSine = 0.02f;
glm::vec4 probeFront(const glm::vec3 toProbe[4], const glm::vec3& normal);

// Irradiance (W/m^2) a point gets from its tet's four probes after occlusion, the run-time answer:
//   (1 - f) E(applyOcclusion(weights, visibility)) + f min(E(p), E(u))   (min per channel)
// with f the fallback share, u the unoccluded weights (applyOcclusion with every probe visible) and
//   p_i = q_i^8 / sum_j q_j^8,   q_i = u_i max(front_i, kOcclusionBehindShare),
// a blend dominated by the nearest probe in front of the surface (continuous where weights tie; exactly the
// nearest-of-all blend u^8 / sum u^8 when none is in front). The stored data claims the point sees none of its probes, but measured at
// the eval points of five levels most such points see one by rays (the data is a 16-texel or 3-plane
// approximation), and the nearest is the best guess of which: against the dimmest probe (the rule before),
// dark holes at the cameras fell from 1.7 % to 0.1 % on Sponza, 1.8 % to 0.2 % on q3 dm4ish and 1.8 % to
// 0.2 % on the conference room. A probe behind the surface plane is never what a surface sees, yet it was
// often the nearest: the conference room's last dark holes (docs/accuracy.md) took a probe under the wall's
// furniture 5 cm off the floor while rays saw the two in front of the wall. Capping by the unoccluded blend
// keeps an enclosed point next to one bright probe from taking all of it. Continuous in the weights, the
// visibility, the front factors and the normal. `probes[i]` is tet.v[i]'s SH; `front` from probeFront.
inline constexpr float kOcclusionBehindShare = 1e-3f;
// q above: how much the fallback leans on each probe (`unoccluded` = u, `front` from probeFront). The bake's
// hole rule (occlusion_holes.h) reads the largest as the probe the fallback answers with.
inline glm::vec4 fallbackLean(const glm::vec4& unoccluded, const glm::vec4& front) {
  return unoccluded * glm::max(front, glm::vec4(kOcclusionBehindShare));
}
glm::vec3 occludedIrradiance(const ShRgb* const probes[4], const glm::vec4& weights,
                             const glm::vec4& visibility, const glm::vec3& normal, const glm::vec4& front);

// occludedIrradiance for tet `tet` of `level` at local-frame point `local`: its probes' SH and their front
// factors there (probeFront). `tet` must be a valid index.
glm::vec3 occludedIrradianceAt(const Level& level, int32_t tet, const glm::vec4& weights,
                               const glm::vec4& visibility, const glm::vec3& local, const glm::vec3& normal);

}  // namespace tetraprobe
