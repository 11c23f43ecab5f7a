// The lookup's shading: the irradiance a located point gets from its tet's four probes, with per-tet
// occlusion (occlusion.h) and the face blend (face_blend.h) applied, and on request a record of how that
// answer was made. The one C++ implementation of the rule: ProbeQuery::irradiance and irradianceBatch,
// eval's tet+occlusion method, `tetraprobe query --explain` and the bake's occlusion-hole finder all call
// shadeLocated(); shaders/tetraprobe.glsl mirrors it (tetraprobeIrradiance). Its per-object SH form,
// shadeLocatedSh(), serves ProbeQuery::interpolatedSh.
// Permissive: standard library and GLM only.
#pragma once

#include <cstdint>

#include <glm/vec3.hpp>
#include <glm/vec4.hpp>

#include "tetraprobe/runtime/level.h"
#include "tetraprobe/runtime/occlusion_data.h"
#include "tetraprobe/runtime/query.h"
#include "tetraprobe/runtime/sh.h"

namespace tetraprobe {

// How an answer was made, slot i being the located tet's probe tet.v[i]. Filled by shadeLocated() when asked;
// for a location with no tet (tet < 0: an empty level) it keeps these defaults and answer 0.
struct ShadeRecord {
  Location location;              // the location shaded (as given)
  bool occlusion = false;         // whether an occlusion set was applied (shadeLocated's `occlusion`)
  glm::vec4 ownVisibility{1.0f};  // [0, 1] per probe by the tet's own data (occlusionVisibility); 1 without
  glm::vec4 visibility{1.0f};     // after the face blend (lookupVisibility): what the answer uses
  glm::vec4 weights{0.0f};        // the weights the answer blends: applyOcclusion(location.weights,
                                  // visibility) with occlusion, else location.weights
  float fallback = 0.0f;          // the fallback's share in the answer (applyOcclusion's from `visibility`,
                                  // 0 without occlusion); > 0: occludedIrradiance gave the answer
  float ownFallback = 0.0f;       // the share the tet's own data alone gives (from ownVisibility, before the
                                  // face blend): what the bake's hole finder counts (occlusion_holes.h)
  glm::vec4 unoccluded{0.0f};     // u = applyOcclusion(location.weights, 1): the fallback's capping blend
  glm::vec4 front{1.0f};          // probeFront of each probe at the point (1: in front, 0: on or behind)
  int fallbackProbe = -1;         // slot of the probe the fallback leans on (the largest
                                  // fallbackLean(u, front), the first of equals); computed with or without
                                  // occlusion, whether or not the fallback ran
  glm::vec3 probeIrradiance[4] = {};     // E(normal) of each probe alone, W/m^2
  glm::vec3 unoccludedIrradiance{0.0f};  // E(normal) of blend u, W/m^2: the per-channel cap of the fallback
  glm::vec3 answer{0.0f};                // what shadeLocated returned, W/m^2
};

// A tet's BaryFrame kept between calls that shade points of the same tet one after another
// (irradianceBatch): the answer is the same, bit for bit, with or without it. Start with tet = -1.
struct ShadeFrameCache {
  int32_t tet = -1;  // the tet whose frame `frame` holds (a tet storing occlusion), or -1
  BaryFrame frame;
};

// Irradiance E in W/m^2 at world-space point `world` (metres; the level's origin is subtracted in double,
// then the local point is taken in float) on a surface with normal `normal` (any length; zero for volumes:
// no bias, every probe counted in front), located at `loc` (ProbeQuery::locate of `world`, or any Location of
// `level` with non-negative weights summing to 1 on tet.v[0..3]).
//   occlusion null: E = the tets' SH blended with loc.weights (shIrradiance(shBlend(...)), bit for bit).
//   occlusion given (usually &level.occlusion; any set built for `level`'s tets, an empty one making every
//   probe visible): v = lookupVisibility(level, *occlusion, loc, occlusionVisibility(...), local, normal)
//   (the tet's own visibility, blended near faces inside the hull), w = applyOcclusion(loc.weights, v, &f);
//   E = the SH blended with w where f is 0, else occludedIrradianceAt(level, loc.tet, loc.weights, v, ...)
//   (the fallback toward the nearest probe in front, capped by the unoccluded blend).
// A location with tet < 0 gives 0. `record` (optional) receives how the answer was made (ShadeRecord; its
// extra fields cost a few SH evaluations); the answer does not depend on it. `cache` (optional): see
// ShadeFrameCache. Allocates nothing; never throws; finite for finite input. Thread-safe for concurrent calls
// with distinct records and caches.
glm::vec3 shadeLocated(const Level& level, const LevelOcclusion* occlusion, const Location& loc,
                       const glm::dvec3& world, const glm::vec3& normal, ShadeRecord* record = nullptr,
                       ShadeFrameCache* cache = nullptr);

// The interpolated SH (incident radiance, W/(m^2 sr), sh.h's basis and order; an L1 level's coefficients 4..8
// stay 0) at `world` located at `loc` (as shadeLocated takes them), for an object that shades its own normals
// from it afterwards (ProbeQuery::interpolatedSh). Occlusion is decided once for the point itself, not per
// surface: the visibility is shadeLocated's with a zero normal (no bias off a surface, every probe counted in
// front), blended near faces the same way, so that
//   occlusion null: shIrradiance(shadeLocatedSh(...), n) == shadeLocated(..., n) bit for bit, for every n;
//   occlusion given: the SH of applyOcclusion(loc.weights, v) with v = lookupVisibility(..., normal 0); where
//   the fallback's share f is > 0, (1 - f) of that plus f of occludedIrradiance's nearest-probe blend
//   p = u^8 / sum u^8 (every probe in front). occludedIrradiance's per-channel cap min(E(p), E(u)) depends
//   on the normal and has no SH form, so it is left out: there the SH may be brighter than shadeLocated's.
// Every case is a convex blend (non-negative weights summing to 1) of tet.v[0..3]'s SH. A location with
// tet < 0 gives zero SH. Allocates nothing; never throws; thread-safe.
ShRgb shadeLocatedSh(const Level& level, const LevelOcclusion* occlusion, const Location& loc,
                     const glm::dvec3& world);

}  // namespace tetraprobe
