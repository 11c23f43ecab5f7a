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

// The side and stride of the windows ImageDiff::worstWindowFraction looks at (pixels).
inline constexpr int kDiffWindow = 16;
inline constexpr int kDiffWindowStride = 8;

struct ImageDiff {
  double meanAbs = 0.0;          // mean over pixels and channels of |a - b|, in 0..255 units
  int maxAbs = 0;                // largest channel difference
  double fractionOver = 0.0;     // fraction of pixels whose largest channel difference exceeds `tolerance`
  double fractionChanged = 0.0;  // fraction of pixels that differ at all (some channel by 1 or more)
  // The largest fraction of pixels over `tolerance` in any kDiffWindow x kDiffWindow window (windows every
  // kDiffWindowStride pixels, so any blob up to 8 pixels across lies whole in one; clipped at the image
  // border, fractions of the clipped window). Large for a blob (a wrong probe, tet, patch), at most about
  // 1/16 for a one-pixel line (a silhouette rasterized differently).
  double worstWindowFraction = 0.0;
  Rgb8Image visual;  // |a - b| x 8 per channel over a dimmed copy of `a`, for people
};

// The thresholds the visual regression tests use (docs/evaluation.md#visual-regression justifies them).
struct DiffThresholds {
  int tolerance = 2;           // a pixel "differs" when some channel differs by more than this (0..255)
  double maxFraction = 0.001;  // at most this fraction of pixels may differ (edges)
  double maxWindow = 0.125;    // ... and at most this fraction of any window (no blob)
  double maxChanged = 0.005;   // at most this fraction may change at all (no shift below the tolerance)
};

// Throws InputError when the sizes differ.
ImageDiff compareImages(const Rgb8Image& a, const Rgb8Image& b, int tolerance);

// True when `d` (computed with t.tolerance) is within every threshold of `t`.
bool imagesMatch(const ImageDiff& d, const DiffThresholds& t);

// Writes an 8-bit RGB PNG atomically; throws on failure.
void writeImage8(const std::string& path, const Rgb8Image& image);

}  // namespace tetraprobe::cli
