// A level as the build side sees it: triangles with Lambertian materials, lights, sky and cameras, in one
// world frame. Produced by loadScene() from glTF 2.0, OBJ/MTL or a scene JSON (docs/scene_format.md).
//
// Frame and units: right-handed, metres (the loader applies the file's unit scale), the input file's up axis
// (usually +Y). Radiometric units: radiance W/(m^2 sr), point/spot intensity W/sr, sun irradiance W/m^2
// (perpendicular to the sun direction). Colours are linear RGB.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include <glm/vec3.hpp>

namespace tetraprobe {

struct Material {
  std::string name;
  glm::vec3 albedo{0.8f};    // diffuse reflectance in [0,1] (base colour x mean linear texture colour)
  glm::vec3 emission{0.0f};  // emitted radiance, W/(m^2 sr), from the front face only
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
  std::string sourcePath;                 // the file the scene was loaded from
  std::vector<glm::vec3> positions;       // vertex positions, world metres
  std::vector<glm::uvec3> triangles;      // counter-clockwise front faces; indices into positions
  std::vector<uint32_t> triangleMaterial; // one per triangle, index into materials
  std::vector<Material> materials;
  std::vector<Light> lights;
  glm::vec3 skyRadiance{0.0f};            // constant sky radiance seen by rays that escape, W/(m^2 sr)
  glm::vec3 skyHorizonRadiance{-1.0f};    // when >= 0: gradient sky, skyRadiance at the zenith (+Y) blending
                                          // to this at the horizon and below
  std::vector<Camera> cameras;
  std::vector<Volume> fineVolumes;        // gameplay space (optional)
  std::vector<std::string> warnings;      // non-fatal problems met while loading (e.g. missing texture)

  bool hasSkyGradient() const { return skyHorizonRadiance.x >= 0.0f; }
};

// Bounds of all vertex positions.
void sceneBounds(const Scene& scene, glm::vec3& lo, glm::vec3& hi);

}  // namespace tetraprobe
