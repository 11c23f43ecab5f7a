// Transparency in the loaders: OBJ d / Tr / map_d, glTF alphaMode BLEND / MASK and KHR_materials_transmission,
// scene JSON's transmission override. Each file is tiny and written by hand; cutout textures are 2 x 2 or 4 x 1
// PNGs whose texels say which corner of a quad is a hole.
#include <cmath>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "scene_test_support.h"
#include "tetraprobe/common/error.h"
#include "tetraprobe/scene/load.h"

namespace tetraprobe {
namespace {

using test::anyWarningContains;
using test::freshDir;
using test::loadError;
using test::writePngChannels;
using test::writeText;

const Material& named(const Scene& s, const std::string& name) {
  for (const Material& m : s.materials)
    if (m.name == name) return m;
  ADD_FAILURE() << "no material " << name;
  return s.materials.front();
}

// One unit quad per material, with texture coordinates equal to its x, y (so v = 0 is its bottom edge).
std::string quadsObj(const std::vector<std::string>& materials) {
  std::string obj = "mtllib m.mtl\nvt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\n";
  for (size_t i = 0; i < materials.size(); ++i) {
    const std::string z = std::to_string(i);
    obj += "v 0 0 " + z + "\nv 1 0 " + z + "\nv 1 1 " + z + "\nv 0 1 " + z + "\n";
    obj += "usemtl " + materials[i] + "\nf " + std::to_string(4 * i + 1) + "/1 " + std::to_string(4 * i + 2) +
           "/2 " + std::to_string(4 * i + 3) + "/3 " + std::to_string(4 * i + 4) + "/4\n";
  }
  return obj;
}

// tinyobjloader reads d as dissolve and Tr as 1 - dissolve (d wins over Tr): transmission = 1 - dissolve.
TEST(LoadObj, DissolveAndTrBecomeTransmission) {
  const auto dir = freshDir();
  writeText(dir / "m.mtl",
            "newmtl opaque\nKd 0.5 0.5 0.5\n"
            "newmtl dissolved\nKd 0.5 0.5 0.5\nd 0.25\n"
            "newmtl tr\nKd 0.5 0.5 0.5\nTr 0.6\n"
            "newmtl both\nKd 0.5 0.5 0.5\nd 1\nTr 0.5\n");
  const Scene s = loadScene(writeText(dir / "q.obj", quadsObj({"opaque", "dissolved", "tr", "both"})));
  EXPECT_EQ(named(s, "opaque").transmission, 0.0f);
  EXPECT_NEAR(named(s, "dissolved").transmission, 0.75f, 1e-6f);
  EXPECT_NEAR(named(s, "tr").transmission, 0.6f, 1e-6f);
  EXPECT_EQ(named(s, "both").transmission, 0.0f);
  EXPECT_TRUE(s.alphaTextures.empty());
  EXPECT_TRUE(s.cutoutTriangles.empty());
}

// map_d is an alpha cutout at 0.5 sampled per texel; OBJ's v runs up from the image's bottom row, so the
// loader flips it into the top-left convention AlphaTexture::sample uses.
TEST(LoadObj, MapDCutsHolesPerTexel) {
  const auto dir = freshDir();
  // RGBA 2 x 2, rows top to bottom: top-left hole, top-right solid; bottom-left solid, bottom-right hole.
  writePngChannels(dir / "tex" / "cut.png", 2, 2, 4, {9, 9, 9, 0, 9, 9, 9, 255, 9, 9, 9, 200, 9, 9, 9, 100});
  writeText(dir / "m.mtl", "newmtl leaves\nKd 0.3 0.6 0.2\nmap_d tex/cut.png\nnewmtl plain\nKd 1 1 1\n");
  const Scene s = loadScene(writeText(dir / "q.obj", quadsObj({"leaves", "plain"})));
  ASSERT_EQ(s.alphaTextures.size(), 1u);
  const Material& m = named(s, "leaves");
  EXPECT_EQ(m.alphaTexture, 0);
  EXPECT_EQ(m.alphaCutoff, 0.5f);
  EXPECT_EQ(m.transmission, 0.0f);
  EXPECT_EQ(named(s, "plain").alphaTexture, -1);
  // Only the two triangles of the first quad are listed, with 3 coordinates each.
  ASSERT_EQ(s.cutoutTriangles, (std::vector<uint32_t>{0, 1}));
  ASSERT_EQ(s.cutoutUvs.size(), 6u);
  EXPECT_EQ(s.cutoutUvs[0], glm::vec2(0.0f, 1.0f));  // vt 0 0: the image's bottom-left corner
  const AlphaTexture& t = s.alphaTextures[0];
  EXPECT_EQ(t.width, 2u);
  EXPECT_EQ(t.height, 2u);
  // Sampled where the quad's corners are (x, y of the quad = OBJ u, v).
  auto alphaAt = [&](float x, float y) { return t.sample({x, 1.0f - y}); };
  EXPECT_LT(alphaAt(0.25f, 0.75f), 0.5f);                   // top-left: hole
  EXPECT_GE(alphaAt(0.75f, 0.75f), 0.5f);                   // top-right: solid
  EXPECT_GE(alphaAt(0.25f, 0.25f), 0.5f);                   // bottom-left: solid (200)
  EXPECT_LT(alphaAt(0.75f, 0.25f), 0.5f);                   // bottom-right: hole (100)
  EXPECT_EQ(alphaAt(1.25f, 0.75f), alphaAt(0.25f, 0.75f));  // repeat wrap
}

// A map_d without an alpha channel is read from its grey value (common for alpha maps).
TEST(LoadObj, GreyMapDIsTheAlpha) {
  const auto dir = freshDir();
  writePngChannels(dir / "grey.png", 2, 1, 1, {0, 255});
  writeText(dir / "m.mtl", "newmtl fence\nmap_d grey.png\n");
  const Scene s = loadScene(writeText(dir / "q.obj", quadsObj({"fence"})));
  ASSERT_EQ(s.alphaTextures.size(), 1u);
  EXPECT_EQ(s.alphaTextures[0].alpha, (std::vector<uint8_t>{0, 255}));
}

// A map_d that is all holes lets everything through without keeping a texture; one without holes changes
// nothing.
TEST(LoadObj, UniformMapDNeedsNoTexture) {
  const auto dir = freshDir();
  writePngChannels(dir / "clear.png", 2, 1, 1, {0, 10});
  writePngChannels(dir / "solid.png", 2, 1, 1, {200, 255});
  writeText(dir / "m.mtl", "newmtl clear\nmap_d clear.png\nnewmtl solid\nmap_d solid.png\n");
  const Scene s = loadScene(writeText(dir / "q.obj", quadsObj({"clear", "solid"})));
  EXPECT_TRUE(s.alphaTextures.empty());
  EXPECT_EQ(named(s, "clear").transmission, 1.0f);
  EXPECT_EQ(named(s, "clear").alphaTexture, -1);
  EXPECT_EQ(named(s, "solid").transmission, 0.0f);
  EXPECT_EQ(named(s, "solid").alphaTexture, -1);
  EXPECT_TRUE(s.cutoutTriangles.empty());
}

// A missing or undecodable alpha texture is a warning and the material stays opaque: never a failure.
TEST(LoadObj, BadAlphaTextureWarnsAndStaysOpaque) {
  const auto dir = freshDir();
  writeText(dir / "broken.png", "not a png");
  writeText(dir / "m.mtl", "newmtl gone\nmap_d missing.png\nnewmtl broken\nmap_d broken.png\n");
  const Scene s = loadScene(writeText(dir / "q.obj", quadsObj({"gone", "broken"})));
  EXPECT_TRUE(anyWarningContains(s, "missing.png"));
  EXPECT_TRUE(anyWarningContains(s, "broken.png"));
  EXPECT_EQ(named(s, "gone").alphaTexture, -1);
  EXPECT_EQ(named(s, "broken").alphaTexture, -1);
  EXPECT_EQ(named(s, "gone").transmission, 0.0f);
  EXPECT_TRUE(s.cutoutTriangles.empty());
}

// Faces of a cutout material without texture coordinates cannot be cut: a warning, and they stay opaque.
TEST(LoadObj, CutoutFacesWithoutTexcoordsWarn) {
  const auto dir = freshDir();
  writePngChannels(dir / "cut.png", 2, 1, 1, {0, 255});
  writeText(dir / "m.mtl", "newmtl fence\nmap_d cut.png\n");
  const Scene s =
      loadScene(writeText(dir / "q.obj", "mtllib m.mtl\nv 0 0 0\nv 1 0 0\nv 1 1 0\nusemtl fence\nf 1 2 3\n"));
  EXPECT_EQ(named(s, "fence").alphaTexture, 0);
  EXPECT_TRUE(s.cutoutTriangles.empty());
  EXPECT_TRUE(anyWarningContains(s, "no texture coordinates"));
}

// Dropping a zero-area triangle keeps cutoutTriangles naming the same (renumbered) triangles.
TEST(LoadObj, DroppedTrianglesKeepCutoutsAligned) {
  const auto dir = freshDir();
  writePngChannels(dir / "cut.png", 2, 1, 1, {0, 255});
  writeText(dir / "m.mtl", "newmtl fence\nmap_d cut.png\n");
  const Scene s = loadScene(writeText(dir / "q.obj",
                                      "mtllib m.mtl\nvt 0 0\nvt 1 0\nvt 1 1\n"
                                      "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 2 2 0\n"
                                      "usemtl fence\nf 1/1 2/2 1/3\nf 1/1 2/2 3/3\n"));
  ASSERT_EQ(s.triangles.size(), 1u);
  EXPECT_EQ(s.cutoutTriangles, (std::vector<uint32_t>{0}));
  ASSERT_EQ(s.cutoutUvs.size(), 3u);
  EXPECT_EQ(s.cutoutUvs[2], glm::vec2(1.0f, 0.0f));  // vt 1 1, v flipped
}

// ---- glTF ----

// One unit quad (2 triangles) with TEXCOORD_0 = its x, y; `materials` and `extra` spliced in.
std::string quadGltf(const std::string& materials, const std::string& extra = "",
                     const std::string& required = "") {
  std::vector<uint8_t> bin;
  test::appendBytes(bin, std::vector<float>{0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0});  // 48 bytes
  test::appendBytes(bin, std::vector<float>{0, 0, 1, 0, 1, 1, 0, 1});              // 32 bytes
  test::appendBytes(bin, std::vector<uint16_t>{0, 1, 2, 0, 2, 3});                 // 12 bytes
  return R"({
  "asset": {"version": "2.0"},)" +
         (required.empty() ? std::string() : R"( "extensionsRequired": [")" + required + R"("],)") + R"(
  "buffers": [{"byteLength": 92, "uri": "data:application/octet-stream;base64,)" +
         test::base64(bin) + R"("}],
  "bufferViews": [
    {"buffer": 0, "byteOffset": 0, "byteLength": 48},
    {"buffer": 0, "byteOffset": 48, "byteLength": 32},
    {"buffer": 0, "byteOffset": 80, "byteLength": 12}
  ],
  "accessors": [
    {"bufferView": 0, "componentType": 5126, "count": 4, "type": "VEC3"},
    {"bufferView": 1, "componentType": 5126, "count": 4, "type": "VEC2"},
    {"bufferView": 2, "componentType": 5123, "count": 6, "type": "SCALAR"}
  ],
  "meshes": [{"primitives": [{"attributes": {"POSITION": 0, "TEXCOORD_0": 1}, "indices": 2, "material": 0}]}],
  "materials": [)" +
         materials + R"(],
  "nodes": [{"mesh": 0}],
  "scenes": [{"nodes": [0]}],
  "scene": 0)" +
         extra + "\n}\n";
}

