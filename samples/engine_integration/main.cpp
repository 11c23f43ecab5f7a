// engine_integration: what a game does with a baked level, through the installed package only.
// Loads a level, moves a sphere along a path through it, and lights the sphere two ways each frame:
// - per object: one ProbeQuery::interpolatedSh at the sphere's centre (the L2 SH a forward shader takes, as
//   Unity's GetInterpolatedProbe), with the tet cached from the previous frame, so each frame's walk starts
//   next to where it ends; every surface normal is then shaded from that SH (shIrradiance);
// - per pixel: the irradiance at each of the sphere's surface points with its own normal, in one
//   irradianceBatch call (CPU; the GPU side below runs the same lookup per pixel in a shader, tetraprobe.glsl).
// It prints a line per frame: the per-object error against the per-pixel answer over the sphere, and at the
// centre the largest relative difference between the SH's and irradiance()'s answer over the six axis
// normals (0 without occlusion; with it the SH sees the probes from the centre, irradiance() from a surface).
// Then the GPU side (gpu_level.cpp, skipped without a Vulkan device): the level's six storage buffers
// uploaded to device-local memory through a staging copy recorded into the engine's command buffer, the
// buffers the engine owns printed, the last frame's sphere shaded per pixel by the engine's own compute pass
// including tetraprobe.glsl (surface_lighting.h; against the CPU's answers), and part of the level relit in
// place (setProbeSh + cmdUpdateLevelSh) and shaded again.
// Left out: a window and meshes (the sphere's surface points stand in for a G-buffer).
// Checks its own results (exit 1 on failure): the cached walk answers as an uncached locate, every value is
// finite, the sphere is darker in the room the lamp does not see (two_rooms: x > 4.2) than in the lit one,
// the GPU's pixels equal the CPU's within 1e-4 relative before and after the relight, and the GPU's probe
// buffer after the relight equals the packing of the relit level byte for byte.
//
// With --stream (a level with a streaming index, `tetraprobe stream`): the GPU side only, streamed by sector
// (gpu_streaming.cpp): a camera's loop over the level with a fixed-size GPU pool within BUDGET (a share of
// the full level's GPU bytes, default 0.25), a line per frame, each frame's view shaded from the pool by the
// same lighting pass and checked against the whole level where sectors are loaded.
//
// Usage: engine_integration LEVEL.tpb [FROM_X,Y,Z TO_X,Y,Z]  (default path: the two_rooms sample's rooms)
//        engine_integration LEVEL.tpb --stream [BUDGET [FRAMES]]
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <numbers>
#include <vector>

#include <tetraprobe/runtime/level.h>
#include <tetraprobe/runtime/luminance.h>
#include <tetraprobe/runtime/query.h>
#include <tetraprobe/runtime/sh.h>

#include "gpu_level.h"
#include "gpu_streaming.h"

namespace {

using tetraprobe::luminance;  // Rec. 709

bool parseVec(const char* s, glm::dvec3& v) {
  return std::sscanf(s, "%lf,%lf,%lf", &v.x, &v.y, &v.z) == 3;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc >= 3 && argc <= 5 && std::strcmp(argv[2], "--stream") == 0) {
    const double budget = argc >= 4 ? std::atof(argv[3]) : 0.25;
    const int frames = argc >= 5 ? std::atoi(argv[4]) : 96;
    if (!(budget > 0.0 && budget <= 1.0) || frames < 1) {
      std::fprintf(stderr, "engine_integration: BUDGET in (0, 1], FRAMES >= 1\n");
      return 2;
    }
    if (!std::filesystem::exists(argv[1])) {
      std::fprintf(stderr, "engine_integration: %s: cannot open\n", argv[1]);
      return 2;
    }
    const bool ok = runGpuStreaming(argv[1], budget, frames);
    std::printf("%s\n", ok ? "ok" : "FAILED");
    return ok ? 0 : 1;
  }
  glm::dvec3 from(1.5, 1.0, 2.0), to(7.2, 1.0, 2.0);  // room A, through the doorway, into room B
  if (argc != 2 && !(argc == 4 && parseVec(argv[2], from) && parseVec(argv[3], to))) {
    std::fprintf(stderr,
                 "usage: engine_integration LEVEL.tpb [FROM_X,Y,Z TO_X,Y,Z]\n"
                 "       engine_integration LEVEL.tpb --stream [BUDGET [FRAMES]]\n");
    return 2;
  }
  tetraprobe::Level level;
  if (auto r = tetraprobe::loadLevel(argv[1], level); !r) {
    std::fprintf(stderr, "engine_integration: %s\n", r.message.c_str());
    return 2;
  }
  const tetraprobe::ProbeQuery query(level);
  std::printf("level: %zu probes, %zu tets, SH L%u, occlusion %s\n", level.probes.size(), level.tets.size(),
              level.shOrder, level.occlusion.empty() ? "none" : "stored");

