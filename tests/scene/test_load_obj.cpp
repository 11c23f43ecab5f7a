// OBJ/MTL loading: triangulation, materials (Kd x mean linear map_Kd, Ke), forgiving texture paths, warnings
// for missing files, and InputError (with the line) for bad vertices and indices.
#include <cmath>

#include <gtest/gtest.h>

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

// Two unit quads (z = 0 and z = 1) and one pentagon: 2 + 2 + 3 triangles.
const char* kQuadsObj =
    "mtllib m.mtl\n"
    "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\n"
    "usemtl textured\n"
    "f 1 2 3 4\n"
    "v 0 0 1\nv 1 0 1\nv 1 1 1\nv 0 1 1\n"
    "usemtl glow\n"
    "f -1 -2 -3 -4\n"  // relative indices, reversed winding: vertices 8 7 6 5
    "v 0 0 2\nv 1 0 2\nv 1.5 0.5 2\nv 1 1 2\nv 0 1 2\n"
    "f 9 10 11 12 13\n";

// 2 x 2 texels: two (255,128,0) and two (0,128,255). Mean linear colour: (0.5, srgb(128), 0.5).
std::vector<uint8_t> halfTexture() {
  return {255, 128, 0, 0, 128, 255, 255, 128, 0, 0, 128, 255};
}
constexpr float kSrgb128 = 0.2158605f;  // ((128/255 + 0.055) / 1.055)^2.4

const Material* findMaterial(const Scene& s, const std::string& name) {
  for (const auto& m : s.materials) {
    if (m.name == name) return &m;
  }
  return nullptr;
}

TEST(LoadObj, TriangleCountMatchesFaces) {
  const auto dir = freshDir();
  writeText(dir / "m.mtl", "newmtl textured\nKd 1 1 1\nnewmtl glow\nKd 0 0 0\nKe 2 3 4\n");
  const Scene s = loadScene(writeText(dir / "quads.obj", kQuadsObj));
  EXPECT_EQ(s.positions.size(), 13u);
  EXPECT_EQ(s.triangles.size(), 7u);  // quad 2 + quad 2 + pentagon 3
  EXPECT_EQ(s.triangleMaterial.size(), s.triangles.size());
}

TEST(LoadObj, RelativeIndicesResolveAndWindingIsKept) {
  const auto dir = freshDir();
  writeText(dir / "m.mtl", "newmtl textured\nKd 1 1 1\nnewmtl glow\nKd 0 0 0\nKe 2 3 4\n");
  const Scene s = loadScene(writeText(dir / "quads.obj", kQuadsObj));
  // Second quad (z = 1) is listed 8 7 6 5: clockwise seen from +z, so its normal points to -z.
  int seen = 0;
  for (size_t t = 0; t < s.triangles.size(); ++t) {
    const glm::vec3 a = s.positions[s.triangles[t].x], b = s.positions[s.triangles[t].y],
                    c = s.positions[s.triangles[t].z];
    if (a.z != 1.0f || b.z != 1.0f || c.z != 1.0f) continue;
    const glm::vec3 e1 = b - a, e2 = c - a;
    EXPECT_LT(e1.x * e2.y - e1.y * e2.x, 0.0f) << "triangle " << t;
    ++seen;
  }
  EXPECT_EQ(seen, 2);
}

TEST(LoadObj, AlbedoIsKdTimesMeanLinearTextureColour) {
  const auto dir = freshDir();
  writePng(dir / "tex.png", 2, 2, halfTexture());
  writeText(dir / "m.mtl", "newmtl textured\nKd 0.5 1 1\nmap_Kd tex.png\nnewmtl glow\nKd 0 0 0\nKe 2 3 4\n");
  const Scene s = loadScene(writeText(dir / "quads.obj", kQuadsObj));
  const Material* m = findMaterial(s, "textured");
  ASSERT_NE(m, nullptr);
  EXPECT_NEAR(m->albedo.x, 0.25f, 1e-5f);
  EXPECT_NEAR(m->albedo.y, kSrgb128, 1e-5f);
  EXPECT_NEAR(m->albedo.z, 0.5f, 1e-5f);
  EXPECT_TRUE(s.warnings.empty()) << s.warnings.front();
}

