// Image output for the renderer: tone-mapped sRGB PNG (stb_image_write), linear float EXR (tinyexr), and a
// percentile auto-exposure. Files are written atomically through tetraprobe::writeFileAtomic.
#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <string>
#include <string_view>
#include <vector>

#include "tetraprobe/render/render.h"
#include "tetraprobe/runtime/file_io.h"
#include "tetraprobe/runtime/luminance.h"

#define STB_IMAGE_WRITE_IMPLEMENTATION
#define STB_IMAGE_WRITE_STATIC
#include <stb/stb_image_write.h>

// Debian's libtinyexr-dev ships the implementation (with zlib) in libtinyexr.so: include the header only.
#include <tinyexr.h>

namespace tetraprobe {
namespace {

bool checkImage(const Image& image, std::string* error) {
  if (image.width <= 0 || image.height <= 0 ||
      image.rgba.size() != size_t(image.width) * size_t(image.height) * 4) {
    if (error)
      *error = "image is empty or its pixel array (" + std::to_string(image.rgba.size()) +
               " floats) does not match " + std::to_string(image.width) + "x" + std::to_string(image.height) +
               " RGBA";
    return false;
  }
  return true;
}

// Linear [0,1] -> sRGB-encoded [0,1].
float srgbEncode(float x) {
  return x <= 0.0031308f ? 12.92f * x : 1.055f * std::pow(x, 1.0f / 2.4f) - 0.055f;
}

void appendToString(void* context, void* data, int size) {
  static_cast<std::string*>(context)->append(static_cast<const char*>(data), size_t(size));
}

// 8-bit sRGB RGB PNG of `image` (already checked): per channel toLinear01(x), clamped to [0, 1], sRGB-encoded.
template <typename ToLinear01>
bool encodePng(const std::string& path, const Image& image, std::string* error, ToLinear01 toLinear01) {
  const size_t n = size_t(image.width) * size_t(image.height);
  std::vector<unsigned char> rgb(n * 3);
  for (size_t i = 0; i < n; ++i)
    for (int c = 0; c < 3; ++c) {
      const float mapped = srgbEncode(std::clamp(toLinear01(image.rgba[4 * i + c]), 0.0f, 1.0f));
      rgb[3 * i + c] = static_cast<unsigned char>(std::lround(std::clamp(mapped, 0.0f, 1.0f) * 255.0f));
    }
  std::string bytes;
  if (!stbi_write_png_to_func(appendToString, &bytes, image.width, image.height, 3, rgb.data(),
                              image.width * 3)) {
    if (error) *error = path + ": PNG encoding failed";
    return false;
  }
  return writeFileAtomic(path, bytes, error);
}

}  // namespace

float autoExposure(const Image& image) {
  std::vector<float> lum;
  const size_t n = image.rgba.size() / 4;
  for (size_t i = 0; i < n; ++i) {
    const float* p = &image.rgba[4 * i];
    if (!(p[3] > 0.0f)) continue;
    const float y = luminance(glm::vec3(p[0], p[1], p[2]));
    if (std::isfinite(y)) lum.push_back(y);
  }
  if (lum.empty()) return 1.0f;
  const size_t k = std::min(lum.size() - 1, size_t(0.95 * double(lum.size())));
  std::nth_element(lum.begin(), lum.begin() + std::ptrdiff_t(k), lum.end());
  const float p95 = lum[k];
  return p95 > 0.0f ? 0.8f / p95 : 1.0f;
}

bool writePng(const std::string& path, const Image& image, float exposure, std::string* error) {
  if (!checkImage(image, error)) return false;
  if (!std::isfinite(exposure) || exposure < 0.0f) {
    if (error) *error = path + ": exposure must be finite and >= 0";
    return false;
  }
  return encodePng(path, image, error, [exposure](float x) {
    float v = x * exposure;
    v = std::isfinite(v) ? std::max(v, 0.0f) : (v > 0.0f ? 1e30f : 0.0f);
    return v / (1.0f + v);
  });
}

bool writePngLinear(const std::string& path, const Image& image, std::string* error) {
  if (!checkImage(image, error)) return false;
  return encodePng(path, image, error, [](float x) { return std::isnan(x) ? 0.0f : x; });
}

bool writeExr(const std::string& path, const Image& image, std::string* error) {
  if (!checkImage(image, error)) return false;
  const size_t n = size_t(image.width) * size_t(image.height);
  // tinyexr wants planar channels; readers expect them sorted by name: A, B, G, R.
  std::vector<float> planes[4];
  for (auto& p : planes) p.resize(n);
  for (size_t i = 0; i < n; ++i) {
    planes[0][i] = image.rgba[4 * i + 3];
    planes[1][i] = image.rgba[4 * i + 2];
    planes[2][i] = image.rgba[4 * i + 1];
    planes[3][i] = image.rgba[4 * i + 0];
  }
  float* ptrs[4] = {planes[0].data(), planes[1].data(), planes[2].data(), planes[3].data()};

  EXRHeader header;
  InitEXRHeader(&header);
  EXRImage exr;
  InitEXRImage(&exr);
  exr.num_channels = 4;
  exr.images = reinterpret_cast<unsigned char**>(ptrs);
  exr.width = image.width;
  exr.height = image.height;
  EXRChannelInfo channels[4] = {};
  const char* names[4] = {"A", "B", "G", "R"};
  int pixelTypes[4], requestedTypes[4];
  for (int c = 0; c < 4; ++c) {
    channels[c].name[0] = names[c][0];
    channels[c].name[1] = '\0';
    pixelTypes[c] = TINYEXR_PIXELTYPE_FLOAT;
    requestedTypes[c] = TINYEXR_PIXELTYPE_FLOAT;
  }
  header.num_channels = 4;
  header.channels = channels;
  header.pixel_types = pixelTypes;
  header.requested_pixel_types = requestedTypes;
  header.compression_type = TINYEXR_COMPRESSIONTYPE_ZIP;

  unsigned char* memory = nullptr;
  const char* err = nullptr;
  const size_t size = SaveEXRImageToMemory(&exr, &header, &memory, &err);
  if (size == 0) {
    if (error) *error = path + ": EXR encoding failed: " + (err ? err : "unknown error");
    if (err) FreeEXRErrorMessage(err);
    std::free(memory);
    return false;
  }
  const bool ok = writeFileAtomic(path, std::string_view(reinterpret_cast<const char*>(memory), size), error);
  std::free(memory);
  return ok;
}

}  // namespace tetraprobe
