// glTF 2.0 loading: node hierarchy transforms (TRS and matrix), winding under mirroring, materials (base
// colour factor x mean linear texture, emissive x KHR_materials_emissive_strength), KHR_lights_punctual and
// cameras placed by their nodes, .glb containers, and InputError for malformed files and out-of-range data.
#include <cmath>
#include <string>

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
using test::writePng;
using test::writeText;

constexpr float kSrgb128 = 0.2158605f;  // ((128/255 + 0.055) / 1.055)^2.4

// One triangle (0,0,0) (1,0,0) (0,1,0) as float VEC3 positions (36 bytes) + uint16 indices (6 bytes + 2 pad).
std::vector<uint8_t> triangleBuffer(std::vector<float> positions = {0, 0, 0, 1, 0, 0, 0, 1, 0},
                                    std::vector<uint16_t> indices = {0, 1, 2}) {
  std::vector<uint8_t> bin;
  test::appendBytes(bin, positions);
  test::appendBytes(bin, indices);
  while (bin.size() % 4 != 0) bin.push_back(0);
  return bin;
}

// The glTF JSON for the triangle buffer; `buffer` is the buffer object (uri or none for GLB), `nodes` and
// `scenes` are spliced in.
std::string gltfJson(const std::string& buffer, size_t bufferBytes, const std::string& nodes,
                     const std::string& extra = "", int posCount = 3, int idxCount = 3) {
  return R"({
  "asset": {"version": "2.0"},
  "extensionsUsed": ["KHR_lights_punctual", "KHR_materials_emissive_strength"],
  "buffers": [)" +
         buffer + R"(],
  "bufferViews": [
    {"buffer": 0, "byteOffset": 0, "byteLength": 36},
    {"buffer": 0, "byteOffset": 36, "byteLength": )" +
         std::to_string(bufferBytes - 36) + R"(}
  ],
  "accessors": [
    {"bufferView": 0, "componentType": 5126, "count": )" +
         std::to_string(posCount) + R"(, "type": "VEC3"},
    {"bufferView": 1, "componentType": 5123, "count": )" +
         std::to_string(idxCount) + R"(, "type": "SCALAR"}
  ],
  "meshes": [
    {"name": "tri", "primitives": [{"attributes": {"POSITION": 0}, "indices": 1, "material": 0}]},
    {"name": "lines", "primitives": [{"attributes": {"POSITION": 0}, "mode": 1}]}
  ],
  "materials": [
    {"name": "glowing", "pbrMetallicRoughness": {"baseColorFactor": [0.5, 0.25, 1.0, 1.0]},
     "emissiveFactor": [1.0, 0.5, 0.0],
     "extensions": {"KHR_materials_emissive_strength": {"emissiveStrength": 4.0}}}
  ],
  "extensions": {"KHR_lights_punctual": {"lights": [
    {"type": "spot", "color": [1.0, 0.5, 0.25], "intensity": 10.0, "spot": {"innerConeAngle": 0.2, "outerConeAngle": 0.6}},
    {"type": "point", "intensity": 3.0},
    {"type": "directional", "color": [1, 1, 1], "intensity": 100.0}
  ]}},
  "cameras": [{"name": "cam", "type": "perspective", "perspective": {"yfov": 0.8, "znear": 0.1}}],
  "nodes": [)" +
         nodes + R"(],
  "scenes": [{"nodes": [0]}],
  "scene": 0)" +
         extra + "\n}\n";
}

std::string embedded(const std::vector<uint8_t>& bin) {
  return R"({"byteLength": )" + std::to_string(bin.size()) +
         R"(, "uri": "data:application/octet-stream;base64,)" + test::base64(bin) + R"("})";
}

