// Occlusion without seams across faces, edges and corners. Each tet's occlusion data (runtime/occlusion.h) is
// fitted on its own, so two tets holding a probe can disagree on whether a point sees it; the light then
// jumps where the point crosses from one tet to the other, and where one side sends the point to the
// all-occluded fallback and the other does not, a render shows hard-edged polygons. The visibility of each
// probe is therefore a partition of unity over the tets around the point that hold the probe: every such tet
// S evaluates its own data at the point (just outside S, its data extrapolated), weighted by how far the
// point lies inside S's band, and those weights are functions of the point alone, so every tet holding the
// point computes the same visibility of a shared probe: continuous across faces, along edges (the ring of
// tets around an edge) and at corners (the star of a vertex).
//
// For the point x in tet T with located weights w and own visibility v, and each probe p of T:
//   omega_S(x) = 1 - smoothstep(0, 1, d),  d = sum over S's weights w_S,g(x) < 0 of
//                -w_S,g(x) max(1, H_S,g / H_M,g) / B
//                                             (S's barycentric weights extrapolated, H_S,g and H_M,g the
//                                             heights of S and of the tet M across face g over it, read from
//                                             M's vertex off the face: the depth past the face counts in the
//                                             thinner tet's units, so a tet's data reaches at most a band of
//                                             the thinner tet past a face; a hull face: ratio 1. 1 on and
//                                             inside S, 0 one band out, sooner near its edges and corners; a
//                                             sliver's data never reaches far)
//   b_S = 1 - smoothstep(0, kFaceBlendBlindSum, s_S)   (blindness: s_S the visible weight sum applyOcclusion
//                                             computes from S's weights and visibility at x; 1 where S sees
//                                             none of its probes; gentler than the fallback's share so float
//                                             rounding of s moves what it drives five times less)
//   tau_S = 1 - (1 - kFaceBlendFallbackTrust) b_S      (a blind tet is trusted a tenth as much)
//   avg_p = sum_S omega_S tau_S v_S,p / sum_S omega_S tau_S        (S over the tets holding p, T included)
//   m_p   = min_S (omega_S v_S,p + 1 - omega_S)        (the lowest visibility, faded in with its tet)
//   beta  = max_S omega_S b_S                          (over every tet found)
//   v_p  <- min(avg_p, max(m_p, front_p, beta)),  clamped to [0, 1]
//                                             (a probe behind the surface, front_p = 0 from probeFront, is
//                                             never raised above the lowest tet's visibility, unless a tet is
//                                             blind, where any light it sees beats the fallback's guess; a
//                                             ceiling's leak on q3 dm4ish came from it)
// with B = kFaceBlendBand. Where the result is still blind (b, from T's weights and the blended v, above 0)
// a second pass runs with B' = kFaceBlendBand + (kFaceBlendFallbackBand - kFaceBlendBand) b and each depth in
// the reaching tet's own units (ratio 1), and is mixed in by b: v <- v + b (v' - v). So a larger
// neighbour's sight reaches through the whole of a small tet whose own data sees nothing, instead of the
// fallback's guess. Every term is a continuous function of x (b and B' too: T's weights of an off-face
// probe vanish on the face), so the light is continuous across every face, edge and corner. Where no other
// tet reaches x (deep inside T) v is unchanged; where only T holds p, v_p is unchanged; where every tet
// holding p sees it at exactly 1, v_p = 1 exactly.
//
// The tets are found breadth first from T across faces, taking a tet that holds one of T's blended probes
// and reaches x (omega > 0), at most kFaceBlendMaxTets looked at (a corner's star: about 20). A reaching tet
// U lists its neighbour M across face k only where M may reach x: in the first pass where w_U,k(x) < B (the
// thinner-tet depth makes omega_M 0 beyond, a test on weights U has), in the blind pass where
// w_U,k(x) < B' H_M / H_U (read from M's vertex off the face). So deep inside T nothing else is read. Only
// visibility is fetched from the other tets (frame, occlusion record; no SH). Cost and figures:
// docs/occlusion.md and docs/accuracy.md.
// Points outside the hull (outer cells) are not blended. Mirrored in shaders/tetraprobe_face_blend.glsl
// (tetraprobeFaceBlendVisibility). Permissive: standard library and GLM only.
#pragma once

#include <cstdint>
#include <vector>

#include <glm/vec3.hpp>
#include <glm/vec4.hpp>

#include "tetraprobe/runtime/level.h"
#include "tetraprobe/runtime/occlusion_data.h"
#include "tetraprobe/runtime/query.h"