TEST(LoadObj, EmissionIsKe) {
  const auto dir = freshDir();
  writeText(dir / "m.mtl", "newmtl textured\nKd 1 1 1\nnewmtl glow\nKd 0 0 0\nKe 2 3 4\n");
  const Scene s = loadScene(writeText(dir / "quads.obj", kQuadsObj));
  const Material* m = findMaterial(s, "glow");
  ASSERT_NE(m, nullptr);
  EXPECT_EQ(m->emission, glm::vec3(2, 3, 4));
  EXPECT_EQ(m->albedo, glm::vec3(0.0f));
  EXPECT_EQ(findMaterial(s, "textured")->emission, glm::vec3(0.0f));
}

// Material files written on Windows name textures with backslashes and in another case.
TEST(LoadObj, TexturePathWithBackslashesAndOddCaseResolves) {
  const auto dir = freshDir();
  writePng(dir / "Textures" / "half.png", 2, 2, halfTexture());
  writeText(dir / "m.mtl", "newmtl textured\nKd 1 1 1\nmap_Kd textures\\HALF.PNG\nnewmtl glow\nKe 1 1 1\n");
  const Scene s = loadScene(writeText(dir / "quads.obj", kQuadsObj));
  EXPECT_NEAR(findMaterial(s, "textured")->albedo.x, 0.5f, 1e-5f);
  EXPECT_FALSE(anyWarningContains(s, "not found"));
}

// A material library in a subfolder names its textures relative to itself.
TEST(LoadObj, TextureBesideMtlInSubfolderResolves) {
  const auto dir = freshDir();
  writePng(dir / "materials" / "half.png", 2, 2, halfTexture());
  writeText(dir / "materials" / "m.mtl", "newmtl textured\nKd 1 1 1\nmap_Kd half.png\n");
  const Scene s = loadScene(writeText(
      dir / "q.obj", "mtllib materials/m.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl textured\nf 1 2 3\n"));
  ASSERT_NE(findMaterial(s, "textured"), nullptr);
  EXPECT_NEAR(findMaterial(s, "textured")->albedo.x, 0.5f, 1e-5f);
  EXPECT_TRUE(s.warnings.empty()) << s.warnings.front();
}

TEST(LoadObj, MissingTextureIsWarningNotFailure) {
  const auto dir = freshDir();
  writeText(dir / "m.mtl", "newmtl textured\nKd 0.3 0.4 0.5\nmap_Kd nowhere.png\nnewmtl glow\nKe 1 1 1\n");
  const Scene s = loadScene(writeText(dir / "quads.obj", kQuadsObj));
  EXPECT_EQ(findMaterial(s, "textured")->albedo, glm::vec3(0.3f, 0.4f, 0.5f));  // Kd alone
  EXPECT_TRUE(anyWarningContains(s, "nowhere.png"));
}

TEST(LoadObj, UndecodableTextureIsWarningNotFailure) {
  const auto dir = freshDir();
  writeText(dir / "junk.png", "this is not a png");
  writeText(dir / "m.mtl", "newmtl textured\nKd 0.3 0.4 0.5\nmap_Kd junk.png\nnewmtl glow\nKe 1 1 1\n");
  const Scene s = loadScene(writeText(dir / "quads.obj", kQuadsObj));
  EXPECT_EQ(findMaterial(s, "textured")->albedo, glm::vec3(0.3f, 0.4f, 0.5f));
  EXPECT_TRUE(anyWarningContains(s, "junk.png"));
}

TEST(LoadObj, MissingMtlIsWarningAndDefaultMaterial) {
  const auto dir = freshDir();
  const Scene s = loadScene(writeText(dir / "quads.obj", kQuadsObj));
  EXPECT_EQ(s.triangles.size(), 7u);
  EXPECT_FALSE(s.warnings.empty());
  ASSERT_EQ(s.materials.size(), 1u);
  EXPECT_EQ(s.materials[0].name, "default");
  for (uint32_t m : s.triangleMaterial) EXPECT_EQ(m, 0u);
}

