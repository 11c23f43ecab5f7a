// `tetraprobe eval --plot`: error against memory and against run time, one point per method (and per level of
// a sweep), as a chart of two panels written as SVG or as a PNG raster (plot_canvas.h). No dependencies.
#pragma once

#include <string>
#include <vector>

#include "image_compare.h"

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

// The SVG document (UTF-8 text): left panel error against bytes, right panel error against `time`; both x
// axes log10, y linear from 0. With options.pareto, the points on each measure's Pareto front over all
// methods are ringed and joined by a dashed step line.
std::string evalPlotSvg(const std::vector<PlotPoint>& points, const PlotOptions& options);

// The same chart as a raster, `scale` pixels per SVG user unit (920 x 372 units for up to four methods, a
// legend row more per four), antialiased, text in the bitmap font. Write it with writeImage8.
Rgb8Image evalPlotImage(const std::vector<PlotPoint>& points, const PlotOptions& options, double scale = 2.0);

}  // namespace tetraprobe::cli