namespace tetraprobe {

inline constexpr float kFaceBlendBand = 0.15f;          // B: band width, barycentric (of the tet reaching)
inline constexpr float kFaceBlendFallbackTrust = 0.1f;  // tau of a tet that sees none of its probes
inline constexpr float kFaceBlendBlindSum = 0.05f;      // visible weight sum from which a tet is not blind
inline constexpr float kFaceBlendFallbackBand = 0.3f;   // the band where the point is blind after the first
                                                        // pass (past the centroid's 0.25: the whole tet)
inline constexpr int kFaceBlendMaxTets = 48;            // tets the search looks at, the point's own included
inline constexpr int kFaceBlendStarTets = 256;          // tets faceBlendProbeFlag walks around one probe

// Which probes the blend computes. kFaceBlendEveryProbe: all four (the CPU lookup). kFaceBlendFlaggedProbes:
// only those faceBlendMask flags (what the GPU does, the flags packed at upload), the same answer bit for
// bit (tests/occlusion/test_shade.cpp proves it).
enum FaceBlendProbes { kFaceBlendEveryProbe, kFaceBlendFlaggedProbes };

// The blend above for a point at local-frame `local` (normal as occlusionVisibility takes it) inside tet
// `tet` (a valid index; not for points outside the hull) with located weights `weights` (non-negative,
// summing to 1) and the tet's own visibility `visibility` (occlusionVisibility). Returns `visibility`
// unchanged where no other tet reaches the point. Finite for finite input.
glm::vec4 faceBlendVisibility(const Level& level, const LevelOcclusion& occlusion, int32_t tet,
                              const glm::vec4& weights, const glm::vec4& visibility, const glm::vec3& local,
                              const glm::vec3& normal, FaceBlendProbes which = kFaceBlendEveryProbe);

// The probe flag, a static property of the level computed at upload (packed into the GPU's occlusion record,
// gpu_layout.h): true when some tet holding probe tet.v[i] (its star, walked across faces) may hide it,
// false where every such tet sees it at exactly 1.0 wherever its data is evaluated (no data; one plane whose
// cells all see the probe; a shadow map of the probe that meets nothing), so the blend cannot move it; true
// too when the star has more than kFaceBlendStarTets tets. faceBlendMask: the four flags, bit i for probe
// slot i (0 for an index out of range).
bool faceBlendProbeFlag(const Level& level, const LevelOcclusion& occlusion, int32_t tet, int i);
uint32_t faceBlendMask(const Level& level, const LevelOcclusion& occlusion, int32_t tet);

// faceBlendMask of every tet at once, in time linear in the tets (a probe's flag from every tet holding it;
// a probe held by more than kFaceBlendStarTets tets flagged): the same masks as faceBlendMask where every
// probe's star is connected across its faces, as in any level the bake writes (the upload packs these).
std::vector<uint8_t> faceBlendMasks(const Level& level, const LevelOcclusion& occlusion);

// Whether tet `tet` may take part in the blend (omega > 0) at some point of the box [lo, hi] (local frame,
// metres) at the widest band (kFaceBlendFallbackBand, plus 1 % for the run time's float rounding). The
// region where omega > 0 is convex, the intersection of the 15 half-spaces -sum_{g in P} w_g < band over
// the non-empty sets P of the tet's vertices; false only where the box lies wholly outside one of them or
// outside the region's own box (from its vertices). Conservative: true for a flat tet.
// The region with the thinner-tet depth lies inside this one. A streamed sector carries the tets sharing a
// probe with its own that may reach its cell and their face neighbours (whose heights omega reads;
// tetra/stream_index.h), so a loaded sector answers as the full level does.
bool faceBlendMayReach(const Level& level, int32_t tet, const glm::dvec3& lo, const glm::dvec3& hi);

// The tets holding probe tet.v[i] that a walk across the faces holding it reaches from `tet` (its star; tet
// first), at most kFaceBlendStarTets: the tets whose probe flags change when one of them changes (a GPU
// sector pool rewrites them when a sector is linked or cut). Empty for an index out of range.
std::vector<int32_t> faceBlendStar(const Level& level, int32_t tet, int i);

// The visibility of the located tet's probes the run-time lookup uses (shadeLocated, shade.h;
// tetraprobeLookupVisibility), from the tet's own `visibility` (occlusionVisibility at `local`, `normal`):
// blended by faceBlendVisibility when the point is inside the hull (loc.outerCell < 0), else
// unchanged (outside the hull, no tet, or a level without occlusion).
glm::vec4 lookupVisibility(const Level& level, const LevelOcclusion& occlusion, const Location& loc,
                           const glm::vec4& visibility, const glm::vec3& local, const glm::vec3& normal);

}  // namespace tetraprobe
