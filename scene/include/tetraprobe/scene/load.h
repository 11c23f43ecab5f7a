// Loading a level from disk into a Scene. Build side.
#pragma once

#include <string>

#include "tetraprobe/scene/scene.h"

namespace tetraprobe {

// Loads by extension: .gltf/.glb (glTF 2.0), .obj (+ .mtl), .scene.json (scene description naming a mesh
// file; schema in docs/scene_format.md). Throws InputError naming the file and problem for unreadable or
// malformed input, NaN/Inf positions, out-of-range indices, or a scene with no triangles. Non-fatal issues
// (missing texture image, unsupported material feature) are appended to Scene::warnings. Zero-area triangles
// are dropped (their count is a warning). Sets Scene::sourcePath. Safe for untrusted files: bad data throws,
// it never crashes or hangs. Units, field mapping and the scene JSON schema: docs/scene_format.md.
Scene loadScene(const std::string& path);

}  // namespace tetraprobe