// Root translated by (1,2,3) with a child scaled by 2 holding the mesh; a spot light pointing down at
// (0,5,0); a point light at (-1,0,0); a camera at (0,1,5) looking along -z.
const char* kNodes = R"(
    {"name": "root", "translation": [1, 2, 3], "children": [1]},
    {"name": "scaled", "scale": [2, 2, 2], "mesh": 0},
    {"name": "spot", "translation": [0, 5, 0], "rotation": [-0.70710678, 0, 0, 0.70710678],
     "extensions": {"KHR_lights_punctual": {"light": 0}}},
    {"name": "point", "matrix": [1,0,0,0, 0,1,0,0, 0,0,1,0, -1,0,0,1], "extensions": {"KHR_lights_punctual": {"light": 1}}},
    {"name": "cam", "translation": [0, 1, 5], "camera": 0},
    {"name": "lines", "mesh": 1})";

Scene loadStandard(const std::filesystem::path& dir) {
  const auto bin = triangleBuffer();
  std::string json = gltfJson(embedded(bin), bin.size(), kNodes);
  // Put every root node into the default scene.
  const std::string from = R"("scenes": [{"nodes": [0]}])";
  json.replace(json.find(from), from.size(), R"("scenes": [{"nodes": [0, 2, 3, 4, 5]}])");
  return loadScene(writeText(dir / "t.gltf", json));
}

TEST(LoadGltf, NodeTransformsApplied) {
  const Scene s = loadStandard(freshDir());
  ASSERT_EQ(s.triangles.size(), 1u);
  const glm::uvec3 t = s.triangles[0];
  EXPECT_EQ(s.positions[t.x], glm::vec3(1, 2, 3));
  EXPECT_EQ(s.positions[t.y], glm::vec3(3, 2, 3));
  EXPECT_EQ(s.positions[t.z], glm::vec3(1, 4, 3));
}

TEST(LoadGltf, LinePrimitivesSkippedWithWarning) {
  const Scene s = loadStandard(freshDir());
  EXPECT_EQ(s.triangles.size(), 1u);
  EXPECT_TRUE(anyWarningContains(s, "point/line")) << (s.warnings.empty() ? "" : s.warnings.front());
}

TEST(LoadGltf, EmissionIsFactorTimesStrength) {
  const Scene s = loadStandard(freshDir());
  ASSERT_EQ(s.materials.size(), 1u);
  EXPECT_EQ(s.materials[0].name, "glowing");
  EXPECT_EQ(s.materials[0].albedo, glm::vec3(0.5f, 0.25f, 1.0f));
  EXPECT_EQ(s.materials[0].emission, glm::vec3(4.0f, 2.0f, 0.0f));
}

TEST(LoadGltf, PunctualLightsPlacedByTheirNodes) {
  const Scene s = loadStandard(freshDir());
  ASSERT_EQ(s.lights.size(), 2u);
  const Light& spot = s.lights[0];
  EXPECT_EQ(spot.type, LightType::kSpot);
  EXPECT_NEAR(glm::distance(spot.position, glm::vec3(0, 5, 0)), 0.0f, 1e-6f);
  EXPECT_NEAR(glm::distance(spot.direction, glm::vec3(0, -1, 0)), 0.0f, 1e-6f);
  EXPECT_EQ(spot.intensity, glm::vec3(10.0f, 5.0f, 2.5f));  // colour x intensity, cd taken as W/sr
  EXPECT_FLOAT_EQ(spot.innerConeRad, 0.2f);
  EXPECT_FLOAT_EQ(spot.outerConeRad, 0.6f);
  const Light& point = s.lights[1];
  EXPECT_EQ(point.type, LightType::kPoint);
  EXPECT_EQ(point.position, glm::vec3(-1, 0, 0));  // from the node matrix
  EXPECT_EQ(point.intensity, glm::vec3(3.0f));     // colour defaults to white
}

TEST(LoadGltf, PerspectiveCameraFromNode) {
  const Scene s = loadStandard(freshDir());
  ASSERT_EQ(s.cameras.size(), 1u);
  EXPECT_EQ(s.cameras[0].name, "cam");
  EXPECT_EQ(s.cameras[0].eye, glm::vec3(0, 1, 5));
  EXPECT_EQ(s.cameras[0].target, glm::vec3(0, 1, 4));
  EXPECT_NEAR(s.cameras[0].fovYDeg, 0.8f * 180.0f / 3.14159265f, 1e-4f);
}

