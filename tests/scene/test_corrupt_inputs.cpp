// Untrusted input: truncated and byte-flipped OBJ, MTL, glTF, GLB and scene JSON files must either load or
// throw InputError - never crash, hang or throw anything else. A fixed seed keeps failures reproducible; run
// under ASan/UBSan (-DCMAKE_CXX_FLAGS=-fsanitize=address,undefined) to catch out-of-bounds reads.
#include <fstream>
#include <iterator>
#include <random>
#include <string>

#include <gtest/gtest.h>

#include "scene_test_support.h"
#include "tetraprobe/common/error.h"
#include "tetraprobe/scene/load.h"

namespace tetraprobe {
namespace {

using test::freshDir;
using test::writeText;

const char* kObj =
    "mtllib c.mtl\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 0 0 1\nusemtl a\nf 1 2 3 4\nf -1 -2 -3\n"
    "usemtl b\nf 1/1 2/1 5/1\nvt 0 0\n";
const char* kMtl = "newmtl a\nKd 0.5 0.5 0.5\nmap_Kd t.png\nnewmtl b\nKe 1 2 3\n";

std::string gltf(const std::string& bufferUri) {
  return R"({"asset": {"version": "2.0"},
 "buffers": [{"byteLength": 44)" +
         bufferUri + R"(}],
 "bufferViews": [{"buffer": 0, "byteOffset": 0, "byteLength": 36}, {"buffer": 0, "byteOffset": 36, "byteLength": 8}],
 "accessors": [{"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3"},
               {"bufferView": 1, "componentType": 5123, "count": 3, "type": "SCALAR"}],
 "meshes": [{"primitives": [{"attributes": {"POSITION": 0}, "indices": 1, "material": 0}]}],
 "materials": [{"pbrMetallicRoughness": {"baseColorFactor": [1, 0, 0, 1], "baseColorTexture": {"index": 0}},
                "emissiveFactor": [1, 1, 1]}],
 "textures": [{"source": 0}], "images": [{"uri": "t.png"}],
 "extensions": {"KHR_lights_punctual": {"lights": [{"type": "spot", "intensity": 2, "spot": {}}]}},
 "cameras": [{"type": "perspective", "perspective": {"yfov": 1, "znear": 0.1}}],
 "nodes": [{"children": [1], "translation": [1, 2, 3]}, {"mesh": 0, "rotation": [0, 0, 0, 1], "children": [2]},
           {"camera": 0, "extensions": {"KHR_lights_punctual": {"light": 0}}}],
 "scenes": [{"nodes": [0]}], "scene": 0})";
}

std::vector<uint8_t> buffer() {
  std::vector<uint8_t> bin;
  test::appendBytes(bin, std::vector<float>{0, 0, 0, 1, 0, 0, 0, 1, 0});
  test::appendBytes(bin, std::vector<uint16_t>{0, 1, 2, 0});
  return bin;
}

// Loads `bytes` from `file`; any outcome but success or InputError fails the test.
void expectLoadsOrInputError(const std::filesystem::path& file, const std::string& bytes) {
  writeText(file, bytes);
  try {
    loadScene(file.string());
  } catch (const InputError&) {
  } catch (const std::exception& e) {
    ADD_FAILURE() << file << ": non-InputError exception: " << e.what();
  }
}

// Every prefix length on a coarse grid, then `flips` single-byte corruptions.
void mutate(const std::filesystem::path& file, const std::string& original, int flips, uint32_t seed) {
  for (size_t len = 0; len < original.size(); len += 1 + original.size() / 64)
    expectLoadsOrInputError(file, original.substr(0, len));
  std::mt19937 rng(seed);
  const char interesting[] = {'\0', '\n', ' ', '-', '9', '"', '{', ']', '/', '\xff', 'e', '.'};
  for (int i = 0; i < flips; ++i) {
    std::string s = original;
    const size_t at = rng() % s.size();
    s[at] = (rng() % 2) ? interesting[rng() % sizeof(interesting)] : static_cast<char>(rng() & 0xff);
    expectLoadsOrInputError(file, s);
  }
}

TEST(CorruptInput, ObjAndMtlLoadOrInputError) {
  const auto dir = freshDir();
  test::writePng(dir / "t.png", 1, 1, {10, 20, 30});
  writeText(dir / "c.mtl", kMtl);
  mutate(dir / "c.obj", kObj, 300, 1);
  writeText(dir / "c.obj", kObj);
  mutate(dir / "c.mtl", kMtl, 200, 2);
}

TEST(CorruptInput, GltfLoadsOrInputError) {
  const auto dir = freshDir();
  test::writePng(dir / "t.png", 1, 1, {10, 20, 30});
  const std::string json =
      gltf(R"(, "uri": "data:application/octet-stream;base64,)" + test::base64(buffer()) + "\"");
  expectLoadsOrInputError(dir / "ok.gltf", json);
  EXPECT_NO_THROW(loadScene((dir / "ok.gltf").string()));
  mutate(dir / "c.gltf", json, 400, 3);
}

TEST(CorruptInput, GlbLoadsOrInputError) {
  const auto dir = freshDir();
  test::writeGlb(dir / "ok.glb", gltf(""), buffer());
  EXPECT_NO_THROW(loadScene((dir / "ok.glb").string()));
  std::ifstream in(dir / "ok.glb", std::ios::binary);
  const std::string glb((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  mutate(dir / "c.glb", glb, 400, 4);
}

TEST(CorruptInput, SceneJsonLoadsOrInputError) {
  const auto dir = freshDir();
  writeText(dir / "m.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
  const std::string json = R"({"mesh": "m.obj", "unit_scale": 2, "sky": {"zenith": [1, 1, 1], "horizon": 0.5},
    "lights": [{"type": "spot", "position": [0, 1, 0], "direction": [0, -1, 0], "intensity": 3, "outer_cone_deg": 40}],
    "cameras": [{"name": "c", "eye": [0, 1, 2], "target": [0, 0, 0]}],
    "fine_volumes": [{"min": [0, 0, 0], "max": [1, 1, 1]}], "materials": {"default": {"emission_scale": 2}}})";
  expectLoadsOrInputError(dir / "ok.scene.json", json);
  EXPECT_NO_THROW(loadScene((dir / "ok.scene.json").string()));
  mutate(dir / "c.scene.json", json, 300, 5);
}

}  // namespace
}  // namespace tetraprobe
