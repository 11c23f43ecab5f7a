// The eval chart (tools/cli/eval_plot.h, cairo): the PNG and the SVG are files of the chart's size, each series
// is drawn in its own colour where its values put it, text is set (antialiased), and the Pareto marks appear
// only when asked for.
#include <gtest/gtest.h>

#include <unistd.h>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "eval_plot.h"
#include "image_compare.h"

namespace tetraprobe::cli {
namespace {

// Decodes PNG bytes through the tool's own reader (a file: readImage8 takes a path).
Rgb8Image decodePng(const std::string& png) {
  const std::filesystem::path path =
      std::filesystem::temp_directory_path() / ("tetraprobe_test_plot_" + std::to_string(getpid()) + ".png");
  std::ofstream(path, std::ios::binary).write(png.data(), std::streamsize(png.size()));
  const Rgb8Image im = readImage8(path.string());
  std::filesystem::remove(path);
  return im;
}

bool near(const uint8_t* p, uint32_t rgb, int tolerance = 2) {
  return std::abs(int(p[0]) - int((rgb >> 16) & 255)) <= tolerance &&
         std::abs(int(p[1]) - int((rgb >> 8) & 255)) <= tolerance &&
         std::abs(int(p[2]) - int(rgb & 255)) <= tolerance;
}

// The pixels of colour `rgb` (within 2 per channel) in [x0, x1) x [y0, y1): their count and centroid.
struct Blob {
  int count = 0;
  double x = 0.0, y = 0.0;
};
Blob blob(const Rgb8Image& im, uint32_t rgb, int x0, int y0, int x1, int y1) {
  Blob b;
  for (int y = y0; y < y1; ++y)
    for (int x = x0; x < x1; ++x)
      if (near(&im.rgb[(size_t(y) * size_t(im.width) + size_t(x)) * 3], rgb)) {
        ++b.count;
        b.x += x;
        b.y += y;
      }
  if (b.count > 0) {
    b.x /= b.count;
    b.y /= b.count;
  }
  return b;
}

// Pixels in the box that are not white, and how many distinct grey levels (min channel) they take.
void ink(const Rgb8Image& im, int x0, int y0, int x1, int y1, int* dark, int* levels) {
  bool seen[256] = {};
  *dark = 0;
  for (int y = y0; y < y1; ++y)
    for (int x = x0; x < x1; ++x) {
      const uint8_t* p = &im.rgb[(size_t(y) * size_t(im.width) + size_t(x)) * 3];
      const uint8_t m = std::min({p[0], p[1], p[2]});
      if (m < 250) ++*dark;
      seen[m] = true;
    }
  *levels = 0;
  for (bool s : seen) *levels += s;
}

std::vector<PlotPoint> samplePoints() {
  return {{"tet", "", 3.2e6, 12.0, 0.19, 0.01},
          {"nearest", "", 0.9e6, 2.0, 0.31, 0.12},
          {"grid (equal bytes)", "", 3.1e6, 9.0, 0.27, 0.05}};
}

// The legend takes a row per four methods: 372 user units high up to four, 400 up to eight.
TEST(EvalPlot, HeightGrowsByALegendRowPerFourMethods) {
  EXPECT_EQ(evalPlotWidth(), 920.0);
  for (size_t m = 1; m <= 4; ++m) EXPECT_EQ(evalPlotHeight(m), 372.0) << m;
  for (size_t m = 5; m <= 8; ++m) EXPECT_EQ(evalPlotHeight(m), 400.0) << m;
  EXPECT_EQ(evalPlotHeight(9), 428.0);
}

// The PNG is a PNG of round(size x scale) pixels, on white (the corner far from any text).
TEST(EvalPlot, PngIsTheChartsSizeTimesTheScale) {
  PlotOptions po;
  po.title = "size";
  for (const double scale : {1.0, 2.0, 1.5}) {
    const std::string png = evalPlot(samplePoints(), po, PlotFormat::kPng, scale);
    ASSERT_GT(png.size(), 8u);
    EXPECT_EQ(png.substr(0, 8), std::string("\x89PNG\r\n\x1a\n", 8));
    const Rgb8Image im = decodePng(png);
    EXPECT_EQ(im.width, int(std::lround(920 * scale))) << scale;
    EXPECT_EQ(im.height, int(std::lround(372 * scale))) << scale;
    EXPECT_TRUE(
        near(&im.rgb[(size_t(im.height - 1) * size_t(im.width) + size_t(im.width - 1)) * 3], 0xffffff));
  }
  std::vector<PlotPoint> five = samplePoints();
  five.push_back({"tet+occlusion", "", 2e6, 0.0, 0.2, 0.02});
  five.push_back({"grid (probe count)", "", 1e6, 3.0, 0.4, 0.2});
  EXPECT_EQ(decodePng(evalPlot(five, po, PlotFormat::kPng, 1.0)).height, 400);
  EXPECT_THROW(evalPlot(five, po, PlotFormat::kPng, 0.0), std::runtime_error);
}

// The SVG is one complete SVG 1.1 document whose size is the chart's, in user units.
TEST(EvalPlot, SvgIsACompleteDocumentOfTheChartsSize) {
  PlotOptions po;
  po.title = "size";
  const std::string svg = evalPlot(samplePoints(), po, PlotFormat::kSvg);
  EXPECT_EQ(svg.rfind("<?xml", 0), 0u) << svg.substr(0, 80);
  const size_t root = svg.find("<svg ");
  ASSERT_NE(root, std::string::npos);
  const std::string head = svg.substr(root, svg.find('>', root) - root);
  EXPECT_NE(head.find("width=\"920\""), std::string::npos) << head;
  EXPECT_NE(head.find("height=\"372\""), std::string::npos) << head;
  EXPECT_NE(head.find("version=\"1.1\""), std::string::npos) << head;
  EXPECT_NE(svg.find("</svg>"), std::string::npos);
  EXPECT_NE(svg.find("<path"), std::string::npos);  // markers and text are drawn as paths and glyph outlines
}

// Each plotted method's colour covers its markers (two panels and the legend); a method not plotted has none.
TEST(EvalPlot, EverySeriesIsDrawnInItsOwnColour) {
  const Rgb8Image im = decodePng(evalPlot(samplePoints(), PlotOptions{}, PlotFormat::kPng, 2.0));
  for (const auto& [method, index] :
       {std::pair<std::string, size_t>{"tet", 0}, {"nearest", 1}, {"grid (equal bytes)", 2}}) {
    const uint32_t c = evalPlotColor(method, index);
    // Filled circles of radius 4 (two panels) and 5 (legend) at 2 pixels a unit: over 3 x 150 pixels inside.
    EXPECT_GT(blob(im, c, 0, 0, im.width, im.height).count, 450) << method;
    EXPECT_GT(blob(im, c, 0, 0, 920, 640).count, 150) << method << ": left panel";
    EXPECT_GT(blob(im, c, 920, 0, 1840, 640).count, 150) << method << ": right panel";
  }
  EXPECT_EQ(blob(im, evalPlotColor("tet (no occlusion)", 3), 0, 0, im.width, im.height).count, 0);
  EXPECT_EQ(evalPlotColor("tet", 0), 0x1b9e77u);
  EXPECT_NE(evalPlotColor("something new", 0), evalPlotColor("something else", 1));
}

// cairo's SVG fill for 0xRRGGBB: each channel as a percentage with up to six decimals, trailing zeros cut.
std::string svgFill(uint32_t rgb) {
  std::string s = "fill:rgb(";
  for (int shift : {16, 8, 0}) {
    char buf[32];
    std::snprintf(buf, sizeof buf, "%f", double((rgb >> shift) & 255) / 255.0 * 100.0);
    std::string v = buf;
    while (v.back() == '0') v.pop_back();
    if (v.back() == '.') v.pop_back();
    s += v + (shift ? "%," : "%)");
  }
  return s;
}

// The SVG fills each plotted series in its colour, and no other method's.
TEST(EvalPlot, SvgFillsEverySeriesInItsOwnColour) {
  const std::string svg = evalPlot(samplePoints(), PlotOptions{}, PlotFormat::kSvg);
  EXPECT_EQ(svgFill(0x66a61e), "fill:rgb(40%,65.098039%,11.764706%)");
  EXPECT_NE(svg.find(svgFill(evalPlotColor("tet", 0))), std::string::npos);
  EXPECT_NE(svg.find(svgFill(evalPlotColor("nearest", 1))), std::string::npos);
  EXPECT_NE(svg.find(svgFill(evalPlotColor("grid (equal bytes)", 2))), std::string::npos);
  EXPECT_EQ(svg.find(svgFill(evalPlotColor("tet (no occlusion)", 3))), std::string::npos);
}

// Log x and linear y put each marker by its value: in the left panel the larger `bytes` lies right, in the
// right panel the larger `time`; the larger error lies higher in both.
TEST(EvalPlot, MarkersSitWhereTheirValuesPutThem) {
  const std::vector<PlotPoint> points = {{"tet", "", 1e6, 10.0, 0.1, 0.05},
                                         {"nearest", "", 1e7, 1.0, 0.3, 0.05}};
  const Rgb8Image im = decodePng(evalPlot(points, PlotOptions{}, PlotFormat::kPng, 2.0));
  const uint32_t a = evalPlotColor("tet", 0), b = evalPlotColor("nearest", 1);
  const int legendTop = 2 * 320;
  const Blob la = blob(im, a, 0, 0, 920, legendTop), lb = blob(im, b, 0, 0, 920, legendTop);
  const Blob ra = blob(im, a, 920, 0, 1840, legendTop), rb = blob(im, b, 920, 0, 1840, legendTop);
  ASSERT_GT(la.count, 0);
  ASSERT_GT(lb.count, 0);
  ASSERT_GT(ra.count, 0);
  ASSERT_GT(rb.count, 0);
  EXPECT_LT(la.x + 100, lb.x) << "10x the bytes lies right";
  EXPECT_GT(ra.x, rb.x + 100) << "10x the time lies right";
  EXPECT_GT(la.y, lb.y + 20) << "the larger mean error lies higher";
  EXPECT_GT(ra.y, rb.y + 20);
}

// A point with no time (<= 0) is drawn in the bytes panel only; the time panel without any time is empty.
TEST(EvalPlot, PointsWithoutATimeAreLeftOutOfTheTimePanel) {
  std::vector<PlotPoint> points = samplePoints();
  points[0].time = 0.0;  // tet
  const Rgb8Image im = decodePng(evalPlot(points, PlotOptions{}, PlotFormat::kPng, 2.0));
  const uint32_t tet = evalPlotColor("tet", 0), nearest = evalPlotColor("nearest", 1);
  const int legendTop = 2 * 320;
  EXPECT_GT(blob(im, tet, 0, 0, 920, legendTop).count, 100);
  EXPECT_EQ(blob(im, tet, 920, 0, 1840, legendTop).count, 0);
  EXPECT_GT(blob(im, nearest, 920, 0, 1840, legendTop).count, 100);
  for (PlotPoint& p : points) p.time = -1.0;
  const Rgb8Image none = decodePng(evalPlot(points, PlotOptions{}, PlotFormat::kPng, 2.0));
  for (const auto& [method, index] : {std::pair<std::string, size_t>{"tet", 0}, {"nearest", 1}})
    EXPECT_EQ(blob(none, evalPlotColor(method, index), 920, 0, 1840, legendTop).count, 0) << method;
}

// The title is set in an antialiased font: ink with many grey levels where it is, none without it.
TEST(EvalPlot, TitleIsSetInAnAntialiasedFont) {
  PlotOptions po;
  po.title = "two_rooms.scene.json (stratified points)";
  const Rgb8Image with = decodePng(evalPlot(samplePoints(), po, PlotFormat::kPng, 2.0));
  po.title.clear();
  const Rgb8Image without = decodePng(evalPlot(samplePoints(), po, PlotFormat::kPng, 2.0));
  int dark = 0, levels = 0;
  ink(with, 600, 10, 1240, 48, &dark, &levels);  // the title's band: baseline at 20 units, 14 units high
  EXPECT_GT(dark, 500);
  EXPECT_GT(levels, 32) << "antialiased edges take many grey levels";
  ink(without, 600, 10, 1240, 48, &dark, &levels);
  EXPECT_EQ(dark, 0);
}

// The Pareto front's rings and step line (dark grey 0x222222) are drawn with options.pareto only.
TEST(EvalPlot, ParetoFrontIsMarkedOnlyWhenAsked) {
  PlotOptions po;
  const Rgb8Image plain = decodePng(evalPlot(samplePoints(), po, PlotFormat::kPng, 2.0));
  po.pareto = true;
  const Rgb8Image marked = decodePng(evalPlot(samplePoints(), po, PlotFormat::kPng, 2.0));
  // Inside the two frames (x 64..444 and 524..904, y 48..264 units), where no text is drawn.
  auto rings = [](const Rgb8Image& im) {
    return blob(im, 0x222222, 2 * 64 + 2, 2 * 48 + 2, 2 * 444 - 2, 2 * 264 - 2).count +
           blob(im, 0x222222, 2 * 524 + 2, 2 * 48 + 2, 2 * 904 - 2, 2 * 264 - 2).count;
  };
  EXPECT_EQ(rings(plain), 0);
  EXPECT_GT(rings(marked), 100);
}

}  // namespace
}  // namespace tetraprobe::cli
