// Image comparison for visual regression: per-pixel differences of two 8-bit images, with the statistics CI
// needs to decide "same picture" and a diff image a person can look at.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace tetraprobe::cli {

struct Rgb8Image {
  int width = 0, height = 0;
  std::vector<uint8_t> rgb;  // row 0 = top
};

// Reads a PNG (any bit depth/channels, converted to 8-bit RGB). Throws InputError naming the file.
Rgb8Image readImage8(const std::string& path);

struct ImageDiff {
  double meanAbs = 0.0;       // mean over pixels and channels of |a - b|, in 0..255 units
  int maxAbs = 0;             // largest channel difference
  double fractionOver = 0.0;  // fraction of pixels whose largest channel difference exceeds `tolerance`
  Rgb8Image visual;           // |a - b| x 8 per channel over a dimmed copy of `a`, for people
};

// Throws InputError when the sizes differ.
ImageDiff compareImages(const Rgb8Image& a, const Rgb8Image& b, int tolerance);

// Writes an 8-bit RGB PNG atomically; throws on failure.
void writeImage8(const std::string& path, const Rgb8Image& image);

}  // namespace tetraprobe::cli
