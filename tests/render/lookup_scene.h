// The GPU lookup tests' scene: a small jittered probe lattice far from the world origin with distinct SH,
// synthetic occlusion, a mesh inside and outside the hull, a camera; and a render that skips without Vulkan.
#pragma once

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <stdexcept>
#include <string>

#include "missing_capability.h"
#include "tetraprobe/render/render.h"
#include "tetraprobe/runtime/occlusion.h"
#include "tetraprobe/runtime/query.h"
#include "tetraprobe/runtime/sh_half.h"
#include "tetraprobe/tetra/tetrahedralize.h"

namespace tetraprobe::test {

// Far from the world origin on purpose: the renderer must subtract it in double.
inline const glm::dvec3 kOrigin(1000.0, -20.0, 500.0);

// 4x3x4 probes on a 1 m grid over local [0,3]x[0,2]x[0,3], slightly jittered (no cospherical ties), with
// distinct SH per probe: a linear field in L00 plus position-dependent L1 and L2 terms. E stays positive
// (L00 dominates), so a relative error is meaningful everywhere.
inline Level makeLevel() {
  Level level;
  level.origin = kOrigin;
  std::vector<glm::dvec3> world;
  for (int z = 0; z < 4; ++z)
    for (int y = 0; y < 3; ++y)
      for (int x = 0; x < 4; ++x) {
        const glm::dvec3 local(x + 0.07 * std::sin(1.3 * x + 2.1 * y + 0.7 * z),
                               y + 0.05 * std::cos(0.9 * x + 1.7 * z),
                               z + 0.06 * std::sin(2.3 * y + 0.4 * x));
        world.push_back(kOrigin + local);
        level.probes.push_back(glm::vec3(local));
        ShRgb sh;
        const glm::vec3 p(local);
        sh.c[0] = glm::vec3(2.0f + 0.4f * p.x, 1.5f + 0.3f * p.y, 1.0f + 0.2f * p.z);
        sh.c[1] = glm::vec3(0.2f * p.y, -0.1f, 0.05f * p.x);
        sh.c[2] = glm::vec3(-0.15f, 0.1f * p.z, 0.2f);
        sh.c[3] = glm::vec3(0.1f * p.x, 0.05f, -0.1f * p.z);
        for (int i = 4; i < 9; ++i)
          sh.c[i] = glm::vec3(0.03f * float(i - 6) + 0.01f * p.x, 0.02f * p.y, -0.02f * float(i - 5));
        level.sh.push_back(quantizeSh(sh));  // as a level file and the GPU hold them: CPU == GPU bit for bit
      }
  const TetMesh mesh = tetrahedralizeDelaunay(world);
  level.tets = buildTetRecords(world, mesh, kOrigin);
  return level;
}

// Synthetic occlusion on every tet of `level` (no geometry needed): tets alternate 1..3 random planes, each
// cell seeing a random non-empty probe set, and random shadow maps, so the GPU mirror of
// evaluateTetOcclusion, the normal bias and applyOcclusion is exercised on every pixel inside the hull.
inline LevelOcclusion syntheticOcclusion(const Level& level) {
  LevelOcclusion occ;
  std::mt19937 rng(11);
  std::uniform_real_distribution<float> u(-1.0f, 1.0f);
  for (size_t t = 0; t < level.tets.size(); ++t) {
    if (t % 4 != 3) {
      const uint32_t count = uint32_t(t % 4) + 1;
      uint32_t cells = 0;
      for (uint32_t c = 0; c < (1u << count); ++c) cells |= (1u + uint32_t(rng()) % 15u) << (4 * c);
      occ.tets.push_back(makeTetOcclusion(kOcclusionPlanes, count, uint32_t(occ.planes.size()), cells));
      for (uint32_t k = 0; k < count; ++k) {
        const double a = u(rng), b = u(rng), c = u(rng), d = u(rng);
        occ.planes.push_back(makeOcclusionPlane(a, b, c, d));
      }
    } else {
      occ.tets.push_back(makeTetOcclusion(kOcclusionShadowMaps, 0,
                                          uint32_t(occ.shadowMaps.size() / kShadowMapBlockBytes), 0));
      for (int b = 0; b < kShadowMapBlockBytes; ++b)
        occ.shadowMaps.push_back(b % 16 == 15 ? kShadowMapNoHit : uint8_t(60 + rng() % 196));
    }
  }
  return occ;
}

inline void addQuad(RenderMesh& mesh, glm::vec3 a, glm::vec3 b, glm::vec3 c, glm::vec3 d, glm::vec3 albedo) {
  // a b c d counter-clockwise seen from the front.
  const auto base = uint32_t(mesh.positions.size());
  for (glm::vec3 p : {a, b, c, d}) mesh.positions.push_back(glm::vec3(kOrigin) + p);
  mesh.triangles.push_back({base, base + 1, base + 2});
  mesh.triangles.push_back({base, base + 2, base + 3});
  mesh.triangleAlbedo.push_back(albedo);
  mesh.triangleAlbedo.push_back(albedo);
}

// Local coordinates written relative to the origin; the mesh stores world positions (float: the origin is
// exactly representable, and so are these small offsets' sums to within float rounding).
inline RenderMesh makeMesh() {
  RenderMesh m;
  // Inside the hull: a floor at y = 0.5 facing up, a tilted panel, a wall facing +z.
  addQuad(m, {0.3f, 0.5f, 2.7f}, {2.7f, 0.5f, 2.7f}, {2.7f, 0.5f, 0.3f}, {0.3f, 0.5f, 0.3f},
          {0.8f, 0.6f, 0.4f});
  addQuad(m, {0.4f, 0.9f, 1.6f}, {1.6f, 0.9f, 1.6f}, {1.6f, 1.7f, 0.6f}, {0.4f, 1.7f, 0.6f},
          {0.3f, 0.7f, 0.9f});
  addQuad(m, {1.8f, 0.6f, 1.2f}, {2.6f, 0.6f, 1.2f}, {2.6f, 1.8f, 1.2f}, {1.8f, 1.8f, 1.2f},
          {0.9f, 0.9f, 0.9f});
  // Outside the hull: a slab above it, a wall beyond -x, a floor in front of +z.
  addQuad(m, {0.5f, 2.6f, 2.5f}, {2.0f, 2.6f, 2.5f}, {2.0f, 2.6f, 1.0f}, {0.5f, 2.6f, 1.0f},
          {0.5f, 0.5f, 0.5f});
  addQuad(m, {-0.8f, 0.0f, 3.2f}, {-0.8f, 0.0f, 0.2f}, {-0.8f, 2.4f, 0.2f}, {-0.8f, 2.4f, 3.2f},
          {0.7f, 0.3f, 0.3f});
  addQuad(m, {0.0f, -0.4f, 4.5f}, {3.5f, -0.4f, 4.5f}, {3.5f, -0.4f, 3.3f}, {0.0f, -0.4f, 3.3f},
          {0.2f, 0.8f, 0.2f});
  return m;
}

inline RenderView makeView(RenderMode mode, int width = 320, int height = 180) {
  RenderView v;
  v.eye = glm::vec3(kOrigin + glm::dvec3(5.5, 5.0, 8.0));
  v.target = glm::vec3(kOrigin + glm::dvec3(1.2, 0.8, 1.6));
  v.fovYDeg = 55;
  v.width = width;
  v.height = height;
  v.mode = mode;
  return v;
}

// Renders, or returns false (and the reason in `skip`) on a machine without a Vulkan driver or device.
inline bool render(const RenderMesh& mesh, const Level& level, const ProbeQuery& query,
                   const RenderView& view, RenderResult& out, std::string& skip,
                   const RenderOptions& options = {}) {
  try {
    out = renderLevel(mesh, level, query, view, options);
    return true;
  } catch (const std::runtime_error& e) {
    const std::string what = e.what();
    if (isNoVulkan(what)) {
      skip = what;
      return false;
    }
    throw;
  }
}

#define RENDER_OR_SKIP(mesh, level, query, view, out)                                  \
  do {                                                                                 \
    std::string skip_;                                                                 \
    if (!render(mesh, level, query, view, out, skip_)) TETRAPROBE_SKIP_MISSING(skip_); \
  } while (0)

inline glm::vec3 px3(const Image& im, size_t i) {
  return {im.rgba[4 * i], im.rgba[4 * i + 1], im.rgba[4 * i + 2]};
}

}  // namespace tetraprobe::test
