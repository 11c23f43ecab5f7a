// Error image: signed log2 luminance ratio of lookup to reference per pixel, its statistics, and a
// diverging heat map with a fixed scale.
// References: Brewer, Harrower et al., ColorBrewer 2.0 (the RdBu diverging scheme); Moreland 2009
// ("Diverging color maps for scientific visualization") on why a diverging map with a neutral centre.
#include "tetraprobe/eval/error_image.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include "tetraprobe/runtime/luminance.h"

namespace tetraprobe {

namespace {

// Rec. 709 luminance, non-finite as 0 and negative clamped to 0.
float clampedLuminance(const glm::vec3& c) {
  const float y = luminance(c);
  return std::isfinite(y) ? std::max(y, 0.0f) : 0.0f;
}

// ColorBrewer RdBu, 11 classes, from the blue end (e = -2) to the red end (e = +2); sRGB bytes.
constexpr unsigned char kRdBu[11][3] = {{0x05, 0x30, 0x61}, {0x21, 0x66, 0xac}, {0x43, 0x93, 0xc3},
                                        {0x92, 0xc5, 0xde}, {0xd1, 0xe5, 0xf0}, {0xf7, 0xf7, 0xf7},
                                        {0xfd, 0xdb, 0xc7}, {0xf4, 0xa5, 0x82}, {0xd6, 0x60, 0x4d},
                                        {0xb2, 0x18, 0x2b}, {0x67, 0x00, 0x1f}};
static_assert(sizeof(kRdBu) / sizeof(kRdBu[0]) % 2 == 1, "the neutral class must sit in the middle");

float srgbDecode(float v) {
  return v <= 0.04045f ? v / 12.92f : std::pow((v + 0.055f) / 1.055f, 2.4f);
}

}  // namespace

float signedLog2Error(const glm::vec3& lookup, const glm::vec3& reference) {
  const double x = std::max(double(clampedLuminance(lookup)), kErrorFloor);
  const double r = std::max(double(clampedLuminance(reference)), kErrorFloor);
  return float(std::log2(x / r));
}

ErrorImage computeErrorImage(const ReferenceGBuffer& gbuffer, const std::vector<glm::vec3>& lookup,
                             const std::vector<glm::vec3>& reference) {
  const size_t n = gbuffer.hit.size();
  if (lookup.size() != n || reference.size() != n)
    throw std::invalid_argument("error image: " + std::to_string(lookup.size()) + " lookups and " +
                                std::to_string(reference.size()) + " references for " + std::to_string(n) +
                                " pixels");
  ErrorImage out;
  out.width = gbuffer.width;
  out.height = gbuffer.height;
  out.hit = gbuffer.hit;
  out.log2Ratio.assign(n, 0.0f);
  ErrorStats& s = out.stats;
  double sum = 0.0, sumAbs = 0.0;
  size_t gross = 0, dark = 0, bright = 0, tooDark = 0;
  for (size_t i = 0; i < n; ++i) {
    if (!gbuffer.hit[i]) continue;
    const float e = signedLog2Error(lookup[i], reference[i]);
    out.log2Ratio[i] = e;
    ++s.pixels;
    sum += e;
    sumAbs += std::abs(e);
    gross += std::abs(e) > kGrossStops;
    bright += e > kGrossStops;
    tooDark += e < -kGrossStops;
    dark += e < kDarkHoleStops;
  }
  if (s.pixels) {
    const double total = double(s.pixels);
    s.gross = double(gross) / total;
    s.darkHoles = double(dark) / total;
    s.tooBright = double(bright) / total;
    s.tooDark = double(tooDark) / total;
    s.meanLog2 = sum / total;
    s.meanAbsLog2 = sumAbs / total;
  }
  return out;
}

glm::vec3 errorColor(float log2Ratio) {
  constexpr int kLast = int(sizeof(kRdBu) / sizeof(kRdBu[0])) - 1;
  const double e =
      std::isnan(log2Ratio) ? 0.0 : std::clamp(double(log2Ratio), -kErrorScaleStops, kErrorScaleStops);
  const double t = (e + kErrorScaleStops) / (2.0 * kErrorScaleStops) * kLast;  // 0 .. kLast
  const int k = std::min(int(t), kLast - 1);
  const double f = t - k;
  glm::vec3 rgb;
  for (int c = 0; c < 3; ++c) {
    const double v = ((1.0 - f) * kRdBu[k][c] + f * kRdBu[k + 1][c]) / 255.0;  // interpolated in sRGB
    rgb[c] = srgbDecode(float(v));
  }
  return rgb;
}

Image errorHeatMap(const ErrorImage& error) {
  Image img;
  img.width = error.width;
  img.height = error.height;
  img.rgba.assign(error.hit.size() * 4, 0.0f);
  for (size_t i = 0; i < error.hit.size(); ++i) {
    if (!error.hit[i]) continue;
    const glm::vec3 c = errorColor(error.log2Ratio[i]);
    img.rgba[4 * i + 0] = c.r;
    img.rgba[4 * i + 1] = c.g;
    img.rgba[4 * i + 2] = c.b;
    img.rgba[4 * i + 3] = 1.0f;
  }
  return img;
}

Image errorValues(const ErrorImage& error) {
  Image img;
  img.width = error.width;
  img.height = error.height;
  img.rgba.assign(error.hit.size() * 4, 0.0f);
  for (size_t i = 0; i < error.hit.size(); ++i) {
    if (!error.hit[i]) continue;
    for (int c = 0; c < 3; ++c) img.rgba[4 * i + c] = error.log2Ratio[i];
    img.rgba[4 * i + 3] = 1.0f;
  }
  return img;
}

}  // namespace tetraprobe