  // The sphere's surface points (latitude-longitude) and normals, relative to its centre.
  const double radius = 0.3;
  std::vector<glm::vec3> normals;
  for (int i = 0; i < 16; ++i)
    for (int j = 0; j < 32; ++j) {
      const double theta = std::numbers::pi * (i + 0.5) / 16, phi = 2 * std::numbers::pi * j / 32;
      normals.emplace_back(std::sin(theta) * std::cos(phi), std::cos(theta), std::sin(theta) * std::sin(phi));
    }
  const glm::vec3 axes[6] = {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}};

  int32_t cachedTet = -1;  // per object, kept across frames
  const int frames = 12;
  float firstRoom = 0, lastRoom = 0;
  bool ok = true;
  std::vector<glm::dvec3> points(normals.size());
  std::vector<glm::vec3> perPixel(normals.size());
  for (int f = 0; f < frames; ++f) {
    const glm::dvec3 centre = from + (to - from) * (double(f) / (frames - 1));
    // Per object: the interpolated SH at the centre, from the cached tet.
    const tetraprobe::ShRgb sh = query.interpolatedSh(centre, &cachedTet);
    const tetraprobe::ShRgb cold = query.interpolatedSh(centre);
    ok = ok && std::memcmp(&sh, &cold, sizeof sh) == 0;  // the cache changes the speed, not the answer
    // At the centre, the SH against the per-pixel lookup for a few normals.
    double centreDiff = 0;
    for (const glm::vec3& n : axes) {
      const float a = luminance(tetraprobe::shIrradiance(sh, n)), b = luminance(query.irradiance(centre, n));
      centreDiff = std::max(centreDiff, std::abs(double(a) - b) / std::max(std::abs(double(b)), 1e-6));
    }
    // Per pixel: every surface point with its own normal.
    for (size_t k = 0; k < normals.size(); ++k) points[k] = centre + radius * glm::dvec3(normals[k]);
    query.irradianceBatch(points.data(), normals.data(), perPixel.data(), points.size(), 1);
    double meanPixel = 0, meanError = 0;
    for (size_t k = 0; k < normals.size(); ++k) {
      const glm::vec3 object = tetraprobe::shIrradiance(sh, normals[k]);
      ok = ok && std::isfinite(luminance(perPixel[k])) && std::isfinite(luminance(object));
      meanPixel += luminance(perPixel[k]);
      meanError += std::abs(luminance(object) - luminance(perPixel[k]));
    }
    meanPixel /= double(normals.size());
    meanError /= double(normals.size());
    if (f == 0) firstRoom = float(meanPixel);
    if (f == frames - 1) lastRoom = float(meanPixel);
    std::printf(
        "frame %2d  centre (%.2f, %.2f, %.2f)  tet %6d  E up %8.4f  per-pixel mean %8.4f W/m^2"
        "  per-object error %5.1f %%  centre SH vs lookup %.1e\n",
        f, centre.x, centre.y, centre.z, cachedTet, luminance(tetraprobe::shIrradiance(sh, axes[2])),
        meanPixel, meanPixel > 0 ? 100.0 * meanError / meanPixel : 0.0, centreDiff);
  }
  if (argc == 2) ok = ok && lastRoom < firstRoom;         // the default path ends in the unlit room
  ok = runGpuLevel(level, query, points, normals) && ok;  // relights `level`: after the CPU frames
  std::printf("%s\n", ok ? "ok" : "FAILED");
  return ok ? 0 : 1;
}
