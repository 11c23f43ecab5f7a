// The scene-to-renderer glue `render` and `bench render` share (render_view.h).
#include "render_view.h"

#include <string>

#include <glm/common.hpp>
#include <glm/geometric.hpp>

#include "tetraprobe/common/error.h"
#include "tetraprobe/scene/load.h"

namespace tetraprobe::cli {

RenderMesh toRenderMesh(const Scene& scene) {
  RenderMesh mesh;
  mesh.positions = scene.positions;
  mesh.triangles = scene.triangles;
  mesh.triangleAlbedo.reserve(scene.triangles.size());
  mesh.triangleEmission.reserve(scene.triangles.size());
  for (uint32_t m : scene.triangleMaterial) {
    mesh.triangleAlbedo.push_back(scene.materials[m].albedo);
    mesh.triangleEmission.push_back(scene.materials[m].emission);
  }
  return mesh;
}

std::vector<RenderLight> toRenderLights(const Scene& scene) {
  std::vector<RenderLight> lights;
  for (const Light& l : scene.lights) {
    RenderLight r;
    r.type = l.type == LightType::kPoint  ? RenderLightType::kPoint
             : l.type == LightType::kSpot ? RenderLightType::kSpot
                                          : RenderLightType::kDirectional;
    r.position = l.position;
    r.direction = l.direction;
    r.intensity = l.intensity;
    r.innerConeRad = l.innerConeRad;
    r.outerConeRad = l.outerConeRad;
    lights.push_back(r);
  }
  return lights;
}

std::vector<OptionSpec> withViewOptions(std::vector<OptionSpec> own) {
  own.insert(own.end(), {{"--camera", "", "NAME",
                          "a camera named in the scene (default: the scene's first, else automatic)", ""},
                         {"--eye", "", "X,Y,Z", "camera position (with --target)", ""},
                         {"--target", "", "X,Y,Z", "point the camera looks at", ""},
                         {"--up", "", "X,Y,Z", "camera up vector", "0,1,0"},
                         {"--fov", "", "DEG", "vertical field of view (with --eye)", "60"}});
  return own;
}

void chooseView(const Args& args, const Scene& scene, RenderView& view) {
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
}

}  // namespace tetraprobe::cli
