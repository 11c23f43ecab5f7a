// Scene JSON: the mesh is loaded relative to the JSON, unit_scale scales geometry, lights, cameras and
// volumes, lights/sky/cameras/volumes/material overrides are read with their units, unknown keys warn, and
// wrong types are InputErrors naming the key path.
#include <gtest/gtest.h>
#include <glm/geometric.hpp>

#include "scene_test_support.h"
#include "tetraprobe/common/error.h"
#include "tetraprobe/scene/load.h"

namespace tetraprobe {
namespace {

using test::anyWarningContains;
using test::freshDir;
using test::loadError;
using test::writeText;

// A 100 x 100 (file units) square in the y = 0 plane, facing up, with an emissive material "lamp".
void writeMesh(const std::filesystem::path& dir) {
  writeText(dir / "mesh" / "floor.mtl", "newmtl floor\nKd 0.5 0.5 0.5\nnewmtl lamp\nKd 0 0 0\nKe 2 2 2\n");
  writeText(dir / "mesh" / "floor.obj",
            "mtllib floor.mtl\nv 0 0 0\nv 100 0 0\nv 100 0 100\nv 0 0 100\nv 0 10 0\nv 1 10 0\nv 0 10 1\n"
            "usemtl floor\nf 1 4 3 2\nusemtl lamp\nf 5 7 6\n");
}

const char* kFullScene = R"({
  "mesh": "mesh/floor.obj",
  "unit_scale": 0.01,
  "sky": {"zenith": [0.2, 0.3, 0.5], "horizon": [0.6, 0.6, 0.6]},
  "lights": [
    {"type": "point", "name": "bulb", "position": [50, 100, 50], "intensity": [10, 8, 6], "radius": 5},
    {"type": "spot", "position": [0, 200, 0], "direction": [0, -2, 0], "intensity": 30,
     "inner_cone_deg": 10, "outer_cone_deg": 30},
    {"type": "directional", "direction": [1, -1, 0], "irradiance": [1000, 900, 800], "angular_radius_deg": 0.25}
  ],
  "cameras": [{"name": "main", "eye": [0, 150, -300], "target": [50, 0, 50], "up": [0, 1, 0], "fov_deg": 50}],
  "fine_volumes": [{"name": "arena", "min": [10, 0, 10], "max": [90, 200, 90]}],
  "materials": {"lamp": {"emission_scale": 10}, "floor": {"albedo": [0.2, 0.3, 0.4]}}
})";

TEST(LoadSceneJson, MeshResolvedRelativeToJsonAndScaled) {
  const auto dir = freshDir();
  writeMesh(dir);
  const Scene s = loadScene(writeText(dir / "level.scene.json", kFullScene));
  EXPECT_EQ(s.triangles.size(), 3u);
  glm::vec3 lo, hi;
  sceneBounds(s, lo, hi);
  EXPECT_FLOAT_EQ(hi.x, 1.0f);
  EXPECT_FLOAT_EQ(hi.y, 0.1f);
  EXPECT_FLOAT_EQ(hi.z, 1.0f);
  EXPECT_EQ(s.sourcePath, (dir / "level.scene.json").string());
}

TEST(LoadSceneJson, LightsReadWithUnitsAndScaledPositions) {
  const auto dir = freshDir();
  writeMesh(dir);
  const Scene s = loadScene(writeText(dir / "level.scene.json", kFullScene));
  ASSERT_EQ(s.lights.size(), 3u);
  EXPECT_EQ(s.lights[0].type, LightType::kPoint);
  EXPECT_FLOAT_EQ(s.lights[0].position.y, 1.0f);
  EXPECT_FLOAT_EQ(s.lights[0].radius, 0.05f);
  EXPECT_EQ(s.lights[0].intensity, glm::vec3(10, 8, 6));  // W/sr, not scaled
  EXPECT_EQ(s.lights[1].type, LightType::kSpot);
  EXPECT_EQ(s.lights[1].direction, glm::vec3(0, -1, 0));  // normalised
  EXPECT_EQ(s.lights[1].intensity, glm::vec3(30.0f));     // a number is grey
  EXPECT_NEAR(s.lights[1].innerConeRad, 10.0f * 3.14159265f / 180.0f, 1e-6f);
  EXPECT_NEAR(s.lights[1].outerConeRad, 30.0f * 3.14159265f / 180.0f, 1e-6f);
  EXPECT_EQ(s.lights[2].type, LightType::kDirectional);
  EXPECT_NEAR(s.lights[2].direction.x, 0.70710678f, 1e-6f);
  EXPECT_EQ(s.lights[2].intensity, glm::vec3(1000, 900, 800));  // W/m^2
  EXPECT_NEAR(s.lights[2].angularRadiusRad, 0.25f * 3.14159265f / 180.0f, 1e-7f);
}

