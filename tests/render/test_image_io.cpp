// Image output: PNG tone mapping and orientation read back with stb_image; EXR floats read back with tinyexr.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <string>

#include <unistd.h>

#include "tetraprobe/render/render.h"

#define STB_IMAGE_IMPLEMENTATION
#define STB_IMAGE_STATIC
#include <stb/stb_image.h>

#include <tinyexr.h>

namespace tetraprobe {
namespace {

std::string tempPath(const std::string& name) {
  const auto dir =
      std::filesystem::temp_directory_path() / ("tetraprobe_test_render_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  return (dir / name).string();
}

// A 5x3 image whose every pixel and channel differs (row 0 = top), values spanning 0 .. ~20, one negative.
Image makeImage() {
  Image im;
  im.width = 5;
  im.height = 3;
  for (int y = 0; y < im.height; ++y)
    for (int x = 0; x < im.width; ++x) {
      im.rgba.push_back(0.05f * float(x + 1) * float(y * y + 1));
      im.rgba.push_back(float(x) * 1.5f + float(y) * 0.25f);
      im.rgba.push_back(x == 0 && y == 0 ? -0.5f : 0.01f * float(x * 7 + y * 3));
      im.rgba.push_back(float((x + y) % 2));
    }
  return im;
}

// The documented curve: v = max(x * exposure, 0), Reinhard v / (1 + v), sRGB encode, round to 8 bits.
int expectedByte(float x, float exposure) {
  const double v = std::max(double(x) * exposure, 0.0);
  const double t = v / (1.0 + v);
  const double s = t <= 0.0031308 ? 12.92 * t : 1.055 * std::pow(t, 1.0 / 2.4) - 0.055;
  return int(std::lround(s * 255.0));
}

// Writing then decoding gives the documented tone curve at every pixel, in the same orientation.
TEST(ImageIo, PngRoundTrip) {
  const Image im = makeImage();
  const std::string path = tempPath("round_trip.png");
  const float exposure = 0.7f;
  std::string error;
  ASSERT_TRUE(writePng(path, im, exposure, &error)) << error;
  int w = 0, h = 0, comp = 0;
  unsigned char* data = stbi_load(path.c_str(), &w, &h, &comp, 3);
  ASSERT_NE(data, nullptr) << stbi_failure_reason();
  ASSERT_EQ(w, im.width);
  ASSERT_EQ(h, im.height);
  EXPECT_EQ(comp, 3);
  for (int i = 0; i < w * h; ++i)
    for (int c = 0; c < 3; ++c)
      EXPECT_NEAR(int(data[3 * i + c]), expectedByte(im.rgba[4 * i + c], exposure), 1)
          << "pixel " << i % w << "," << i / w << " channel " << c;
  EXPECT_EQ(data[2], 0) << "negative values clamp to black";
  stbi_image_free(data);
  std::filesystem::remove_all(std::filesystem::path(path).parent_path());
}

// EXR keeps the linear 32-bit floats bit for bit (ZIP is lossless), alpha included, row 0 = top.
TEST(ImageIo, ExrWritesLinearFloats) {
  const Image im = makeImage();
  const std::string path = tempPath("linear.exr");
  std::string error;
  ASSERT_TRUE(writeExr(path, im, &error)) << error;
  float* rgba = nullptr;
  int w = 0, h = 0;
  const char* err = nullptr;
  ASSERT_EQ(LoadEXR(&rgba, &w, &h, path.c_str(), &err), TINYEXR_SUCCESS) << (err ? err : "");
  ASSERT_EQ(w, im.width);
  ASSERT_EQ(h, im.height);
  for (size_t i = 0; i < im.rgba.size(); ++i) EXPECT_EQ(rgba[i], im.rgba[i]) << "float " << i;
  std::free(rgba);
  std::filesystem::remove_all(std::filesystem::path(path).parent_path());
}

// Bad input is reported, not written.
TEST(ImageIo, RejectsMismatchedImage) {
  Image im = makeImage();
  im.rgba.pop_back();
  std::string error;
  EXPECT_FALSE(writePng(tempPath("bad.png"), im, 1.0f, &error));
  EXPECT_FALSE(error.empty());
  error.clear();
  EXPECT_FALSE(writeExr(tempPath("bad.exr"), im, &error));
  EXPECT_FALSE(error.empty());
  EXPECT_FALSE(std::filesystem::exists(tempPath("bad.png")));
  std::filesystem::remove_all(std::filesystem::path(tempPath("x")).parent_path());
}

// The 95th-percentile geometry luminance maps to 0.8; background pixels (a = 0) are ignored.
TEST(ImageIo, AutoExposureMapsHighPercentile) {
  Image im;
  im.width = 100;
  im.height = 2;
  for (int i = 0; i < 200; ++i) {
    const bool geometry = i < 100;
    const float v = geometry ? float(i + 1) : 1000.0f;  // luminance 1..100 on geometry
    im.rgba.insert(im.rgba.end(), {v, v, v, geometry ? 1.0f : 0.0f});
  }
  EXPECT_NEAR(autoExposure(im), 0.8f / 96.0f, 1e-6f);
  Image empty;
  EXPECT_EQ(autoExposure(empty), 1.0f);
}

}  // namespace
}  // namespace tetraprobe
