// Tiny scenes and levels for the reference- and error-image tests: a floor under a sky (closed forms), and a
// level of probes baked over it.
#pragma once

#include <vector>

#include <glm/vec3.hpp>

#include "../bake/test_scenes.h"
#include "tetraprobe/bake/bake.h"
#include "tetraprobe/render/render.h"
#include "tetraprobe/runtime/level.h"
#include "tetraprobe/tetra/tetrahedralize.h"

namespace tetraprobe::test {

// A 200 x 200 m floor at y = 0 facing up, of albedo `albedo`, under a constant sky of radiance `sky`.
inline Scene floorUnderSky(glm::vec3 albedo, glm::vec3 sky) {
  Scene s;
  const uint32_t m = addMaterial(s, albedo);
  addGround(s, 0.0f, 100.0f, m);
  s.skyRadiance = sky;
  s.skyHorizonRadiance = sky;
  return s;
}

// floorUnderSky's geometry as the renderer takes it (no albedo: irradiance views).
inline RenderMesh floorMesh() {
  const Scene s = floorUnderSky(glm::vec3(0.5f), glm::vec3(1.0f));
  RenderMesh mesh;
  mesh.positions = s.positions;
  mesh.triangles = s.triangles;
  return mesh;
}

// Looking down at the floor from 3 m: every pixel of it sees the floor within about 15 m.
inline RenderView floorView(int width = 64, int height = 48) {
  RenderView v;
  v.eye = {0.3f, 3.0f, 4.0f};
  v.target = {0.0f, 0.0f, 0.0f};
  v.fovYDeg = 50.0f;
  v.width = width;
  v.height = height;
  return v;
}

// Probes at `world` (jittered by the caller or not), tetrahedralized, SH baked from `tracer` with the
// default content (no origin shift).
inline Level bakedLevel(const SceneTracer& tracer, const std::vector<glm::dvec3>& world, int samples = 1024) {
  Level level;
  level.origin = glm::dvec3(0.0);
  for (const glm::dvec3& p : world) level.probes.push_back(glm::vec3(p));
  BakeOptions bake;
  bake.samplesPerProbe = samples;
  bake.progress = false;
  level.sh = bakeProbes(tracer, world, bake);
  level.content = bake.content;
  level.tets = buildTetRecords(world, tetrahedralizeDelaunay(world), level.origin);
  return level;
}

// 3 x 2 x 3 probes over [-2, 2] x [0.5, 2] x [-2, 2], slightly jittered (no cospherical ties).
inline std::vector<glm::dvec3> probeGrid() {
  std::vector<glm::dvec3> world;
  for (int z = 0; z < 3; ++z)
    for (int y = 0; y < 2; ++y)
      for (int x = 0; x < 3; ++x)
        world.push_back({-2.0 + 2.0 * x + 0.03 * std::sin(1.3 * x + 2.1 * z),
                         0.5 + 1.5 * y + 0.02 * std::cos(0.7 * x + z),
                         -2.0 + 2.0 * z + 0.04 * std::sin(2.3 * y + 0.4 * x)});
  return world;
}

}  // namespace tetraprobe::test
