// Two-panel chart of error against bytes and against run time (tetraprobe eval --plot), drawn once on a
// PlotCanvas and written as SVG or PNG. Contract: eval_plot.h.
#include "eval_plot.h"

#include "plot_canvas.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>

namespace tetraprobe::cli {

namespace {

constexpr double kPanelW = 460, kPanelH = 320, kMarginL = 64, kMarginR = 16, kMarginT = 48, kMarginB = 56,
                 kLegendH = 28;

std::string colorOf(const std::string& method, size_t index) {
  static const std::map<std::string, std::string> known = {{"tet", "#1b9e77"},
                                                           {"tet (no occlusion)", "#7570b3"},
                                                           {"nearest", "#d95f02"},
                                                           {"grid (equal bytes)", "#e7298a"},
                                                           {"grid (probe count)", "#66a61e"},
                                                           {"tet+occlusion", "#e6ab02"}};
  static const char* spare[] = {"#a6761d", "#666666", "#1f78b4", "#b2df8a"};
  const auto it = known.find(method);
  return it != known.end() ? it->second : spare[index % 4];
}

std::string tickLabel(double v, bool bytes) {
  char buf[32];
  if (bytes) {
    if (v >= 1e9)
      std::snprintf(buf, sizeof buf, "%g GB", v / 1e9);
    else if (v >= 1e6)
      std::snprintf(buf, sizeof buf, "%g MB", v / 1e6);
    else if (v >= 1e3)
      std::snprintf(buf, sizeof buf, "%g kB", v / 1e3);
    else
      std::snprintf(buf, sizeof buf, "%g B", v);
  } else {
    std::snprintf(buf, sizeof buf, "%g", v);
  }
  return buf;
}

// Indices of the points on the Pareto front of (x, y): no other point has x' <= x and y' <= y with one
// strictly smaller. Sorted by x.
std::vector<size_t> paretoFront(const std::vector<double>& x, const std::vector<double>& y) {
  std::vector<size_t> order;
  for (size_t i = 0; i < x.size(); ++i)
    if (x[i] > 0.0) order.push_back(i);
  std::sort(order.begin(), order.end(),
            [&](size_t a, size_t b) { return x[a] != x[b] ? x[a] < x[b] : y[a] < y[b]; });
  std::vector<size_t> front;
  double best = INFINITY;
  for (size_t i : order)
    if (y[i] < best) {
      front.push_back(i);
      best = y[i];
    }
  return front;
}

// Plot size in user units for `methods` series (the legend takes a row per four methods).
double plotWidth() {
  return 2 * kPanelW;
}
double plotHeight(size_t methods) {
  return kPanelH + kLegendH * double((methods + 3) / 4) + 24;
}

void panel(PlotCanvas& cv, const std::vector<PlotPoint>& points, bool bytesAxis, double ox,
           const std::string& xTitle, const PlotOptions& options, const std::vector<std::string>& methods) {
  std::vector<double> xs;
  for (const PlotPoint& p : points) xs.push_back(bytesAxis ? p.bytes : p.time);
  double xmin = INFINITY, xmax = 0.0, ymax = 0.0;
  for (size_t i = 0; i < points.size(); ++i) {
    if (!(xs[i] > 0.0)) continue;
    xmin = std::min(xmin, xs[i]);
    xmax = std::max(xmax, xs[i]);
    ymax = std::max({ymax, points[i].meanRel, points[i].gross});
  }
  const double x0 = ox + kMarginL, y0 = kMarginT, w = kPanelW - kMarginL - kMarginR,
               h = kPanelH - kMarginT - kMarginB;
  cv.rect(x0, y0, w, h, "white", "none", 0.0);  // the frame's stroke is drawn over the grid lines, below
  cv.text(x0 + w / 2, y0 + h + 40, xTitle, TextAnchor::kMiddle, 12);
  cv.text(ox + 16, y0 + h / 2, "error", TextAnchor::kMiddle, 12, "#000000", true);
  if (!(xmax > 0.0)) {
    cv.rect(x0, y0, w, h, "none", "#444", 1.0);
    cv.text(x0 + w / 2, y0 + h / 2, "not measured", TextAnchor::kMiddle, 12, "#888");
    return;
  }
  // Log x padded by a fifth of a decade each side (at least one decade in all); ticks at 1, 2, 5 x 10^d.
  double lx0 = std::log10(xmin) - 0.2, lx1 = std::log10(xmax) + 0.2;
  if (lx1 - lx0 < 1.0) {
    const double mid = 0.5 * (lx0 + lx1);
    lx0 = mid - 0.5;
    lx1 = mid + 0.5;
  }
  ymax = ymax > 0.0 ? ymax * 1.1 : 1.0;
  const double ystep = ymax > 1.0 ? 0.5 : ymax > 0.5 ? 0.1 : ymax > 0.2 ? 0.05 : 0.02;
  ymax = std::ceil(ymax / ystep) * ystep;
  auto X = [&](double v) { return x0 + (std::log10(v) - lx0) / (lx1 - lx0) * w; };
  auto Y = [&](double v) { return y0 + h - v / ymax * h; };
  for (double d = std::floor(lx0); d <= lx1; d += 1.0)
    for (const double m : {1.0, 2.0, 5.0}) {
      const double v = m * std::pow(10.0, d);
      if (std::log10(v) < lx0 || std::log10(v) > lx1) continue;
      cv.polyline({X(v), y0, X(v), y0 + h}, m == 1.0 ? "#ccc" : "#eee", 1.0);
      cv.text(X(v), y0 + h + 16, tickLabel(v, bytesAxis), TextAnchor::kMiddle, 11);
    }
  for (double v = 0.0; v <= ymax + 1e-9; v += ystep) {
    char buf[16];
    std::snprintf(buf, sizeof buf, "%g", std::round(v * 1000.0) / 1000.0);
    cv.polyline({x0, Y(v), x0 + w, Y(v)}, "#eee", 1.0);
    cv.text(x0 - 6, Y(v) + 4, buf, TextAnchor::kEnd, 11);
  }
  cv.rect(x0, y0, w, h, "none", "#444", 1.0);
  // Series: per method, points joined in x order, circles for mean_rel, open squares for gross.
  for (size_t mi = 0; mi < methods.size(); ++mi) {
    const std::string color = colorOf(methods[mi], mi);
    std::vector<size_t> idx;
    for (size_t i = 0; i < points.size(); ++i)
      if (points[i].method == methods[mi] && xs[i] > 0.0) idx.push_back(i);
    std::sort(idx.begin(), idx.end(), [&](size_t a, size_t b) { return xs[a] < xs[b]; });
    for (int measure = 0; measure < 2; ++measure) {
      auto yv = [&](size_t i) { return measure == 0 ? points[i].meanRel : points[i].gross; };
      if (idx.size() > 1) {
        std::vector<double> line;
        for (size_t i : idx) line.insert(line.end(), {X(xs[i]), Y(yv(i))});
        cv.polyline(line, color, 1.5, measure == 1 ? 2.0 : 0.0, measure == 1 ? 2.0 : 0.0);
      }
      for (size_t i : idx) {
        if (measure == 0)
          cv.circle(X(xs[i]), Y(yv(i)), 4, color, "none", 0.0);
        else
          cv.rect(X(xs[i]) - 3.5, Y(yv(i)) - 3.5, 7, 7, "white", color, 1.5);
      }
    }
    for (size_t i : idx)
      if (!points[i].label.empty())
        cv.text(X(xs[i]) + 6, Y(points[i].meanRel) - 6, points[i].label, TextAnchor::kStart, 10, color);
  }
  if (options.pareto) {
    for (int measure = 0; measure < 2; ++measure) {
      std::vector<double> ys;
      for (const PlotPoint& p : points) ys.push_back(measure == 0 ? p.meanRel : p.gross);
      const std::vector<size_t> front = paretoFront(xs, ys);
      if (front.empty()) continue;
      std::vector<double> step;
      for (size_t k = 0; k < front.size(); ++k) {
        const size_t i = front[k];
        if (k > 0) step.insert(step.end(), {X(xs[i]), Y(ys[front[k - 1]])});
        step.insert(step.end(), {X(xs[i]), Y(ys[i])});
      }
      if (step.size() >= 4) cv.polyline(step, "#222", 1.0, 5.0, 3.0);
      for (size_t i : front) cv.circle(X(xs[i]), Y(ys[i]), 7, "none", "#222", 1.0);
    }
  }
}

std::vector<std::string> methodsOf(const std::vector<PlotPoint>& points) {
  std::vector<std::string> methods;
  for (const PlotPoint& p : points)
    if (std::find(methods.begin(), methods.end(), p.method) == methods.end()) methods.push_back(p.method);
  return methods;
}

}  // namespace

namespace {

void drawEvalPlot(PlotCanvas& cv, const std::vector<PlotPoint>& points, const PlotOptions& options) {
  const std::vector<std::string> methods = methodsOf(points);
  const double width = plotWidth();
  cv.text(width / 2, 20, options.title, TextAnchor::kMiddle, 14);
  cv.text(width / 2, 36,
          std::string(
              "filled circles: mean_rel_error; open squares: gross_error (fraction off by more than 2x)") +
              (options.pareto ? "; ringed, dashed black: Pareto front" : ""),
          TextAnchor::kMiddle, 11, "#555");
  panel(cv, points, true, 0.0, "bytes the lookup touches", options, methods);
  panel(cv, points, false, kPanelW, options.timeAxis, options, methods);
  for (size_t mi = 0; mi < methods.size(); ++mi) {
    const double lx = 24 + double(mi % 4) * (width - 48) / 4,
                 ly = kPanelH + 8 + kLegendH * double(mi / 4) + 12;
    cv.circle(lx, ly - 4, 5, colorOf(methods[mi], mi), "none", 0.0);
    cv.text(lx + 10, ly, methods[mi], TextAnchor::kStart, 12);
  }
}

}  // namespace

std::string evalPlotSvg(const std::vector<PlotPoint>& points, const PlotOptions& options) {
  SvgCanvas cv(plotWidth(), plotHeight(methodsOf(points).size()));
  drawEvalPlot(cv, points, options);
  return cv.finish();
}

Rgb8Image evalPlotImage(const std::vector<PlotPoint>& points, const PlotOptions& options, double scale) {
  RasterCanvas cv(plotWidth(), plotHeight(methodsOf(points).size()), scale);
  drawEvalPlot(cv, points, options);
  return cv.finish();
}

}  // namespace tetraprobe::cli
