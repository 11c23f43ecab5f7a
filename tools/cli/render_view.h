// What `render` and `bench render` share: the scene as the renderer's mesh and lights, and the camera from
// --camera / --eye --target --up --fov (or the scene's first camera, or an automatic view of its box).
#pragma once

#include <vector>

#include "args.h"
#include "tetraprobe/render/render.h"
#include "tetraprobe/scene/scene.h"

namespace tetraprobe::cli {

// The scene's triangles with each material's albedo and emission.
RenderMesh toRenderMesh(const Scene& scene);
// The scene's point, spot and sun lights.
std::vector<RenderLight> toRenderLights(const Scene& scene);
// A command's own options followed by those chooseView reads: --camera, --eye, --target, --up, --fov.
std::vector<OptionSpec> withViewOptions(std::vector<OptionSpec> own);
// Sets view.eye, target, up and fovYDeg from the options (which `args` must declare: --camera, --eye,
// --target, --up, --fov); throws UsageError / InputError naming a bad combination or an unknown camera.
void chooseView(const Args& args, const Scene& scene, RenderView& view);

}  // namespace tetraprobe::cli
