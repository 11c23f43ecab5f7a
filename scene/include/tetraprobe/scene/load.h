// Loading a level from disk into a Scene. Build side.
#pragma once

#include <string>

#include "tetraprobe/scene/scene.h"

namespace tetraprobe {

// Loads by extension: .gltf/.glb (glTF 2.0), .obj (+ .mtl), .scene.json (scene description naming a mesh
// file; schema in docs/scene_format.md). Throws InputError naming the file and problem for unreadable or
// malformed input, NaN/Inf positions, out-of-range indices, or a scene with no triangles. Non-fatal issues
// (missing texture image, unsupported material feature) are appended to Scene::warnings.
Scene loadScene(const std::string& path);

}  // namespace tetraprobe
