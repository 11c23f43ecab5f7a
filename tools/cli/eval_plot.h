// `tetraprobe eval --plot`: error against memory and against run time, one point per method (and per level of
// a sweep), as a chart of two panels drawn once with cairo onto an SVG or a PNG surface. cairo is LGPL/MPL:
// the build side only (tools/cli; cmake/TetraprobeHelpers.cmake keeps it out of the runtime).
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace tetraprobe::cli {

struct PlotPoint {
  std::string method;                 // series: one colour per method, points of a series joined in x order
  std::string label;                  // text beside the point (e.g. "1 m"); may be empty
  double bytes = 0.0;                 // x of the left panel (log scale)
  double time = 0.0;                  // x of the right panel (log scale); <= 0: the point is left out there
  double meanRel = 0.0, gross = 0.0;  // y: mean_rel_error (filled circle), gross_error (open square)
};

struct PlotOptions {
  std::string title;
  std::string timeAxis = "GPU ms (1280x720 lookup pass)";
  bool pareto = false;  // mark each panel's Pareto front (lowest error for at most that x), per measure
};

enum class PlotFormat { kSvg, kPng };

// The chart's size in SVG user units: 920 wide; 372 high for up to four methods, the legend taking a row of
// 28 more per further four.
double evalPlotWidth();
double evalPlotHeight(size_t methods);

// The colour of a series as 0xRRGGBB: fixed for the methods eval reports ("tet" 0x1b9e77, "nearest"
// 0xd95f02, ...), else the spare colour for `index`, the method's place in order of first appearance.
uint32_t evalPlotColor(const std::string& method, size_t index);

// The chart as the bytes of a file. Left panel: error against bytes; right panel: error against `time`
// (options.timeAxis), "not measured" when no point has a time; both x axes log10, y linear from 0. Each
// method's points are joined in x order: filled circles for mean_rel_error, open squares on a dashed line for
// gross_error, in evalPlotColor; a legend row per four methods. With options.pareto, the points on each
// measure's Pareto front over all methods are ringed and joined by a dashed black step line. Text is set in
// the fontconfig "sans-serif" face (DejaVu Sans on Debian), antialiased.
//   kSvg: an SVG 1.1 document of evalPlotWidth() x evalPlotHeight() user units (text as glyph outlines).
//   kPng: an 8-bit RGB PNG of round(width * scale) x round(height * scale) pixels, `scale` > 0.
// Throws std::runtime_error when cairo fails (out of memory, a size cairo refuses).
std::string evalPlot(const std::vector<PlotPoint>& points, const PlotOptions& options, PlotFormat format,
                     double scale = 2.0);

}  // namespace tetraprobe::cli
