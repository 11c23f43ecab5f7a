// SceneTracer::Impl: the Embree handles and the per-triangle tables the bake's samplers read (geometric
// normals, areas, an area CDF over all triangles and a power CDF over emissive ones). Also the
// flush-to-zero scope every tracing work item enters. Internal to the bake module.
#pragma once

#include <cstdint>
#include <vector>

#include <embree3/rtcore.h>
#include <glm/vec2.hpp>
#include <glm/vec3.hpp>

#include "tetraprobe/bake/tracer.h"

namespace tetraprobe {

struct SceneTracer::Impl {
  const Scene* scene = nullptr;
  RTCDevice device = nullptr;
  RTCScene rtcScene = nullptr;
  float rayEpsilon = 1e-6f;

  std::vector<glm::vec3> normals;  // unit geometric normal per triangle (front side); zero if degenerate
  std::vector<float> areas;        // per triangle, m^2
  std::vector<double> areaCdf;     // inclusive prefix sums of areas (for area-weighted surface points)
  double totalArea = 0.0;

  // Emissive triangles, chosen with probability proportional to power = luminance(Le) x area x pi.
  std::vector<uint32_t> emissive;      // triangle indices
  std::vector<double> emissiveCdf;     // inclusive prefix sums of power, normalised to end at 1
  std::vector<float> emissivePdfArea;  // per triangle (all triangles): P(choose it) / area, 0 if not emissive
  double emissiveArea = 0.0;           // m^2
  double emissivePower = 0.0;          // W (luminance-weighted)

  // Transparency. The triangles of materials with an alpha cutout (and texture coordinates) are Embree
  // geometry 1, whose filter functions reject hits in holes; in geometry 0 they are degenerate (never hit),
  // so geometry 0's primitive ids stay the Scene's triangle indices.
  struct Cutout {
    uint32_t triangle = 0;  // index into Scene::triangles
    glm::vec2 uv[3];        // texture coordinates of its corners
    const AlphaTexture* texture = nullptr;
    float cutoff = 0.5f;
    bool hole(float u, float v) const {
      return texture->sample(uv[0] * (1.0f - u - v) + uv[1] * u + uv[2] * v) < cutoff;
    }
  };
  std::vector<Cutout> cutouts;  // geometry 1's primitives, by increasing triangle index
  bool anyTransmission = false;

  const Material& material(uint32_t triangle) const {
    return scene->materials[scene->triangleMaterial[triangle]];
  }
  void vertices(uint32_t triangle, glm::vec3& p0, glm::vec3& p1, glm::vec3& p2) const {
    const glm::uvec3 t = scene->triangles[triangle];
    p0 = scene->positions[t.x];
    p1 = scene->positions[t.y];
    p2 = scene->positions[t.z];
  }
  glm::vec3 pointOn(uint32_t triangle, float u, float v) const {
    glm::vec3 p0, p1, p2;
    vertices(triangle, p0, p1, p2);
    return p0 * (1.0f - u - v) + p1 * u + p2 * v;
  }
};

namespace bake_detail {

// Every tracing work item of the bake enters one (parallelFor threads are short-lived, and setting the mode
// per item keeps results independent of which thread runs it).
using DenormalScope = FlushDenormalsScope;

}  // namespace bake_detail
}  // namespace tetraprobe
