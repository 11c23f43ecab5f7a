// The lookup's shading (shade.h): a located point's irradiance from its tet's four probes, after per-tet
// occlusion (Valient 2014, occlusion.h) blended across faces (face_blend.h), with the all-occluded fallback
// (occludedIrradiance), and the record of how the answer was made for the tools that explain or audit it.
#include "tetraprobe/runtime/shade.h"

#include "blend_irradiance.h"
#include "tetraprobe/runtime/face_blend.h"
#include "tetraprobe/runtime/occlusion.h"
#include "tetraprobe/runtime/sh.h"

namespace tetraprobe {
namespace {

using runtime_detail::blendIrradiance;

// The record's fallback fields, which do not depend on the occlusion: each probe's own light, the front
// factors, the unoccluded blend and the probe the fallback leans on (occludedIrradiance's rule, the same
// operations so the same bits).
void describeFallback(const Level& level, const Tet& t, const Location& loc, const glm::vec3& local,
                      const glm::vec3& normal, ShadeRecord& record) {
  const ShRgb* sh[4];
  glm::vec3 toProbe[4];
  for (int i = 0; i < 4; ++i) {
    sh[i] = &level.sh[size_t(t.v[i])];
    toProbe[i] = level.probes[size_t(t.v[i])] - local;
    record.probeIrradiance[i] = shIrradiance(*sh[i], normal);
  }
  record.front = probeFront(toProbe, normal);
  const glm::vec4 u = applyOcclusion(loc.weights, glm::vec4(1.0f));
  record.unoccluded = u;
  const glm::vec4 lean = fallbackLean(u, record.front);
  int best = 0;
  for (int i = 1; i < 4; ++i)
    if (lean[i] > lean[best]) best = i;
  record.fallbackProbe = best;
  const float uf[4] = {u.x, u.y, u.z, u.w};
  record.unoccludedIrradiance = shIrradiance(shBlend(sh, uf, 4), normal);
}

}  // namespace

glm::vec3 shadeLocated(const Level& level, const LevelOcclusion* occlusion, const Location& loc,
                       const glm::dvec3& world, const glm::vec3& normal, ShadeRecord* record,
                       ShadeFrameCache* cache) {
  if (record) {
    *record = ShadeRecord{};
    record->location = loc;
  }
  if (loc.tet < 0) return glm::vec3(0.0f);
  const Tet& t = level.tets[size_t(loc.tet)];
  if (occlusion == nullptr) {
    const glm::vec3 answer = blendIrradiance(level.sh, t, loc.weights, normal);
    if (record) {
      record->weights = loc.weights;
      describeFallback(level, t, loc, glm::vec3(world - level.origin), normal, *record);
      record->answer = answer;
    }
    return answer;
  }
  const glm::vec3 local(world - level.origin);
  // Outside the hull the outer cell's weights sit on its hull tet's probes; that tet's occlusion still tells
  // which of them the point can see (a wall cutting the tet usually extends past the hull), so it applies too.
  glm::vec4 own;
  if (cache == nullptr) {
    own = occlusionVisibility(level, *occlusion, loc.tet, local, normal);
  } else {
    // The frame of a tet with occlusion data, kept while the points stay in it (the frame occlusionVisibility
    // would compute, so the same bits); a tet storing nothing sees every probe.
    if (cache->tet != loc.tet && size_t(loc.tet) < occlusion->tets.size() &&
        occlusion->tets[size_t(loc.tet)].kind() != kOcclusionNone) {
      cache->frame = baryFrame(t, level.probes);
      cache->tet = loc.tet;
    }
    own = cache->tet == loc.tet ? occlusionVisibility(level, *occlusion, loc.tet, cache->frame, local, normal)
                                : glm::vec4(1.0f);
  }
  // Near a face, blended with the neighbour's visibility of the face's probes so that the two tets' data
  // leave no seam (face_blend.h); not outside the hull, where the outer cell's weights are not the tet's.
  const glm::vec4 vis = lookupVisibility(level, *occlusion, loc, own, local, normal);
  float fallback = 0.0f;
  const glm::vec4 weights = applyOcclusion(loc.weights, vis, &fallback);
  // A point that sees (almost) none of its probes blends into the fallback (occludedIrradiance).
  const glm::vec3 answer = fallback > 0.0f
                               ? occludedIrradianceAt(level, loc.tet, loc.weights, vis, local, normal)
                               : blendIrradiance(level.sh, t, weights, normal);
  if (record) {
    record->occlusion = true;
    record->ownVisibility = own;
    record->visibility = vis;
    record->weights = weights;
    record->fallback = fallback;
    applyOcclusion(loc.weights, own, &record->ownFallback);
    describeFallback(level, t, loc, local, normal, *record);
    record->answer = answer;
  }
  return answer;
}

ShRgb shadeLocatedSh(const Level& level, const LevelOcclusion* occlusion, const Location& loc,
                     const glm::dvec3& world) {
  if (loc.tet < 0) return ShRgb{};
  const Tet& t = level.tets[size_t(loc.tet)];
  const ShRgb* sh[4];
  for (int i = 0; i < 4; ++i) sh[i] = &level.sh[size_t(t.v[i])];
  const auto blend = [&sh](const glm::vec4& w) {
    const float f[4] = {w.x, w.y, w.z, w.w};
    return shBlend(sh, f, 4);
  };
  if (occlusion == nullptr) return blend(loc.weights);
  // shadeLocated's visibility with a zero normal: the point's own, no bias, no probe behind a surface.
  const glm::vec3 local(world - level.origin), none(0.0f);
  const glm::vec4 own = occlusionVisibility(level, *occlusion, loc.tet, local, none);
  const glm::vec4 vis = lookupVisibility(level, *occlusion, loc, own, local, none);
  float fallback = 0.0f;
  const glm::vec4 weights = applyOcclusion(loc.weights, vis, &fallback);
  if (!(fallback > 0.0f)) return blend(weights);
  // occludedIrradiance's nearest-probe blend with every probe in front (front = 1), without its cap.
  const glm::vec4 u = applyOcclusion(loc.weights, glm::vec4(1.0f));
  glm::vec4 p = fallbackLean(u, glm::vec4(1.0f));
  p = p * p;
  p = p * p;
  p = p * p;
  const float ps = p.x + p.y + p.z + p.w;
  p = ps > 0.0f ? p / ps : u;
  return blend((1.0f - fallback) * weights + fallback * p);
}

}  // namespace tetraprobe