// BLEND is coverage: a fraction alpha (factor x mean texture alpha) of the surface is there.
TEST(LoadGltf, BlendTransmissionIsOneMinusAlpha) {
  const auto dir = freshDir();
  writePngChannels(dir / "a.png", 2, 1, 4, {255, 255, 255, 0, 255, 255, 255, 255});  // mean alpha 0.5
  const Scene plain = loadScene(writeText(
      dir / "plain.gltf",
      quadGltf(R"({"alphaMode": "BLEND", "pbrMetallicRoughness": {"baseColorFactor": [1, 1, 1, 0.25]}})")));
  EXPECT_NEAR(plain.materials[0].transmission, 0.75f, 1e-6f);
  const Scene textured = loadScene(writeText(dir / "tex.gltf", quadGltf(R"({"alphaMode": "BLEND",
      "pbrMetallicRoughness": {"baseColorFactor": [1, 1, 1, 0.5], "baseColorTexture": {"index": 0}}})",
                                                                        R"(,
  "images": [{"uri": "a.png"}], "textures": [{"source": 0}])")));
  EXPECT_NEAR(textured.materials[0].transmission, 0.75f, 1e-6f);  // 1 - 0.5 x 0.5
  EXPECT_TRUE(textured.alphaTextures.empty());                    // only the mean is kept
  EXPECT_TRUE(textured.warnings.empty()) << textured.warnings.front();
}