TEST(LoadObj, DegenerateTrianglesDroppedWithCount) {
  const auto dir = freshDir();
  const Scene s = loadScene(writeText(dir / "d.obj",
                                      "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 2 0 0\n"
                                      "f 1 2 3\n"
                                      "f 1 2 4\n"     // collinear
                                      "f 1 1 3\n"));  // repeated vertex
  EXPECT_EQ(s.triangles.size(), 1u);
  EXPECT_TRUE(anyWarningContains(s, "dropped 2 zero-area triangles"));
}

TEST(LoadObj, NanCoordinateIsInputError) {
  const auto dir = freshDir();
  const std::string msg = loadError(writeText(dir / "nan.obj", "v 0 0 0\nv nan 0 0\nv 0 1 0\nf 1 2 3\n"));
  EXPECT_NE(msg.find("nan.obj"), std::string::npos) << msg;
  EXPECT_NE(msg.find("line 2"), std::string::npos) << msg;
  EXPECT_NE(msg.find("not finite"), std::string::npos) << msg;
}

TEST(LoadObj, InfCoordinateIsInputError) {
  const auto dir = freshDir();
  const std::string msg = loadError(writeText(dir / "inf.obj", "v 0 0 0\nv 1 0 0\nv 0 1e999 0\nf 1 2 3\n"));
  EXPECT_NE(msg.find("line 3"), std::string::npos) << msg;
}

TEST(LoadObj, OutOfRangeIndexIsInputError) {
  const auto dir = freshDir();
  const std::string msg = loadError(writeText(dir / "oob.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 99\n"));
  EXPECT_NE(msg.find("line 4"), std::string::npos) << msg;
  EXPECT_NE(msg.find("99 out of range (3 vertices)"), std::string::npos) << msg;
}

TEST(LoadObj, OutOfRangeIndexInQuadIsInputError) {
  // tinyobjloader would silently skip this quad; the pre-scan must not.
  const auto dir = freshDir();
  const std::string msg = loadError(writeText(dir / "oobq.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3 7\n"));
  EXPECT_NE(msg.find("out of range"), std::string::npos) << msg;
}

TEST(LoadObj, RelativeIndexBeforeFirstVertexIsInputError) {
  const auto dir = freshDir();
  const std::string msg = loadError(writeText(dir / "rel.obj", "v 0 0 0\nf -1 -2 -3\nv 1 0 0\nv 0 1 0\n"));
  EXPECT_NE(msg.find("line 2"), std::string::npos) << msg;
}

TEST(LoadObj, ZeroIndexIsInputError) {
  const auto dir = freshDir();
  const std::string msg = loadError(writeText(dir / "zero.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 0 1 2\n"));
  EXPECT_NE(msg.find("index 0"), std::string::npos) << msg;
}

TEST(LoadObj, NoTrianglesIsInputError) {
  const auto dir = freshDir();
  const std::string msg = loadError(writeText(dir / "empty.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\n"));
  EXPECT_NE(msg.find("no triangles"), std::string::npos) << msg;
}

TEST(LoadObj, OnlyDegenerateTrianglesIsInputError) {
  const auto dir = freshDir();
  const std::string msg = loadError(writeText(dir / "flat.obj", "v 0 0 0\nv 1 0 0\nv 2 0 0\nf 1 2 3\n"));
  EXPECT_NE(msg.find("no triangles"), std::string::npos) << msg;
}

TEST(LoadObj, TruncatedVertexIsInputError) {
  const auto dir = freshDir();
  const std::string msg = loadError(writeText(dir / "short.obj", "v 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n"));
  EXPECT_NE(msg.find("line 1"), std::string::npos) << msg;
}

}  // namespace
}  // namespace tetraprobe
