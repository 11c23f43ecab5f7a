// Whole files: the bundled two_rooms sample always; the shared reference scenes (../shared/scenes) when
// present, checked against the triangle counts in their README (a loader may drop zero-area triangles, never
// more).
#include <algorithm>
#include <filesystem>
#include <iostream>

#include <gtest/gtest.h>
#include <glm/geometric.hpp>

#include "missing_capability.h"
#include "scene_test_support.h"
#include "tetraprobe/scene/load.h"

namespace tetraprobe {
namespace {

const std::filesystem::path kShared = TETRAPROBE_SHARED_SCENES;
const std::filesystem::path kSource = TETRAPROBE_SOURCE_DIR;

size_t emissiveMaterialsUsed(const Scene& s) {
  std::vector<bool> used(s.materials.size(), false);
  for (uint32_t m : s.triangleMaterial) used[m] = true;
  size_t n = 0;
  for (size_t i = 0; i < s.materials.size(); ++i) {
    const glm::vec3 e = s.materials[i].emission;
    if (used[i] && (e.x > 0 || e.y > 0 || e.z > 0)) ++n;
  }
  return n;
}

TEST(TwoRoomsSample, LoadsWithOneEmissiveMaterialAndItsCameras) {
  const Scene s = loadScene((kSource / "samples/two_rooms/two_rooms.scene.json").string());
  EXPECT_GE(s.triangles.size(), 300u);
  EXPECT_LE(s.triangles.size(), 2000u);
  EXPECT_EQ(emissiveMaterialsUsed(s), 1u);
  EXPECT_TRUE(s.lights.empty());
  EXPECT_EQ(s.skyRadiance, glm::vec3(0.0f));
  ASSERT_EQ(s.cameras.size(), 3u);
  EXPECT_EQ(s.cameras[0].name, "overview");
  EXPECT_EQ(s.cameras[1].name, "doorway");
  EXPECT_EQ(s.cameras[2].name, "room_b");
  EXPECT_TRUE(s.warnings.empty()) << s.warnings.front();
  glm::vec3 lo, hi;
  sceneBounds(s, lo, hi);
  EXPECT_EQ(lo, glm::vec3(0.0f));
  EXPECT_NEAR(hi.x, 8.2f, 1e-5f);
  EXPECT_EQ(hi.y, 3.0f);
  EXPECT_EQ(hi.z, 4.0f);
}

// The light is in room A only: every emissive triangle lies at x < 4 and faces down.
TEST(TwoRoomsSample, EmitterIsInRoomAFacingDown) {
  const Scene s = loadScene((kSource / "samples/two_rooms/two_rooms.obj").string());
  size_t emitters = 0;
  for (size_t t = 0; t < s.triangles.size(); ++t) {
    if (s.materials[s.triangleMaterial[t]].emission == glm::vec3(0.0f)) continue;
    ++emitters;
    const glm::vec3 a = s.positions[s.triangles[t].x], b = s.positions[s.triangles[t].y],
                    c = s.positions[s.triangles[t].z];
    EXPECT_LT(std::max({a.x, b.x, c.x}), 4.0f);
    EXPECT_LT(glm::cross(b - a, c - a).y, 0.0f);
  }
  EXPECT_GT(emitters, 0u);
}

// Number N in a "dropped N zero-area triangles" warning, 0 if none.
size_t droppedDegenerate(const Scene& s) {
  for (const auto& w : s.warnings) {
    const size_t at = w.find("dropped ");
    if (at != std::string::npos && w.find("zero-area", at) != std::string::npos)
      return std::stoul(w.substr(at + 8));
  }
  return 0;
}

// Loaded + dropped-degenerate triangles must equal the README count; the drop may not exceed 2 %.
void expectTriangles(const std::string& file, size_t expected, size_t emissive) {
  const auto path = kShared / file;
  if (!std::filesystem::exists(path)) TETRAPROBE_SKIP_MISSING(path << " not present");
  const Scene s = loadScene(path.string());
  const size_t dropped = droppedDegenerate(s);
  EXPECT_EQ(s.triangles.size() + dropped, expected) << file;
  EXPECT_LE(dropped, expected / 50) << file;
  if (emissive > 0) {
    EXPECT_GE(emissiveMaterialsUsed(s), emissive) << file;
  }
  std::cout << "  " << file << ": " << s.triangles.size() << " triangles (+" << dropped
            << " zero-area dropped), " << s.materials.size() << " materials, " << s.warnings.size()
            << " warnings\n";
}

TEST(SharedScenes, VeachAjarObjTriangleCount) {
  expectTriangles("veach_ajar/veach_ajar.obj", 4546, 1);
}
TEST(SharedScenes, VeachAjarGlbTriangleCount) {
  expectTriangles("veach_ajar/veach_ajar.glb", 4546, 1);
}
TEST(SharedScenes, CornellBoxObjTriangleCount) {
  expectTriangles("cornell_box/CornellBox-Original.obj", 36, 1);
}
TEST(SharedScenes, CornellBoxGlbTriangleCount) {
  expectTriangles("cornell_box/CornellBox-Original.glb", 36, 1);
}
TEST(SharedScenes, SponzaObjTriangleCount) {
  expectTriangles("sponza_dabrovic/sponza.obj", 66450, 0);
}
TEST(SharedScenes, SponzaGlbTriangleCount) {
  expectTriangles("sponza_dabrovic/sponza.glb", 66450, 0);
}
TEST(SharedScenes, CornellDataObjTriangleCount) {
  expectTriangles("cornell_box/cornell_box_cornelldata.obj", 36, 1);
}
TEST(SharedScenes, ConferenceObjTriangleCount) {
  expectTriangles("conference/conference.obj", 69047, 0);
}
TEST(SharedScenes, ConferenceGlbTriangleCount) {
  expectTriangles("conference/conference.glb", 69047, 0);
}
TEST(SharedScenes, Dm4ishObjTriangleCount) {
  expectTriangles("q3_dm4ish/dm4ish.obj", 3430, 1);
}
TEST(SharedScenes, Dm4ishGlbTriangleCount) {
  expectTriangles("q3_dm4ish/dm4ish.glb", 3430, 1);
}

TEST(SharedScenes, SponzaTexturesAllResolve) {
  const auto path = kShared / "sponza_dabrovic/sponza.obj";
  if (!std::filesystem::exists(path)) TETRAPROBE_SKIP_MISSING(path << " not present");
  const Scene s = loadScene(path.string());
  EXPECT_FALSE(test::anyWarningContains(s, "not found"));
  EXPECT_FALSE(test::anyWarningContains(s, "cannot decode"));
}

}  // namespace
}  // namespace tetraprobe

