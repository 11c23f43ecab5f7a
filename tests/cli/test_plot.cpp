// The eval chart's two back ends: the bitmap font is complete, the raster canvas draws where the SVG says
// (markers cross-checked against the SVG document's own coordinates), dashes and quarter-turned text come out
// as drawn, and colour strings outside the chart's vocabulary are refused rather than drawn black.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <set>
#include <stdexcept>
#include <string>
#include <vector>

#include "bitmap_font.h"
#include "eval_plot.h"
#include "plot_canvas.h"

namespace tetraprobe::cli {
namespace {

std::vector<uint8_t> glyph(char c) {
  const uint8_t* r = glyphRows(c);
  return std::vector<uint8_t>(r, r + kGlyphH);
}

uint64_t packed(const std::vector<uint8_t>& rows) {
  uint64_t key = 0;
  for (uint8_t row : rows) key = (key << kGlyphW) | row;
  return key;
}

// Every printable character has its own glyph (no two alike, so no character silently reuses another's
// shape), all but the space have ink, no row has bits beyond the 5 columns, and anything else draws as '?'.
TEST(BitmapFont, EveryPrintableCharacterHasItsOwnInkedGlyph) {
  std::set<uint64_t> seen;  // 9 rows x 5 bits
  for (int c = 32; c <= 126; ++c) {
    const std::vector<uint8_t> g = glyph(char(c));
    int ink = 0;
    for (uint8_t row : g) {
      EXPECT_EQ(row >> kGlyphW, 0) << "character " << c;
      ink += __builtin_popcount(row);
    }
    if (c == ' ')
      EXPECT_EQ(ink, 0);
    else
      EXPECT_GT(ink, 0) << "character '" << char(c) << "' has no ink";
    EXPECT_TRUE(seen.insert(packed(g)).second) << "character '" << char(c) << "' repeats another glyph";
  }
  EXPECT_EQ(glyph('\n'), glyph('?'));
  EXPECT_EQ(glyph(char(200)), glyph('?'));
  // Descenders only where a letter has one.
  for (char c : std::string("gjpqy")) EXPECT_NE(glyph(c)[kGlyphBaseline], 0) << c;
  for (char c : std::string("ABCabcxz019")) EXPECT_EQ(glyph(c)[kGlyphBaseline], 0) << c;
}

TEST(PlotCanvas, ColourStringsAreTheChartsOrRefused) {
  uint8_t rgb[3];
  ASSERT_TRUE(parsePlotColor("#1b9e77", rgb));
  EXPECT_EQ(rgb[0], 0x1b);
  EXPECT_EQ(rgb[1], 0x9e);
  EXPECT_EQ(rgb[2], 0x77);
  ASSERT_TRUE(parsePlotColor("#4a8", rgb));
  EXPECT_EQ(rgb[0], 0x44);
  EXPECT_EQ(rgb[1], 0xaa);
  EXPECT_EQ(rgb[2], 0x88);
  ASSERT_TRUE(parsePlotColor("white", rgb));
  EXPECT_EQ(rgb[2], 255);
  EXPECT_FALSE(parsePlotColor("none", rgb));
  for (const char* bad : {"", "red", "#12345", "#12345g", "1b9e77", "#1b9e7700"})
    EXPECT_THROW(parsePlotColor(bad, rgb), std::invalid_argument) << bad;
}

const uint8_t* pixel(const Rgb8Image& im, double x, double y) {
  const int i = std::clamp(int(x), 0, im.width - 1), j = std::clamp(int(y), 0, im.height - 1);
  return &im.rgb[(size_t(j) * size_t(im.width) + size_t(i)) * 3];
}

// Fraction of the pixels in [x0, x1) x [y0, y1) that are not white.
double ink(const Rgb8Image& im, int x0, int y0, int x1, int y1) {
  int n = 0, dark = 0;
  for (int y = y0; y < y1; ++y)
    for (int x = x0; x < x1; ++x, ++n) {
      const uint8_t* p = pixel(im, x, y);
      dark += (p[0] < 250 || p[1] < 250 || p[2] < 250);
    }
  return n ? double(dark) / n : 0.0;
}

std::vector<PlotPoint> samplePoints() {
  return {{"tet", "", 3.2e6, 12.0, 0.19, 0.01},
          {"nearest", "", 0.9e6, 2.0, 0.31, 0.12},
          {"grid (equal bytes)", "", 3.1e6, 9.0, 0.27, 0.05}};
}

// Each filled marker the SVG places (mean_rel circles of radius 4 and the legend's of radius 5) is drawn in
// its colour at the same place, scaled, in the raster: the two back ends draw the same chart.
TEST(EvalPlot, RasterMarkersSitWhereTheSvgPutsThem) {
  PlotOptions po;
  po.title = "closed-form check";
  const std::string svg = evalPlotSvg(samplePoints(), po);
  const double scale = 2.0;
  const Rgb8Image im = evalPlotImage(samplePoints(), po, scale);
  EXPECT_EQ(im.width, 1840);
  EXPECT_EQ(im.height, 744);
  // Every "<circle cx='X' cy='Y' r='R' fill='#rrggbb'" of radius 4 or 5 (filled markers), parsed by hand.
  int checked = 0;
  for (size_t at = svg.find("<circle "); at != std::string::npos; at = svg.find("<circle ", at + 1)) {
    double cx = 0.0, cy = 0.0, r = 0.0;
    char fill[8] = {};
    if (std::sscanf(svg.c_str() + at, "<circle cx='%lf' cy='%lf' r='%lf' fill='%7[#0-9a-f]'", &cx, &cy, &r,
                    fill) != 4 ||
        !(r == 4.0 || r == 5.0))
      continue;
    uint8_t want[3];
    ASSERT_TRUE(parsePlotColor(fill, want));
    const uint8_t* got = pixel(im, cx * scale, cy * scale);
    for (int c = 0; c < 3; ++c)
      EXPECT_NEAR(int(got[c]), int(want[c]), 2) << "marker " << fill << " at " << cx << "," << cy;
    ++checked;
  }
  // 3 methods x 2 panels (mean_rel circles) + 3 legend circles.
  EXPECT_EQ(checked, 9);
  // Text is drawn: the title's box has ink, the margin right of the legend has none.
  EXPECT_GT(ink(im, 920 - 100, 2 * 20 - 18, 920 + 100, 2 * 20), 0.05);
  EXPECT_EQ(ink(im, 1840 - 60, 744 - 40, 1840, 744), 0.0);
}

// A dash pattern of 2 on, 2 off inks about half the line's length; the solid line all of it.
TEST(RasterCanvas, DashesInkTheirShareOfTheLine) {
  for (const double on : {0.0, 2.0}) {
    RasterCanvas cv(100, 10, 4.0, 3);
    cv.polyline({10, 5, 90, 5}, "#000000", 1.0, on, on);
    const Rgb8Image im = cv.finish();
    int dark = 0;
    for (int x = 40; x < 360; ++x) dark += pixel(im, x, 20)[0] < 128;
    const double share = dark / 320.0;
    if (on == 0.0)
      EXPECT_EQ(share, 1.0);
    else
      EXPECT_NEAR(share, 0.5, 0.05);
  }
}

// A quarter-turned '-' is a vertical bar, an upright one a horizontal bar; a vertical label reads bottom to
// top, so its first character sits below its last.
TEST(RasterCanvas, VerticalTextIsTurnedCounterClockwise) {
  auto inkBox = [](const Rgb8Image& im, int box[4]) {
    box[0] = box[1] = 1 << 30;
    box[2] = box[3] = -1;
    for (int y = 0; y < im.height; ++y)
      for (int x = 0; x < im.width; ++x)
        if (pixel(im, x, y)[0] < 128) {
          box[0] = std::min(box[0], x);
          box[1] = std::min(box[1], y);
          box[2] = std::max(box[2], x);
          box[3] = std::max(box[3], y);
        }
  };
  int upright[4], turned[4];
  {
    RasterCanvas cv(100, 100, 1.0, 2);
    cv.text(50, 50, "-", TextAnchor::kMiddle, 20, "#000000", false);
    inkBox(cv.finish(), upright);
  }
  {
    RasterCanvas cv(100, 100, 1.0, 2);
    cv.text(50, 50, "-", TextAnchor::kMiddle, 20, "#000000", true);
    inkBox(cv.finish(), turned);
  }
  EXPECT_GT(upright[2] - upright[0], 3 * (upright[3] - upright[1]));
  EXPECT_GT(turned[3] - turned[1], 3 * (turned[2] - turned[0]));
  // "_." turned: the underscore (first) is the lower, the full stop (second) the higher ink.
  RasterCanvas cv(100, 100, 1.0, 2);
  cv.text(50, 50, "_.", TextAnchor::kMiddle, 20, "#000000", true);
  const Rgb8Image im = cv.finish();
  EXPECT_GT(ink(im, 0, 50, 100, 100), 0.0);
  EXPECT_GT(ink(im, 0, 0, 100, 50), 0.0);
  int lowestX = -1;  // the underscore lies at v = +1 cell below the baseline: x > 50 once turned
  for (int y = 99; y >= 50 && lowestX < 0; --y)
    for (int x = 0; x < 100; ++x)
      if (pixel(im, x, y)[0] < 128) {
        lowestX = x;
        break;
      }
  EXPECT_GE(lowestX, 50);
}

}  // namespace
}  // namespace tetraprobe::cli