TEST(LoadSceneJson, SkyCamerasVolumesAndOverrides) {
  const auto dir = freshDir();
  writeMesh(dir);
  const Scene s = loadScene(writeText(dir / "level.scene.json", kFullScene));
  EXPECT_TRUE(s.hasSkyGradient());
  EXPECT_EQ(s.skyRadiance, glm::vec3(0.2f, 0.3f, 0.5f));
  EXPECT_EQ(s.skyHorizonRadiance, glm::vec3(0.6f));
  ASSERT_EQ(s.cameras.size(), 1u);
  EXPECT_EQ(s.cameras[0].name, "main");
  EXPECT_NEAR(glm::distance(s.cameras[0].eye, glm::vec3(0, 1.5f, -3)), 0.0f, 1e-6f);
  EXPECT_NEAR(glm::distance(s.cameras[0].target, glm::vec3(0.5f, 0, 0.5f)), 0.0f, 1e-6f);
  EXPECT_FLOAT_EQ(s.cameras[0].fovYDeg, 50.0f);
  ASSERT_EQ(s.fineVolumes.size(), 1u);
  EXPECT_NEAR(glm::distance(s.fineVolumes[0].max, glm::vec3(0.9f, 2.0f, 0.9f)), 0.0f, 1e-6f);
  for (const auto& m : s.materials) {
    if (m.name == "lamp") {
      EXPECT_EQ(m.emission, glm::vec3(20.0f));
    }
    if (m.name == "floor") {
      EXPECT_EQ(m.albedo, glm::vec3(0.2f, 0.3f, 0.4f));
    }
  }
  EXPECT_TRUE(s.warnings.empty()) << s.warnings.front();
}

TEST(LoadSceneJson, ConstantSkyHasNoGradient) {
  const auto dir = freshDir();
  writeMesh(dir);
  const Scene s = loadScene(
      writeText(dir / "s.scene.json", R"({"mesh": "mesh/floor.obj", "sky": {"radiance": [1, 2, 3]}})"));
  EXPECT_FALSE(s.hasSkyGradient());
  EXPECT_EQ(s.skyRadiance, glm::vec3(1, 2, 3));
}

// Some converters store a texture's mean colour in Kd as well as naming the texture (q3_dm4ish): "ignore".
TEST(LoadSceneJson, TexturesIgnoreKeepsKd) {
  const auto dir = freshDir();
  test::writePng(dir / "t.png", 1, 1, {0, 0, 0});
  writeText(dir / "m.mtl", "newmtl dark\nKd 0.25 0.5 0.75\nmap_Kd t.png\n");
  writeText(dir / "m.obj", "mtllib m.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl dark\nf 1 2 3\n");
  const Scene multiplied = loadScene(writeText(dir / "a.scene.json", R"({"mesh": "m.obj"})"));
  EXPECT_EQ(multiplied.materials[0].albedo, glm::vec3(0.0f));
  const Scene kept = loadScene(writeText(dir / "b.scene.json", R"({"mesh": "m.obj", "textures": "ignore"})"));
  EXPECT_EQ(kept.materials[0].albedo, glm::vec3(0.25f, 0.5f, 0.75f));
  const std::string msg =
      loadError(writeText(dir / "c.scene.json", R"({"mesh": "m.obj", "textures": "replace"})"));
  EXPECT_NE(msg.find("textures"), std::string::npos) << msg;
}