// MASK cuts per texel where factor alpha x texel alpha < alphaCutoff; wrap modes come from the sampler.
TEST(LoadGltf, MaskCutsHolesPerTexelAtTheCutoff) {
  const auto dir = freshDir();
  // 4 x 1 texels, alpha 0, 100, 160, 255: with factor 0.8 and cutoff 0.5, texel alpha must be >= 0.625
  // (159.4 / 255): holes at the first two texels only.
  writePngChannels(dir / "a.png", 4, 1, 4, {0, 0, 0, 0, 0, 0, 0, 100, 0, 0, 0, 160, 0, 0, 0, 255});
  const Scene s = loadScene(writeText(dir / "mask.gltf", quadGltf(R"({"name": "fence", "alphaMode": "MASK",
      "pbrMetallicRoughness": {"baseColorFactor": [1, 1, 1, 0.8], "baseColorTexture": {"index": 0}}})",
                                                                  R"(,
  "images": [{"uri": "a.png"}], "samplers": [{"wrapS": 33071, "wrapT": 33648}],
  "textures": [{"source": 0, "sampler": 0}])")));
  ASSERT_EQ(s.alphaTextures.size(), 1u);
  const Material& m = s.materials[0];
  ASSERT_EQ(m.alphaTexture, 0);
  EXPECT_EQ(m.transmission, 0.0f);
  const AlphaTexture& t = s.alphaTextures[0];
  EXPECT_EQ(t.wrapU, TextureWrap::kClampToEdge);
  EXPECT_EQ(t.wrapV, TextureWrap::kMirroredRepeat);
  const float xs[4] = {0.125f, 0.375f, 0.625f, 0.875f};
  const bool hole[4] = {true, true, false, false};
  for (int i = 0; i < 4; ++i) EXPECT_EQ(t.sample({xs[i], 0.5f}) < m.alphaCutoff, hole[i]) << "texel " << i;
  EXPECT_EQ(t.sample({-3.0f, 0.5f}), t.sample({0.125f, 0.5f}));  // clamped
  // Both triangles listed, corners in triangle order with glTF's (unflipped) coordinates.
  ASSERT_EQ(s.cutoutTriangles, (std::vector<uint32_t>{0, 1}));
  EXPECT_EQ(s.cutoutUvs[1], glm::vec2(1.0f, 0.0f));
  EXPECT_EQ(s.cutoutUvs[5], glm::vec2(0.0f, 1.0f));
}

