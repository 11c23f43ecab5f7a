// A level as the build side sees it: triangles with Lambertian materials, lights, sky and cameras, in one
// world frame. Produced by loadScene() from glTF 2.0, OBJ/MTL or a scene JSON (docs/scene_format.md).
//
// Transparency (docs/scene_format.md maps each format's fields): a material may let a fraction of the light
// through (Material::transmission, a thin-glass model) and may cut holes per texel (an alpha cutout:
// Material::alphaTexture, with texture coordinates for its triangles in Scene::cutoutTriangles/cutoutUvs).
//
// Frame and units: right-handed, metres (the loader applies the file's unit scale), the input file's up axis
// (usually +Y). Radiometric units: radiance W/(m^2 sr), point/spot intensity W/sr, sun irradiance W/m^2
// (perpendicular to the sun direction). Colours are linear RGB.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include <glm/vec2.hpp>
#include <glm/vec3.hpp>

namespace tetraprobe {

// Energy model of a surface, per unit of light arriving from either side:
//   - `transmission` of it passes straight through, unchanged in direction and colour (thin glass: no
//     refraction, no tint, no absorption inside);
//   - the rest, 1 - transmission, meets a Lambertian reflector of reflectance `albedo`, so the surface
//     reflects (1 - transmission) x albedo in all and absorbs (1 - transmission) x (1 - albedo);
//   - `emission` is emitted from the front face whatever the transmission.
// transmission 0 is an opaque surface (the only kind before transparency was read); 1 lets everything
// through (and reflects nothing). Where an alpha cutout says "hole", there is no surface at all.
struct Material {
  std::string name;
  glm::vec3 albedo{0.8f};     // diffuse reflectance in [0,1] of the part that does not transmit (base colour
                              // x mean linear texture colour)
  glm::vec3 emission{0.0f};   // emitted radiance, W/(m^2 sr), from the front face only
  float transmission = 0.0f;  // in [0,1]: fraction of light passing straight through (see above)
  int32_t alphaTexture = -1;  // index into Scene::alphaTextures: per-texel cutout; -1: none
  float alphaCutoff = 0.5f;   // with alphaTexture: texels whose alpha (in [0,1]) is below this are holes
};

enum class TextureWrap : uint8_t { kRepeat, kClampToEdge, kMirroredRepeat };

// The alpha channel of a texture that cuts holes (only textures some material uses as an alpha cutout are
// kept: one byte per texel). Sampled at the nearest texel.
struct AlphaTexture {
  std::string name;  // file or image name, for messages
  uint32_t width = 0, height = 0;
  std::vector<uint8_t> alpha;  // width x height, row-major from the image's top row; linear, 255 = opaque
  TextureWrap wrapU = TextureWrap::kRepeat, wrapV = TextureWrap::kRepeat;

  // Alpha in [0,1] of the texel nearest to `uv`: u runs right and v down from the image's top-left corner
  // (the glTF convention; the OBJ loader flips v on load), one unit per image, wrapped per wrapU/wrapV.
  // Non-finite coordinates give 1 (opaque). Requires width, height > 0 and alpha.size() == width x height.
  float sample(glm::vec2 uv) const;
};

enum class LightType { kPoint, kSpot, kDirectional };

struct Light {
  LightType type = LightType::kPoint;
  glm::vec3 position{0.0f};       // point, spot: metres
  glm::vec3 direction{0, -1, 0};  // spot, directional: unit vector the light travels along
  glm::vec3 intensity{0.0f};      // point, spot: W/sr; directional: irradiance W/m^2 at normal incidence
  float innerConeRad = 0.0f;      // spot: full intensity inside this half-angle
  float outerConeRad = 0.7854f;   // spot: zero outside this half-angle (smoothstep between)
  float angularRadiusRad = 0.0f;  // directional: half-angle of the sun disc (0 = hard shadows)
  float radius = 0.0f;            // point, spot: emitter radius for soft shadows (0 = point)
};

struct Camera {
  std::string name;
  glm::vec3 eye{0.0f};
  glm::vec3 target{0, 0, -1};
  glm::vec3 up{0, 1, 0};
  float fovYDeg = 60.0f;  // vertical field of view
};

// An axis-aligned box that must keep fine probe spacing (gameplay space).
struct Volume {
  std::string name;
  glm::vec3 min{0.0f};
  glm::vec3 max{0.0f};
};

struct Scene {
  std::string sourcePath;                  // the file the scene was loaded from
  std::vector<glm::vec3> positions;        // vertex positions, world metres
  std::vector<glm::uvec3> triangles;       // counter-clockwise front faces; indices into positions
  std::vector<uint32_t> triangleMaterial;  // one per triangle, index into materials
  std::vector<Material> materials;
  // Alpha cutouts: the textures, and the texture coordinates of exactly those triangles whose material has
  // alphaTexture >= 0 (cutoutTriangles: increasing triangle indices; cutoutUvs: 3 per entry, in the corner
  // order of `triangles`, AlphaTexture::sample's convention). A cutout-material triangle that is not listed
  // (its file gave it no texture coordinates) is opaque everywhere. All empty when nothing is cut out.
  std::vector<AlphaTexture> alphaTextures;
  std::vector<uint32_t> cutoutTriangles;
  std::vector<glm::vec2> cutoutUvs;
  std::vector<Light> lights;
  glm::vec3 skyRadiance{0.0f};          // constant sky radiance seen by rays that escape, W/(m^2 sr)
  glm::vec3 skyHorizonRadiance{-1.0f};  // when >= 0: gradient sky, skyRadiance at the zenith (+Y) blending
                                        // to this at the horizon and below
  std::vector<Camera> cameras;
  std::vector<Volume> fineVolumes;    // gameplay space (optional)
  std::vector<std::string> warnings;  // non-fatal problems met while loading (e.g. missing texture)

  bool hasSkyGradient() const { return skyHorizonRadiance.x >= 0.0f; }
};

// The first inconsistency in the transparency data, or "" when there is none: a material's transmission
// outside [0,1] or not finite, alphaCutoff not finite, alphaTexture out of range, a texture whose size does
// not match its texels (or is empty), cutoutTriangles not increasing or out of range, or cutoutUvs not 3 per
// entry. (Non-finite texture coordinates are allowed: they sample as opaque.)
std::string transparencyProblem(const Scene& scene);

// Bounds of all vertex positions.
void sceneBounds(const Scene& scene, glm::vec3& lo, glm::vec3& hi);

// Total area of the triangles, m^2 (each side counted once), summed in double in triangle order.
double surfaceArea(const Scene& scene);

}  // namespace tetraprobe
