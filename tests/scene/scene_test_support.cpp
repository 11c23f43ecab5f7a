// Test helpers for the scene module; also the one stb_image_write implementation in the test binary.
#include "scene_test_support.h"

#include <fstream>

#if defined(__GNUC__)
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wmissing-field-initializers"
#pragma GCC diagnostic ignored "-Wunused-function"
#endif
#define STB_IMAGE_WRITE_STATIC
#define STB_IMAGE_WRITE_IMPLEMENTATION
#include <stb/stb_image_write.h>
#if defined(__GNUC__)
#pragma GCC diagnostic pop
#endif

#include "tetraprobe/common/error.h"
#include "tetraprobe/scene/load.h"

namespace tetraprobe::test {

namespace {

std::filesystem::path dirOf(const ::testing::TestInfo& info) {
  return std::filesystem::temp_directory_path() /
         (std::string("tetraprobe_scene_") + info.test_suite_name() + "_" + info.name());
}

// Removes a passed test's directory when the test ends; a failed test's stays for a look at its files.
class RemoveDirOnPass : public ::testing::EmptyTestEventListener {
  void OnTestEnd(const ::testing::TestInfo& info) override {
    if (!info.result()->Failed()) {
      std::error_code ignored;
      std::filesystem::remove_all(dirOf(info), ignored);
    }
  }
};

}  // namespace

std::filesystem::path freshDir() {
  static const bool listening = [] {
    ::testing::UnitTest::GetInstance()->listeners().Append(new RemoveDirOnPass);  // gtest owns it
    return true;
  }();
  (void)listening;
  const auto dir = dirOf(*::testing::UnitTest::GetInstance()->current_test_info());
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  return dir;
}

std::string writeText(const std::filesystem::path& file, const std::string& text) {
  std::filesystem::create_directories(file.parent_path());
  std::ofstream out(file, std::ios::binary);
  out << text;
  return file.string();
}

std::string writePng(const std::filesystem::path& file, int w, int h, const std::vector<uint8_t>& rgb) {
  std::filesystem::create_directories(file.parent_path());
  EXPECT_EQ(rgb.size(), static_cast<size_t>(w * h * 3));
  EXPECT_NE(stbi_write_png(file.string().c_str(), w, h, 3, rgb.data(), w * 3), 0) << file;
  return file.string();
}

std::string writePngChannels(const std::filesystem::path& file, int w, int h, int channels,
                             const std::vector<uint8_t>& texels) {
  std::filesystem::create_directories(file.parent_path());
  EXPECT_EQ(texels.size(), static_cast<size_t>(w * h * channels));
  EXPECT_NE(stbi_write_png(file.string().c_str(), w, h, channels, texels.data(), w * channels), 0) << file;
  return file.string();
}

std::string base64(const std::vector<uint8_t>& bytes) {
  static const char* alphabet = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string out;
  size_t i = 0;
  for (; i + 2 < bytes.size(); i += 3) {
    const uint32_t v = (uint32_t(bytes[i]) << 16) | (uint32_t(bytes[i + 1]) << 8) | bytes[i + 2];
    for (int k = 3; k >= 0; --k) out += alphabet[(v >> (6 * k)) & 63];
  }
  if (i + 1 == bytes.size()) {
    const uint32_t v = uint32_t(bytes[i]) << 16;
    out += alphabet[(v >> 18) & 63];
    out += alphabet[(v >> 12) & 63];
    out += "==";
  } else if (i + 2 == bytes.size()) {
    const uint32_t v = (uint32_t(bytes[i]) << 16) | (uint32_t(bytes[i + 1]) << 8);
    out += alphabet[(v >> 18) & 63];
    out += alphabet[(v >> 12) & 63];
    out += alphabet[(v >> 6) & 63];
    out += '=';
  }
  return out;
}

std::string writeGlb(const std::filesystem::path& file, const std::string& json,
                     const std::vector<uint8_t>& bin) {
  std::string j = json;
  while (j.size() % 4 != 0) j += ' ';
  std::vector<uint8_t> b = bin;
  while (b.size() % 4 != 0) b.push_back(0);
  std::vector<uint8_t> out;
  auto u32 = [&out](uint32_t v) { appendBytes(out, std::vector<uint32_t>{v}); };
  u32(0x46546C67u);  // "glTF"
  u32(2);
  u32(static_cast<uint32_t>(12 + 8 + j.size() + 8 + b.size()));
  u32(static_cast<uint32_t>(j.size()));
  u32(0x4E4F534Au);  // "JSON"
  out.insert(out.end(), j.begin(), j.end());
  u32(static_cast<uint32_t>(b.size()));
  u32(0x004E4942u);  // "BIN\0"
  out.insert(out.end(), b.begin(), b.end());
  return writeText(file, std::string(out.begin(), out.end()));
}

std::string loadError(const std::string& path) {
  try {
    loadScene(path);
  } catch (const InputError& e) {
    return e.what();
  } catch (const std::exception& e) {
    ADD_FAILURE() << "expected InputError, got another exception: " << e.what();
    return e.what();
  }
  ADD_FAILURE() << "expected InputError loading " << path;
  return "";
}

bool anyWarningContains(const Scene& scene, const std::string& text) {
  for (const auto& w : scene.warnings) {
    if (w.find(text) != std::string::npos) return true;
  }
  return false;
}

}  // namespace tetraprobe::test