// KHR_texture_transform on the base-colour texture moves the coordinates the cutout samples.
TEST(LoadGltf, MaskFollowsTextureTransform) {
  const auto dir = freshDir();
  writePngChannels(dir / "a.png", 2, 1, 4, {0, 0, 0, 0, 0, 0, 0, 255});
  const Scene s = loadScene(writeText(dir / "mask.gltf", quadGltf(R"({"alphaMode": "MASK",
      "pbrMetallicRoughness": {"baseColorTexture": {"index": 0,
        "extensions": {"KHR_texture_transform": {"offset": [0.5, 0], "scale": [0.5, 1]}}}}})",
                                                                  R"(,
  "images": [{"uri": "a.png"}], "textures": [{"source": 0}])",
                                                                  "KHR_texture_transform")));
  ASSERT_EQ(s.cutoutUvs.size(), 6u);
  EXPECT_EQ(s.cutoutUvs[0], glm::vec2(0.5f, 0.0f));
  EXPECT_EQ(s.cutoutUvs[1], glm::vec2(1.0f, 0.0f));
}

// MASK without a texture is all or nothing; an unreadable texture is a warning and opaque.
TEST(LoadGltf, MaskWithoutUsableTextureIsUniform) {
  const auto dir = freshDir();
  const Scene below = loadScene(writeText(
      dir / "below.gltf",
      quadGltf(
          R"({"alphaMode": "MASK", "alphaCutoff": 0.6, "pbrMetallicRoughness": {"baseColorFactor": [1, 1, 1, 0.5]}})")));
  EXPECT_EQ(below.materials[0].transmission, 1.0f);
  const Scene above = loadScene(writeText(
      dir / "above.gltf",
      quadGltf(R"({"alphaMode": "MASK", "pbrMetallicRoughness": {"baseColorFactor": [1, 1, 1, 0.5]}})")));
  EXPECT_EQ(above.materials[0].transmission, 0.0f);
  const Scene missing = loadScene(writeText(dir / "missing.gltf", quadGltf(R"({"alphaMode": "MASK",
      "pbrMetallicRoughness": {"baseColorTexture": {"index": 0}}})",
                                                                           R"(,
  "images": [{"uri": "nowhere.png"}], "textures": [{"source": 0}])")));
  EXPECT_EQ(missing.materials[0].alphaTexture, -1);
  EXPECT_EQ(missing.materials[0].transmission, 0.0f);
  EXPECT_TRUE(anyWarningContains(missing, "nowhere.png"));
}