TEST(LoadGltf, OnlyDefaultSceneNodesAreLoaded) {
  const auto bin = triangleBuffer();
  // Scene 0 holds node 0 only: the light, camera and line nodes are not part of it.
  const Scene s = loadScene(writeText(freshDir() / "t.gltf", gltfJson(embedded(bin), bin.size(), kNodes)));
  EXPECT_EQ(s.triangles.size(), 1u);
  EXPECT_TRUE(s.lights.empty());
  EXPECT_TRUE(s.cameras.empty());
}

TEST(LoadGltf, WithoutScenesAllRootNodesAreLoaded) {
  const auto bin = triangleBuffer();
  std::string json = gltfJson(embedded(bin), bin.size(), kNodes);
  const std::string from = R"(,
  "scenes": [{"nodes": [0]}],
  "scene": 0)";
  json.replace(json.find(from), from.size(), "");
  const Scene s = loadScene(writeText(freshDir() / "t.gltf", json));
  EXPECT_EQ(s.triangles.size(), 1u);
  EXPECT_EQ(s.lights.size(), 2u);
  EXPECT_EQ(s.cameras.size(), 1u);
  EXPECT_EQ(s.positions[s.triangles[0].y], glm::vec3(3, 2, 3));  // child reached through its parent only
}

// A mirroring transform reverses the winding in space; the loader must flip it back (glTF 3.7.4).
TEST(LoadGltf, MirroredNodeKeepsFrontFace) {
  const auto bin = triangleBuffer();
  const std::string nodes = R"({"name": "mirror", "scale": [-1, 1, 1], "mesh": 0})";
  const Scene s = loadScene(writeText(freshDir() / "m.gltf", gltfJson(embedded(bin), bin.size(), nodes)));
  ASSERT_EQ(s.triangles.size(), 1u);
  const glm::vec3 a = s.positions[s.triangles[0].x], b = s.positions[s.triangles[0].y],
                  c = s.positions[s.triangles[0].z];
  EXPECT_GT(glm::cross(b - a, c - a).z, 0.0f);  // original triangle faces +z
}

TEST(LoadGltf, AlbedoIsFactorTimesMeanLinearTexture) {
  const auto dir = freshDir();
  writePng(dir / "base.png", 2, 2, {255, 128, 0, 0, 128, 255, 255, 128, 0, 0, 128, 255});
  const auto bin = triangleBuffer();
  std::string json = gltfJson(embedded(bin), bin.size(), R"({"mesh": 0})",
                              R"(,
  "images": [{"uri": "base.png"}],
  "textures": [{"source": 0}])");
  const std::string from = R"("baseColorFactor": [0.5, 0.25, 1.0, 1.0]})";
  json.replace(json.find(from), from.size(),
               R"("baseColorFactor": [0.5, 0.25, 1.0, 1.0], "baseColorTexture": {"index": 0}})");
  const Scene s = loadScene(writeText(dir / "tex.gltf", json));
  EXPECT_NEAR(s.materials[0].albedo.x, 0.25f, 1e-5f);
  EXPECT_NEAR(s.materials[0].albedo.y, 0.25f * kSrgb128, 1e-5f);
  EXPECT_NEAR(s.materials[0].albedo.z, 0.5f, 1e-5f);
}

TEST(LoadGltf, MissingTextureIsWarningNotFailure) {
  const auto dir = freshDir();
  const auto bin = triangleBuffer();
  std::string json = gltfJson(embedded(bin), bin.size(), R"({"mesh": 0})",
                              R"(,
  "images": [{"uri": "missing.png"}],
  "textures": [{"source": 0}])");
  const std::string from = R"("baseColorFactor": [0.5, 0.25, 1.0, 1.0]})";
  json.replace(json.find(from), from.size(),
               R"("baseColorFactor": [0.5, 0.25, 1.0, 1.0], "baseColorTexture": {"index": 0}})");
  const Scene s = loadScene(writeText(dir / "tex.gltf", json));
  EXPECT_EQ(s.materials[0].albedo, glm::vec3(0.5f, 0.25f, 1.0f));
  EXPECT_TRUE(anyWarningContains(s, "missing.png"));
}

