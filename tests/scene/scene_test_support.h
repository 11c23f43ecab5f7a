// Helpers for the scene tests: a fresh temp directory per test, file writers (text, PNG, base64 for glTF data
// URIs, GLB container) and an expectation that loadScene throws InputError mentioning given text.
#pragma once

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "tetraprobe/scene/scene.h"

namespace tetraprobe::test {

// Empty directory unique to the running test (removed and recreated); removed again when the test passes.
std::filesystem::path freshDir();

std::string writeText(const std::filesystem::path& file, const std::string& text);

// Writes an 8-bit RGB PNG of w x h texels from `rgb` (3 bytes per texel).
std::string writePng(const std::filesystem::path& file, int w, int h, const std::vector<uint8_t>& rgb);

// Writes an 8-bit PNG of w x h texels with `channels` (1 grey, 2 grey+alpha, 3 RGB, 4 RGBA) bytes per texel.
std::string writePngChannels(const std::filesystem::path& file, int w, int h, int channels,
                             const std::vector<uint8_t>& texels);

std::string base64(const std::vector<uint8_t>& bytes);

// A .glb container: JSON chunk (space-padded) + BIN chunk (zero-padded).
std::string writeGlb(const std::filesystem::path& file, const std::string& json,
                     const std::vector<uint8_t>& bin);

// Appends the little-endian bytes of `values` to `out`.
template <typename T>
void appendBytes(std::vector<uint8_t>& out, const std::vector<T>& values) {
  const auto* p = reinterpret_cast<const uint8_t*>(values.data());
  out.insert(out.end(), p, p + values.size() * sizeof(T));
}

// The message of the InputError that loadScene(path) throws, or "" (with a test failure) if it does not.
std::string loadError(const std::string& path);

bool anyWarningContains(const Scene& scene, const std::string& text);

}  // namespace tetraprobe::test