// KHR_materials_transmission's factor (x mean red of transmissionTexture) is the transmission, combined with
// BLEND coverage as 1 - (1 - t_blend)(1 - t).
TEST(LoadGltf, KhrMaterialsTransmissionSetsTransmission) {
  const auto dir = freshDir();
  const Scene glass = loadScene(writeText(dir / "glass.gltf", quadGltf(R"({"name": "glass",
      "extensions": {"KHR_materials_transmission": {"transmissionFactor": 0.9}}})",
                                                                       "", "KHR_materials_transmission")));
  EXPECT_NEAR(glass.materials[0].transmission, 0.9f, 1e-6f);
  writePngChannels(dir / "t.png", 2, 1, 1, {0, 255});  // mean red 0.5
  const Scene both = loadScene(writeText(dir / "both.gltf", quadGltf(R"({"alphaMode": "BLEND",
      "pbrMetallicRoughness": {"baseColorFactor": [1, 1, 1, 0.5]},
      "extensions": {"KHR_materials_transmission": {"transmissionFactor": 0.8, "transmissionTexture": {"index": 0}}}})",
                                                                     R"(,
  "images": [{"uri": "t.png"}], "textures": [{"source": 0}])")));
  EXPECT_NEAR(both.materials[0].transmission, 1.0f - 0.5f * (1.0f - 0.4f), 1e-6f);
}

// ---- scene JSON ----

TEST(LoadSceneJson, TransmissionOverrideIsReadAndRangeChecked) {
  const auto dir = freshDir();
  writeText(dir / "m.mtl", "newmtl pane\nKd 0.9 0.9 0.9\n");
  writeText(dir / "q.obj", quadsObj({"pane"}));
  const Scene s = loadScene(
      writeText(dir / "s.scene.json", R"({"mesh": "q.obj", "materials": {"pane": {"transmission": 0.7}}})"));
  EXPECT_NEAR(named(s, "pane").transmission, 0.7f, 1e-6f);
  const std::string msg = loadError(writeText(
      dir / "bad.scene.json", R"({"mesh": "q.obj", "materials": {"pane": {"transmission": 1.5}}})"));
  EXPECT_NE(msg.find("materials.pane.transmission: must be in [0, 1]"), std::string::npos) << msg;
}

}  // namespace
}  // namespace tetraprobe
