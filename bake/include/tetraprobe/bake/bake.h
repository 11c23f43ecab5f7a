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
  int bounces = 2;                      // diffuse bounces after the first hit (0 = direct light only)
  int samplesPerProbe = 256;            // paths per probe
  int threads = 0;                      // 0 = all cores; never changes the result
  uint32_t content = kContentDefault;   // which light the probes hold (ProbeContent flags)
  uint64_t seed = 0x7e77a9b0be5eedull;  // base seed; each probe/point derives its own from it and its index
  bool progress = true;                 // progress bar on a terminal
};

// Bakes one SH per probe (world-space positions). Deterministic for any `threads`.
// Per probe: options.samplesPerProbe directions (bakeSphereDirections keyed by the seed and the probe index),
// incident radiance L(d) by path tracing (options.bounces, options.content), projected with projectToSh.
// With kContentDirectPunctual, each unshadowed point/spot light adds (I spot / r^2) Y(d) and each unshadowed
// sun E Y(d) (d towards the light, or the sun disc's centre) analytically: the delta's exact projection.
// Probes inside geometry are baked like any other (filter them with probesInsideGeometry).
// Throws InputError for samplesPerProbe < 1, bounces < 0 or a non-finite probe position.
std::vector<ShRgb> bakeProbes(const SceneTracer& tracer, const std::vector<glm::dvec3>& probes,
                              const BakeOptions& options);

// The bake's direction set over the unit sphere: an n-point spherical Fibonacci set under a uniformly random
// rotation derived from `key` (the probe bake uses key = hash(seed, probe index)). Each direction is
// marginally uniform, so projectToSh of it is an unbiased randomised-QMC estimate.
std::vector<glm::vec3> bakeSphereDirections(int count, uint64_t key);

// Monte Carlo SH projection over the sphere: L_lm = 4 pi / N sum_k radiance[k] Y_lm(dirs[k]) (N =
// dirs.size(), accumulated in double). `radiance` has one entry per direction, W/(m^2 sr). Empty input gives
// zeros.
ShRgb projectToSh(const std::vector<glm::vec3>& dirs, const std::vector<glm::vec3>& radiance);

// Adds the exact projection of a delta of irradiance `irradiance` (W/m^2, perpendicular) arriving from unit
// direction `dir`: sh[i] += irradiance * Y_i(dir).
void addDeltaToSh(ShRgb& sh, const glm::vec3& dir, const glm::vec3& irradiance);

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
// Each of `samples` samples: NEE of the emissive triangles (MIS, power heuristic) + exact punctual
// irradiance (I cos / r^2, sampled only for sun discs and light radii) + pi x the radiance of one
// cosine-sampled path. Rays start at point + normal x tracer.rayEpsilon(); punctual distances and cosines
// use the exact point. stderror = sample standard deviation / sqrt(samples) (per-sample variance).
// Single-threaded (callers parallelise over points). samples < 1 gives zeros with samples = 0. Throws
// InputError for a non-finite point, a zero or non-finite normal, or bounces < 0.
ReferenceIrradiance referenceIrradiance(const SceneTracer& tracer, const glm::dvec3& point,
                                        const glm::vec3& normal, int samples, uint64_t seed,
                                        const BakeOptions& options);

struct SurfacePoint {
  glm::dvec3 position{0.0};
  glm::vec3 normal{0.0f};  // unit, pointing into open space (the side a viewer could see)
  glm::vec3 albedo{0.0f};
  uint32_t triangle = 0;
};

// `count` random points on the scene's surfaces, area-weighted, each on a side that faces open space
// (points whose both sides are enclosed are skipped and redrawn). Deterministic for a given seed.
// A side is open when at most 25 % of 32 uniform-hemisphere rays from the point (offset by
// tracer.rayEpsilon() along that side's normal) hit back faces -- or, when the sky is black, hit back faces
// or escape (the level is an interior and the void is its outside); the front side wins when both are open.
// At most 20 x count draws: may return fewer than `count` points when most surface is enclosed.
std::vector<SurfacePoint> sampleSurfacePoints(const SceneTracer& tracer, int count, uint64_t seed);

}  // namespace tetraprobe