TEST(LoadGltf, GlbContainerLoads) {
  const auto bin = triangleBuffer();
  const std::string json = gltfJson(R"({"byteLength": )" + std::to_string(bin.size()) + "}", bin.size(),
                                    R"({"translation": [0, 0, 7], "mesh": 0})");
  const Scene s = loadScene(test::writeGlb(freshDir() / "t.glb", json, bin));
  ASSERT_EQ(s.triangles.size(), 1u);
  EXPECT_EQ(s.positions[s.triangles[0].z], glm::vec3(0, 1, 7));
}

TEST(LoadGltf, NonIndexedPrimitiveLoads) {
  const auto bin = triangleBuffer();
  std::string json = gltfJson(embedded(bin), bin.size(), R"({"mesh": 0})");
  const std::string from = R"("indices": 1, )";
  json.replace(json.find(from), from.size(), "");
  const Scene s = loadScene(writeText(freshDir() / "n.gltf", json));
  EXPECT_EQ(s.triangles.size(), 1u);
}

TEST(LoadGltf, OutOfRangeIndexIsInputError) {
  const auto bin = triangleBuffer({0, 0, 0, 1, 0, 0, 0, 1, 0}, {0, 1, 5});
  const std::string msg =
      loadError(writeText(freshDir() / "oob.gltf", gltfJson(embedded(bin), bin.size(), R"({"mesh": 0})")));
  EXPECT_NE(msg.find("oob.gltf"), std::string::npos) << msg;
  EXPECT_NE(msg.find("index 5 out of range"), std::string::npos) << msg;
}

TEST(LoadGltf, NanCoordinateIsInputError) {
  const auto bin = triangleBuffer({0, 0, 0, NAN, 0, 0, 0, 1, 0});
  const std::string msg =
      loadError(writeText(freshDir() / "nan.gltf", gltfJson(embedded(bin), bin.size(), R"({"mesh": 0})")));
  EXPECT_NE(msg.find("non-finite"), std::string::npos) << msg;
}

TEST(LoadGltf, AccessorPastBufferIsInputError) {
  const auto bin = triangleBuffer();
  const std::string msg = loadError(writeText(
      freshDir() / "long.gltf", gltfJson(embedded(bin), bin.size(), R"({"mesh": 0})", "", /*posCount=*/4)));
  EXPECT_NE(msg.find("exceed"), std::string::npos) << msg;
}

TEST(LoadGltf, NodeCycleIsInputError) {
  const auto bin = triangleBuffer();
  const std::string nodes = R"({"children": [1], "mesh": 0}, {"children": [0]})";
  const std::string msg =
      loadError(writeText(freshDir() / "cycle.gltf", gltfJson(embedded(bin), bin.size(), nodes)));
  EXPECT_NE(msg.find("cycle"), std::string::npos) << msg;
}

// Draco or quantized meshes cannot be read as float positions: a required extension must fail loudly.
TEST(LoadGltf, UnsupportedRequiredExtensionIsInputError) {
  const auto bin = triangleBuffer();
  const std::string json = gltfJson(embedded(bin), bin.size(), R"({"mesh": 0})", R"(,
  "extensionsRequired": ["KHR_draco_mesh_compression"])");
  const std::string msg = loadError(writeText(freshDir() / "draco.gltf", json));
  EXPECT_NE(msg.find("KHR_draco_mesh_compression"), std::string::npos) << msg;
}

TEST(LoadGltf, MalformedJsonIsInputError) {
  const std::string msg = loadError(writeText(freshDir() / "bad.gltf", "{ \"asset\": { \"version\": "));
  EXPECT_NE(msg.find("bad.gltf"), std::string::npos) << msg;
}

TEST(LoadGltf, TruncatedGlbIsInputError) {
  const std::string msg = loadError(writeText(freshDir() / "short.glb", std::string("glTF\x02\0\0\0", 8)));
  EXPECT_NE(msg.find("short.glb"), std::string::npos) << msg;
}

}  // namespace
}  // namespace tetraprobe
