// PNG reading (stb_image, a private static copy) and per-pixel image comparison.
#include "image_compare.h"

#include <algorithm>
#include <cstdlib>
#include <stdexcept>

#define STB_IMAGE_STATIC
#define STB_IMAGE_IMPLEMENTATION
#define STBI_ONLY_PNG
#include <stb/stb_image.h>
#define STB_IMAGE_WRITE_STATIC
#define STB_IMAGE_WRITE_IMPLEMENTATION
#include <stb/stb_image_write.h>

#include "tetraprobe/common/error.h"
#include "tetraprobe/runtime/file_io.h"

namespace tetraprobe::cli {

Rgb8Image readImage8(const std::string& path) {
  std::vector<char> bytes;
  std::string error;
  if (!readFile(path, bytes, &error)) throw InputError(error);
  int w = 0, h = 0, n = 0;
  stbi_uc* data =
      stbi_load_from_memory(reinterpret_cast<const stbi_uc*>(bytes.data()), int(bytes.size()), &w, &h, &n, 3);
  if (!data) throw InputError(path + ": not a readable PNG (" + stbi_failure_reason() + ")");
  Rgb8Image img;
  img.width = w;
  img.height = h;
  img.rgb.assign(data, data + size_t(w) * size_t(h) * 3);
  stbi_image_free(data);
  return img;
}

ImageDiff compareImages(const Rgb8Image& a, const Rgb8Image& b, int tolerance) {
  if (a.width != b.width || a.height != b.height)
    throw InputError("image sizes differ: " + std::to_string(a.width) + "x" + std::to_string(a.height) +
                     " vs " + std::to_string(b.width) + "x" + std::to_string(b.height));
  ImageDiff d;
  d.visual = a;
  const size_t w = size_t(a.width), h = size_t(a.height), pixels = w * h;
  uint64_t sum = 0, over = 0, changed = 0;
  // integral[(y) * (w + 1) + x]: pixels over the tolerance in rows < y, columns < x.
  std::vector<uint32_t> integral((w + 1) * (h + 1), 0);
  for (size_t y = 0; y < h; ++y) {
    uint32_t row = 0;
    for (size_t x = 0; x < w; ++x) {
      const size_t p = y * w + x;
      int worst = 0;
      for (int c = 0; c < 3; ++c) {
        const int diff = std::abs(int(a.rgb[3 * p + c]) - int(b.rgb[3 * p + c]));
        sum += uint64_t(diff);
        worst = std::max(worst, diff);
        d.visual.rgb[3 * p + c] = uint8_t(std::min(255, a.rgb[3 * p + c] / 4 + diff * 8));
      }
      d.maxAbs = std::max(d.maxAbs, worst);
      over += worst > tolerance;
      changed += worst > 0;
      row += worst > tolerance;
      integral[(y + 1) * (w + 1) + x + 1] = integral[y * (w + 1) + x + 1] + row;
    }
  }
  const auto count = [&](size_t x0, size_t y0, size_t x1, size_t y1) {  // [x0, x1) x [y0, y1)
    return integral[y1 * (w + 1) + x1] - integral[y0 * (w + 1) + x1] - integral[y1 * (w + 1) + x0] +
           integral[y0 * (w + 1) + x0];
  };
  for (size_t y = 0; y < h; y += kDiffWindowStride)
    for (size_t x = 0; x < w; x += kDiffWindowStride) {
      const size_t x1 = std::min(w, x + kDiffWindow), y1 = std::min(h, y + kDiffWindow);
      d.worstWindowFraction =
          std::max(d.worstWindowFraction, double(count(x, y, x1, y1)) / double((x1 - x) * (y1 - y)));
    }
  d.meanAbs = pixels ? double(sum) / double(3 * pixels) : 0.0;
  d.fractionOver = pixels ? double(over) / double(pixels) : 0.0;
  d.fractionChanged = pixels ? double(changed) / double(pixels) : 0.0;
  return d;
}

bool imagesMatch(const ImageDiff& d, const DiffThresholds& t) {
  return d.fractionOver <= t.maxFraction && d.worstWindowFraction <= t.maxWindow &&
         d.fractionChanged <= t.maxChanged;
}

namespace {
void append(void* ctx, void* data, int size) {
  static_cast<std::string*>(ctx)->append(static_cast<const char*>(data), size_t(size));
}
}  // namespace

void writeImage8(const std::string& path, const Rgb8Image& image) {
  std::string bytes;
  if (!stbi_write_png_to_func(append, &bytes, image.width, image.height, 3, image.rgb.data(),
                              image.width * 3))
    throw std::runtime_error(path + ": PNG encoding failed");
  std::string error;
  if (!writeFileAtomic(path, bytes, &error)) throw std::runtime_error(error);
}

}  // namespace tetraprobe::cli
