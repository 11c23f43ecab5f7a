// Internal interface between the scene loaders: one loader per file format, plus the shared validation pass
// and the texture helpers. Not installed; only scene/src includes it.
#pragma once

#include <cstddef>
#include <filesystem>
#include <optional>
#include <string>

#include <glm/vec3.hpp>

#include "tetraprobe/scene/scene.h"

namespace tetraprobe::detail {

struct MeshOptions {
  // false: ignore base-colour/diffuse and emissive textures (albedo = Kd or baseColorFactor alone), for files
  // whose Kd already holds the texture's mean colour. Scene JSON key "textures": "ignore".
  bool textures = true;
};

// Each loader fills positions/triangles/materials/lights/cameras of a fresh Scene and throws InputError
// ("<path>: <problem>") for malformed input. They do not run validateScene(); loadMesh()/loadScene() do.
Scene loadObj(const std::string& path, const MeshOptions& options);
Scene loadGltf(const std::string& path, const MeshOptions& options);
Scene loadSceneJson(const std::string& path);

// Loads an .obj/.gltf/.glb file by extension and validates it (a scene JSON is not a mesh: InputError).
Scene loadMesh(const std::string& path, const MeshOptions& options);

// Shared validation: throws InputError naming `path` for NaN/Inf positions, out-of-range indices or
// material ids, or zero triangles; drops zero-area triangles and records their count in scene.warnings.
void validateScene(Scene& scene, const std::string& path);

// Mean linear RGB of an encoded image (PNG, JPEG, TGA, BMP, PSD, GIF, HDR, PIC, PNM). 8- and 16-bit images
// are taken as sRGB-encoded and decoded per texel before averaging; Radiance .hdr is already linear. Alpha is
// ignored (every texel counts equally). Returns nullopt and sets `error` when the bytes cannot be decoded.
std::optional<glm::vec3> meanLinearColor(const unsigned char* bytes, std::size_t size, std::string& error);
std::optional<glm::vec3> meanLinearColorFile(const std::filesystem::path& file, std::string& error);

// Which channel of an image holds the alpha a cutout or a transmission map reads.
enum class AlphaSource {
  kAlphaElseOpaque,  // the alpha channel; 1 everywhere when the image has none (glTF base colour)
  kAlphaElseFirst,   // the alpha channel; the first (grey or red) channel when there is none (OBJ map_d)
  kFirst,            // the first channel (glTF transmissionTexture: red)
};

// One channel of an encoded image as a Scene alpha texture (8 bits a texel, taken as linear: alpha is not
// sRGB-encoded; 16-bit images are reduced to 8 bits, Radiance .hdr clamped to [0,1]). Wrap modes are left at
// repeat. Returns nullopt and sets `error` when the bytes cannot be decoded.
std::optional<AlphaTexture> decodeAlpha(const unsigned char* bytes, std::size_t size, AlphaSource source,
                                        std::string& error);
std::optional<AlphaTexture> decodeAlphaFile(const std::filesystem::path& file, AlphaSource source,
                                            std::string& error);

// Mean alpha of a texture, in [0,1].
float meanAlpha(const AlphaTexture& texture);

// Makes `m` cut holes where `texture`'s alpha is below `cutoff`: when some texels are holes and some are not,
// m.alphaTexture is set to `slot` (adding the texture to scene.alphaTextures the first time: slot < 0 on
// entry); when every texel is a hole the material lets everything through (transmission 1, no texture);
// when none is, nothing changes. Returns true when m now has a per-texel cutout.
bool applyCutout(Scene& scene, Material& m, const AlphaTexture& texture, float cutoff, int32_t& slot);

// IEC 61966-2-1 sRGB transfer function, encoded value in [0,1] -> linear.
float srgbToLinear(float encoded);

// Finds a texture named in a material file, forgivingly: as given (relative to baseDir unless absolute), then
// with '\\' turned into '/', then matching each path component case-insensitively. nullopt if none exists.
std::optional<std::filesystem::path> resolveTexturePath(const std::filesystem::path& baseDir,
                                                        const std::string& name);

}  // namespace tetraprobe::detail
