// `tetraprobe render SCENE LEVEL.tpb -o IMAGE`: a view lit per pixel by the probes, rendered headless through
// Vulkan (G-buffer raster, then the GLSL lookup pass of shaders/tetraprobe.glsl).
#include <chrono>
#include <cstdio>

#include <glm/common.hpp>
#include <glm/geometric.hpp>

#include "args.h"
#include "commands.h"
#include "tetraprobe/common/error.h"
#include "tetraprobe/render/render.h"
#include "tetraprobe/runtime/query.h"
#include "tetraprobe/scene/load.h"

namespace tetraprobe::cli {

namespace {

bool endsWith(const std::string& s, const std::string& suffix) {
  return s.size() >= suffix.size() && s.compare(s.size() - suffix.size(), suffix.size(), suffix) == 0;
}

RenderMesh toRenderMesh(const Scene& scene) {
  RenderMesh mesh;
  mesh.positions = scene.positions;
  mesh.triangles = scene.triangles;
  mesh.triangleAlbedo.reserve(scene.triangles.size());
  for (uint32_t m : scene.triangleMaterial) mesh.triangleAlbedo.push_back(scene.materials[m].albedo);
  return mesh;
}

}  // namespace

int cmdRender(int argc, char** argv) {
  Args args("tetraprobe render SCENE LEVEL.tpb -o IMAGE [options]",
            "Renders the scene lit per pixel by the level's probes (headless Vulkan; lavapipe works).\n"
            "IMAGE ending in .png is tone-mapped 8-bit sRGB; .exr is linear float RGBA.\n"
            "Modes: irradiance = E in W/m^2 (the light content the probes hold); indirect = albedo * E / pi.",
            {{"--output", "-o", "IMAGE", "image to write (.png or .exr)", ""},
             {"--camera", "", "NAME",
              "a camera named in the scene (default: the scene's first, else automatic)", ""},
             {"--eye", "", "X,Y,Z", "camera position (with --target)", ""},
             {"--target", "", "X,Y,Z", "point the camera looks at", ""},
             {"--up", "", "X,Y,Z", "camera up vector", "0,1,0"},
             {"--fov", "", "DEG", "vertical field of view (with --eye)", "60"},
             {"--size", "", "WxH", "image size in pixels", "960x540"},
             {"--mode", "", "irradiance|indirect", "what the pixels show", "indirect"},
             {"--exposure", "", "auto|X", "PNG exposure multiplier before tone mapping", "auto"}});
  if (!args.parse(argc, argv)) return 0;
  args.requirePositional(2, 2);
  if (!args.has("--output")) throw UsageError("missing -o IMAGE");
  const std::string out = args.str("--output");
  if (!endsWith(out, ".png") && !endsWith(out, ".exr")) throw UsageError("IMAGE must end in .png or .exr");

  RenderView view;
  const std::string size = args.str("--size");
  if (std::sscanf(size.c_str(), "%dx%d", &view.width, &view.height) != 2 || view.width < 1 ||
      view.height < 1 || view.width > 16384 || view.height > 16384)
    throw UsageError("--size must be WxH with 1..16384 pixels a side, not '" + size + "'");
  const std::string mode = args.str("--mode");
  if (mode == "irradiance")
    view.mode = RenderMode::kIrradiance;
  else if (mode == "indirect")
    view.mode = RenderMode::kIndirect;
  else
    throw UsageError("--mode must be irradiance or indirect, not '" + mode + "'");

  const Scene scene = loadScene(args.positional()[0]);
  Level level;
  if (const LevelResult r = loadLevel(args.positional()[1], level); !r) throw InputError(r.message);

  if (args.has("--eye") || args.has("--target")) {
    if (!args.has("--eye") || !args.has("--target")) throw UsageError("--eye and --target go together");
    if (args.has("--camera")) throw UsageError("--camera and --eye/--target exclude each other");
    view.eye = args.vec3("--eye");
    view.target = args.vec3("--target");
    view.up = args.vec3("--up");
    view.fovYDeg = float(args.number("--fov"));
  } else if (!scene.cameras.empty()) {
    const Camera* cam = &scene.cameras[0];
    if (args.has("--camera")) {
      cam = nullptr;
      std::string names;
      for (const auto& c : scene.cameras) {
        if (c.name == args.str("--camera")) cam = &c;
        names += (names.empty() ? "" : ", ") + c.name;
      }
      if (!cam)
        throw InputError("no camera named '" + args.str("--camera") + "' in the scene (it has: " + names +
                         ")");
    }
    view.eye = cam->eye;
    view.target = cam->target;
    view.up = cam->up;
    view.fovYDeg = cam->fovYDeg;
  } else {
    if (args.has("--camera")) throw InputError("the scene names no cameras; use --eye and --target");
    glm::vec3 lo, hi;
    sceneBounds(scene, lo, hi);
    const glm::vec3 c = (lo + hi) * 0.5f, ext = hi - lo;
    view.target = c;
    view.eye = c + glm::vec3(0.7f, 0.5f, 0.9f) * glm::max(ext, glm::vec3(glm::length(ext) * 0.3f));
  }
  if (!(view.fovYDeg > 0.0f && view.fovYDeg < 179.0f)) throw UsageError("--fov must be in (0, 179) degrees");
  if (glm::length(view.target - view.eye) <= 0.0f) throw UsageError("camera eye and target coincide");

  const ProbeQuery query(level);
  const auto t0 = std::chrono::steady_clock::now();
  const RenderResult result = renderLevel(toRenderMesh(scene), level, query, view);
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();

  std::string error;
  if (endsWith(out, ".exr")) {
    if (!writeExr(out, result.color, &error)) throw std::runtime_error(error);
  } else {
    const float exposure =
        args.str("--exposure") == "auto" ? autoExposure(result.color) : float(args.number("--exposure"));
    if (!writePng(out, result.color, exposure, &error)) throw std::runtime_error(error);
  }
  std::printf("tetraprobe render: %s (%dx%d, %s) in %.2fs; GPU: G-buffer %.1f ms, per-pixel lookup %.1f ms\n",
              out.c_str(), view.width, view.height, mode.c_str(), seconds, result.timings.gbufferMs,
              result.timings.lightingMs);
  return 0;
}

}  // namespace tetraprobe::cli
