// Occlusion without seams across shared faces. Each tet's occlusion data (runtime/occlusion.h) is fitted on
// its own, so two tets sharing a face can disagree on which of the face's three probes a point sees; the
// light then jumps on the face, and where one side sends the point to the all-occluded fallback and the
// other does not, a render shows hard-edged polygons. Near a face the visibility of the face's three probes
// is therefore blended with the neighbour's visibility of the same probes at the same point (the
// neighbour's data evaluated there, just outside it), so that on the face both tets use the same numbers.
//
// For the point's tet T with located weights w (w_k = 0 on the face opposite probe k), its visibility v,
// the neighbour N_k across that face, m_k = N_k's weight of its own vertex opposite the face (<= 0 in T),
// v'_i = N_k's visibility of T's probe i (i != k; 1 when N_k stores nothing), front_i = probeFront of T's
// probe i at the point (0 behind the surface) and b, b' the blindness of T and N_k at the point by their
// own visibility alone, b = 1 - smoothstep(0, kFaceBlendBlindSum, s) with s the visible weight sum
// applyOcclusion computes (1 where a side sees none of its probes; gentler than the fallback's share so
// float rounding of s moves what it drives five times less, keeping GPU and CPU within 1e-5):
//   B   = kFaceBlendBand + (kFaceBlendFallbackBand - kFaceBlendBand) b    (the band: wider where T's own
//                                             data sees nothing, so such a tet takes what its neighbours see
//                                             throughout instead of the fallback's guess)
//   x_k = max(w_k, -m_k) / B                 (distance to the face in band units, in the thinner of the two
//                                             tets: N_k's data is extrapolated at most a band of its own
//                                             height; w_k / B when N_k stores nothing)
//   a_k = 1 - smoothstep(0, 1, x_k)          (1 on the face, 0 from one band in)
//   t = 1 - (1 - kFaceBlendFallbackTrust) b,  t' likewise from b'    (trust: a side that sees none of its
//                                             probes is trusted a tenth as much as one that sees)
//   c = t / (t + t')
//   target_i = min(c v_i + (1 - c) v'_i, max(min(v_i, v'_i), front_i, max(b, b')))
//                                             (a probe behind the surface is never seen from it: the
//                                             neighbour may not raise it above the lower side's visibility,
//                                             unless a side is blind, where any light it sees beats the
//                                             fallback's guess; a ceiling's leak on q3 dm4ish came from it)
//   v_i <- v_i + sum_{k != i} a_k (target_i - v_i),   clamped to [0, 1]
// On the face opposite probe k, away from the other faces' bands, both tets get the same target for each of
// the face's probes (every term is symmetric in the two sides); their weights there agree, the fourth
// probe's is 0, so the occluded blend, the fallback's share and the fallback's answer (occludedIrradiance)
// agree: the light is continuous across the face. Within a band of an edge the tets around the edge that
// are not face neighbours are not consulted, so a smaller jump can remain along edges (tests/stability).
// Only visibility is fetched from the neighbour (its frame and occlusion record; no SH). Cost: about 1.5
// faces per point qualify; a point's occluded shading takes about twice as long on the CPU and 1.6x on
// lavapipe (docs/occlusion.md).
// Faces on the hull, faces whose two tets both store no occlusion (every probe visible on both sides), a
// neighbour storing nothing where this tet sees every probe too (nothing would change) and points outside
// the hull (outer cells) are not blended. Mirrored in shaders/tetraprobe_face_blend.glsl
// (tetraprobeFaceBlendVisibility). Permissive: standard library and GLM only.
#pragma once

#include <cstdint>

#include <glm/vec3.hpp>
#include <glm/vec4.hpp>

#include "tetraprobe/runtime/level.h"
#include "tetraprobe/runtime/occlusion_data.h"
#include "tetraprobe/runtime/query.h"

namespace tetraprobe {

inline constexpr float kFaceBlendBand = 0.15f;          // band half-width, barycentric (of the thinner tet)
inline constexpr float kFaceBlendFallbackTrust = 0.1f;  // t of a side that sees none of its probes
inline constexpr float kFaceBlendBlindSum = 0.05f;      // visible weight sum from which a side is not blind
inline constexpr float kFaceBlendFallbackBand = 0.3f;   // the band where the tet's own data sees nothing
                                                        // (past the centroid's 0.25: the whole tet)

// Which faces the blend consults. kFaceBlendFlaggedFaces (what the lookup does, CPU and GPU): only the
// faces faceBlendFaceFlag sets, the same answer bit for bit as kFaceBlendEveryFace (every face, the rule
// without the flag; for tests that prove it: tests/runtime/test_face_blend.cpp).
enum FaceBlendFaces { kFaceBlendFlaggedFaces, kFaceBlendEveryFace };

// The blend above for a point at local-frame `local` (normal as occlusionVisibility takes it) inside tet
// `tet` (a valid index; not for points outside the hull) with located weights `weights` (non-negative,
// summing to 1) and the tet's own visibility `visibility` (occlusionVisibility). Returns `visibility`
// unchanged where no face qualifies (every w_k at least the band). Finite for finite input.
glm::vec4 faceBlendVisibility(const Level& level, const LevelOcclusion& occlusion, int32_t tet,
                              const glm::vec4& weights, const glm::vec4& visibility, const glm::vec3& local,
                              const glm::vec3& normal, FaceBlendFaces faces = kFaceBlendFlaggedFaces);

// The face flag, a static property of the level computed at upload (packed into the GPU's occlusion record,
// gpu_layout.h): true when the blend across face k of `tet` may change a visibility, false where it cannot:
// a hull face (no neighbour), or a face whose three probes both sides see at exactly 1.0 wherever their data
// is evaluated (no data; one plane whose cells all see the probe; a shadow map of the probe that meets
// nothing), where every target of the blend is 1 and so equals the visibility it would move. Which faces do
// blend where the flag is set is still decided per point (the band, a neighbour without data where this tet
// sees every probe). faceBlendMask: the four flags, bit k for face k (0 for an index out of range).
bool faceBlendFaceFlag(const Level& level, const LevelOcclusion& occlusion, int32_t tet, int k);
uint32_t faceBlendMask(const Level& level, const LevelOcclusion& occlusion, int32_t tet);

// The visibility of the located tet's probes the run-time lookup uses (shadeLocated, shade.h;
// tetraprobeLookupVisibility), from the tet's own `visibility` (occlusionVisibility at `local`, `normal`):
// blended near faces by faceBlendVisibility when the point is inside the hull (loc.outerCell < 0), else
// unchanged (outside the hull, no tet, or a level without occlusion).
glm::vec4 lookupVisibility(const Level& level, const LevelOcclusion& occlusion, const Location& loc,
                           const glm::vec4& visibility, const glm::vec3& local, const glm::vec3& normal);

}  // namespace tetraprobe
