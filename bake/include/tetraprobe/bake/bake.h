// Probe radiance baking: path-traced incident radiance projected onto SH L2 RGB, and the ground-truth
// reference oracle used by the evaluation. Build side.
#pragma once

#include <cstdint>
#include <vector>

#include <glm/vec3.hpp>

#include "tetraprobe/bake/tracer.h"
#include "tetraprobe/runtime/level.h"
#include "tetraprobe/runtime/sh.h"

namespace tetraprobe {

struct BakeOptions {
  int bounces = 2;                       // diffuse bounces after the first hit (0 = direct light only)
  int samplesPerProbe = 256;             // paths per probe
  int threads = 0;                       // 0 = all cores; never changes the result
  uint32_t content = kContentDefault;    // which light the probes hold (ProbeContent flags)
  uint64_t seed = 0x7e77a9b0be5eedull;   // base seed; each probe/point derives its own from it and its index
  bool progress = true;                  // progress bar on a terminal
};

// Bakes one SH per probe (world-space positions). Deterministic for any `threads`.
std::vector<ShRgb> bakeProbes(const SceneTracer& tracer, const std::vector<glm::dvec3>& probes,
                              const BakeOptions& options);

// For each point, true when it is inside geometry: more than `backFaceFraction` of `rays` uniformly
// distributed rays hit back faces (the Unity APV rule, 25 %). Deterministic.
std::vector<uint8_t> probesInsideGeometry(const SceneTracer& tracer, const std::vector<glm::dvec3>& points,
                                          int rays = 64, double backFaceFraction = 0.25, int threads = 0);

struct ReferenceIrradiance {
  glm::vec3 irradiance{0.0f};  // W/m^2, same light content as the probes (options.content)
  glm::vec3 stderror{0.0f};    // standard error of the estimate, per channel
  int samples = 0;
};

// Ground-truth irradiance at a surface point with unit normal `normal` (the point is offset along the
// normal by a small epsilon internally). `seed` makes it reproducible. Uses options.bounces/content.
ReferenceIrradiance referenceIrradiance(const SceneTracer& tracer, const glm::dvec3& point,
                                        const glm::vec3& normal, int samples, uint64_t seed,
                                        const BakeOptions& options);

struct SurfacePoint {
  glm::dvec3 position{0.0};
  glm::vec3 normal{0.0f};   // unit, pointing into open space (the side a viewer could see)
  glm::vec3 albedo{0.0f};
  uint32_t triangle = 0;
};

// `count` random points on the scene's surfaces, area-weighted, each on a side that faces open space
// (points whose both sides are enclosed are skipped and redrawn). Deterministic for a given seed.
std::vector<SurfacePoint> sampleSurfacePoints(const SceneTracer& tracer, int count, uint64_t seed);

}  // namespace tetraprobe