TEST(LoadSceneJson, MeshMustNotBeAnotherSceneJson) {
  const auto dir = freshDir();
  writeText(dir / "inner.scene.json", R"({"mesh": "outer.scene.json"})");
  const std::string msg = loadError(writeText(dir / "outer.scene.json", R"({"mesh": "inner.scene.json"})"));
  EXPECT_NE(msg.find("unknown mesh format"), std::string::npos) << msg;
}

TEST(LoadSceneJson, UnknownKeysWarn) {
  const auto dir = freshDir();
  writeMesh(dir);
  const Scene s = loadScene(writeText(dir / "s.scene.json",
                                      R"({"mesh": "mesh/floor.obj", "colour_grading": 1,
                                          "lights": [{"type": "point", "position": [0,1,0], "intensity": 1, "size": 2}]})"));
  EXPECT_TRUE(anyWarningContains(s, "colour_grading"));
  EXPECT_TRUE(anyWarningContains(s, "lights[0].size"));
}

TEST(LoadSceneJson, OverrideOfUnknownMaterialWarns) {
  const auto dir = freshDir();
  writeMesh(dir);
  const Scene s = loadScene(writeText(
      dir / "s.scene.json", R"({"mesh": "mesh/floor.obj", "materials": {"marble": {"albedo": 0.5}}})"));
  EXPECT_TRUE(anyWarningContains(s, "marble"));
}

TEST(LoadSceneJson, WrongTypeIsInputErrorNamingKeyPath) {
  const auto dir = freshDir();
  writeMesh(dir);
  std::string msg =
      loadError(writeText(dir / "a.scene.json", R"({"mesh": "mesh/floor.obj", "unit_scale": "big"})"));
  EXPECT_NE(msg.find("a.scene.json: unit_scale: expected a number"), std::string::npos) << msg;
  msg = loadError(writeText(dir / "b.scene.json", R"({"mesh": "mesh/floor.obj",
      "lights": [{"type": "point", "position": [0, 1, 0], "intensity": 1},
                 {"type": "point", "position": [0, 1], "intensity": 1}]})"));
  EXPECT_NE(msg.find("lights[1].position: expected an array of 3 numbers"), std::string::npos) << msg;
  msg = loadError(writeText(dir / "c.scene.json", R"({"mesh": "mesh/floor.obj", "cameras": [{"name": 3}]})"));
  EXPECT_NE(msg.find("cameras[0].name"), std::string::npos) << msg;
  msg = loadError(writeText(dir / "d.scene.json", R"({"mesh": 7})"));
  EXPECT_NE(msg.find("mesh: expected a string"), std::string::npos) << msg;
  msg = loadError(
      writeText(dir / "e.scene.json", R"({"mesh": "mesh/floor.obj", "lights": [{"type": "laser"}]})"));
  EXPECT_NE(msg.find("lights[0].type"), std::string::npos) << msg;
}

TEST(LoadSceneJson, MalformedJsonIsInputError) {
  const auto dir = freshDir();
  const std::string msg = loadError(writeText(dir / "m.scene.json", "{ \"mesh\": \"a.obj\", "));
  EXPECT_NE(msg.find("m.scene.json: malformed JSON"), std::string::npos) << msg;
}

TEST(LoadSceneJson, MissingMeshIsInputErrorNamingTheMesh) {
  const auto dir = freshDir();
  const std::string msg = loadError(writeText(dir / "m.scene.json", R"({"mesh": "nowhere.obj"})"));
  EXPECT_NE(msg.find("nowhere.obj"), std::string::npos) << msg;
}

TEST(LoadScene, UnreadableFileIsInputError) {
  const std::string msg = loadError((freshDir() / "absent.obj").string());
  EXPECT_NE(msg.find("absent.obj"), std::string::npos) << msg;
}

TEST(LoadScene, UnknownExtensionIsInputError) {
  const auto dir = freshDir();
  const std::string msg = loadError(writeText(dir / "level.fbx", "binary"));
  EXPECT_NE(msg.find("unknown scene format"), std::string::npos) << msg;
}

TEST(LoadScene, DirectoryIsInputError) {
  const auto dir = freshDir();
  std::filesystem::create_directories(dir / "x.obj");
  const std::string msg = loadError((dir / "x.obj").string());
  EXPECT_NE(msg.find("x.obj"), std::string::npos) << msg;
}

}  // namespace
}  // namespace tetraprobe