namespace tetraprobe {
namespace {

// An OBJ and the glTF converted from it must give the same albedo and emission for every material name: the
// loaders interpret Kd/baseColorFactor, map_Kd/baseColorTexture and Ke/emissiveFactor the same way.
void expectObjAndGlbAgree(const std::string& obj, const std::string& glb) {
  if (!std::filesystem::exists(kShared / obj) || !std::filesystem::exists(kShared / glb))
    TETRAPROBE_SKIP_MISSING("shared scenes not present: " << kShared);
  const Scene a = loadScene((kShared / obj).string());
  const Scene b = loadScene((kShared / glb).string());
  size_t compared = 0;
  for (const Material& ma : a.materials) {
    for (const Material& mb : b.materials) {
      if (ma.name != mb.name) continue;
      ++compared;
      EXPECT_NEAR(glm::distance(ma.albedo, mb.albedo), 0.0f, 1e-4f) << ma.name;
      EXPECT_NEAR(glm::distance(ma.emission, mb.emission), 0.0f, 1e-3f) << ma.name;
    }
  }
  EXPECT_GE(compared + 1, a.materials.size());  // all but at most an unused default
}

TEST(SharedScenes, SponzaObjAndGlbMaterialsAgree) {
  expectObjAndGlbAgree("sponza_dabrovic/sponza.obj", "sponza_dabrovic/sponza.glb");
}
TEST(SharedScenes, VeachAjarObjAndGlbMaterialsAgree) {
  expectObjAndGlbAgree("veach_ajar/veach_ajar.obj", "veach_ajar/veach_ajar.glb");
}
TEST(SharedScenes, Dm4ishObjAndGlbMaterialsAgree) {
  expectObjAndGlbAgree("q3_dm4ish/dm4ish.obj", "q3_dm4ish/dm4ish.glb");
}

}  // namespace
}  // namespace tetraprobe

namespace tetraprobe {
namespace {

// The measurement scene descriptions in samples/shared follow docs/scene_format.md: they load, warning-free
// apart from dropped zero-area triangles, whenever the shared scenes are present.
TEST(SharedScenes, SceneDescriptionsLoadWithoutUnexpectedWarnings) {
  if (!std::filesystem::exists(kShared / "README.md"))
    TETRAPROBE_SKIP_MISSING("shared scenes not present: " << kShared);
  const auto dir = kSource / "samples/shared";
  ASSERT_TRUE(std::filesystem::exists(dir)) << dir << " is part of the repository";
  size_t loaded = 0;
  for (const auto& entry : std::filesystem::directory_iterator(dir)) {
    const std::string name = entry.path().filename().string();
    if (name.size() < 11 || name.compare(name.size() - 11, 11, ".scene.json") != 0) continue;
    const Scene s = loadScene(entry.path().string());
    ++loaded;
    EXPECT_FALSE(s.cameras.empty()) << name;
    for (const auto& w : s.warnings) EXPECT_NE(w.find("zero-area"), std::string::npos) << name << ": " << w;
  }
  EXPECT_GT(loaded, 0u);
}

}  // namespace
}  // namespace tetraprobe
