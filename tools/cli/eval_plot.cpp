// Two-panel SVG of error against bytes and against run time (tetraprobe eval --plot). Contract: eval_plot.h.
#include "eval_plot.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <sstream>

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

std::string escape(const std::string& s) {
  std::string out;
  for (char c : s) {
    if (c == '&')
      out += "&amp;";
    else if (c == '<')
      out += "&lt;";
    else if (c == '>')
      out += "&gt;";
    else
      out += c;
  }
  return out;
}

std::string num(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.1f", v);
  return buf;
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

void panel(std::ostringstream& svg, const std::vector<PlotPoint>& points, bool bytesAxis, double ox,
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
  svg << "<rect x='" << num(x0) << "' y='" << num(y0) << "' width='" << num(w) << "' height='" << num(h)
      << "' fill='white' stroke='#444'/>\n";
  svg << "<text x='" << num(x0 + w / 2) << "' y='" << num(y0 + h + 40) << "' text-anchor='middle'>"
      << escape(xTitle) << "</text>\n";
  svg << "<text x='" << num(ox + 16) << "' y='" << num(y0 + h / 2)
      << "' text-anchor='middle' transform='rotate(-90 " << num(ox + 16) << " " << num(y0 + h / 2)
      << ")'>error</text>\n";
  if (!(xmax > 0.0)) {
    svg << "<text x='" << num(x0 + w / 2) << "' y='" << num(y0 + h / 2)
        << "' text-anchor='middle' fill='#888'>not measured</text>\n";
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
      svg << "<line x1='" << num(X(v)) << "' y1='" << num(y0) << "' x2='" << num(X(v)) << "' y2='"
          << num(y0 + h) << "' stroke='" << (m == 1.0 ? "#ccc" : "#eee") << "'/>\n<text x='" << num(X(v))
          << "' y='" << num(y0 + h + 16) << "' text-anchor='middle' font-size='11'>"
          << tickLabel(v, bytesAxis) << "</text>\n";
    }
  for (double v = 0.0; v <= ymax + 1e-9; v += ystep) {
    char buf[16];
    std::snprintf(buf, sizeof buf, "%g", std::round(v * 1000.0) / 1000.0);
    svg << "<line x1='" << num(x0) << "' y1='" << num(Y(v)) << "' x2='" << num(x0 + w) << "' y2='"
        << num(Y(v)) << "' stroke='#eee'/>\n<text x='" << num(x0 - 6) << "' y='" << num(Y(v) + 4)
        << "' text-anchor='end' font-size='11'>" << buf << "</text>\n";
  }
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
        svg << "<polyline fill='none' stroke='" << color << "' stroke-width='1.5'"
            << (measure == 1 ? " stroke-dasharray='2 2'" : "") << " points='";
        for (size_t i : idx) svg << num(X(xs[i])) << "," << num(Y(yv(i))) << " ";
        svg << "'/>\n";
      }
      for (size_t i : idx) {
        if (measure == 0)
          svg << "<circle cx='" << num(X(xs[i])) << "' cy='" << num(Y(yv(i))) << "' r='4' fill='" << color
              << "'/>\n";
        else
          svg << "<rect x='" << num(X(xs[i]) - 3.5) << "' y='" << num(Y(yv(i)) - 3.5)
              << "' width='7' height='7' fill='white' stroke='" << color << "' stroke-width='1.5'/>\n";
      }
    }
    for (size_t i : idx)
      if (!points[i].label.empty())
        svg << "<text x='" << num(X(xs[i]) + 6) << "' y='" << num(Y(points[i].meanRel) - 6)
            << "' font-size='10' fill='" << color << "'>" << escape(points[i].label) << "</text>\n";
  }
  if (options.pareto) {
    for (int measure = 0; measure < 2; ++measure) {
      std::vector<double> ys;
      for (const PlotPoint& p : points) ys.push_back(measure == 0 ? p.meanRel : p.gross);
      const std::vector<size_t> front = paretoFront(xs, ys);
      if (front.empty()) continue;
      svg << "<polyline fill='none' stroke='#222' stroke-width='1' stroke-dasharray='5 3' points='";
      for (size_t k = 0; k < front.size(); ++k) {
        const size_t i = front[k];
        if (k > 0) svg << num(X(xs[i])) << "," << num(Y(ys[front[k - 1]])) << " ";
        svg << num(X(xs[i])) << "," << num(Y(ys[i])) << " ";
      }
      svg << "'/>\n";
      for (size_t i : front)
        svg << "<circle cx='" << num(X(xs[i])) << "' cy='" << num(Y(ys[i]))
            << "' r='7' fill='none' stroke='#222' stroke-width='1'/>\n";
    }
  }
}

}  // namespace

std::string evalPlotSvg(const std::vector<PlotPoint>& points, const PlotOptions& options) {
  std::vector<std::string> methods;
  for (const PlotPoint& p : points)
    if (std::find(methods.begin(), methods.end(), p.method) == methods.end()) methods.push_back(p.method);
  const double width = 2 * kPanelW, height = kPanelH + kLegendH * double((methods.size() + 3) / 4) + 24;
  std::ostringstream svg;
  svg << "<svg xmlns='http://www.w3.org/2000/svg' width='" << num(width) << "' height='" << num(height)
      << "' viewBox='0 0 " << num(width) << " " << num(height)
      << "' font-family='Helvetica, Arial, sans-serif' font-size='12'>\n";
  svg << "<rect width='100%' height='100%' fill='white'/>\n";
  svg << "<text x='" << num(width / 2) << "' y='20' text-anchor='middle' font-size='14'>"
      << escape(options.title) << "</text>\n";
  svg << "<text x='" << num(width / 2) << "' y='36' text-anchor='middle' font-size='11' fill='#555'>"
      << "filled circles: mean_rel_error; open squares: gross_error (fraction off by more than 2x)"
      << (options.pareto ? "; ringed, dashed black: Pareto front" : "") << "</text>\n";
  panel(svg, points, true, 0.0, "bytes the lookup touches", options, methods);
  panel(svg, points, false, kPanelW, options.timeAxis, options, methods);
  for (size_t mi = 0; mi < methods.size(); ++mi) {
    const double lx = 24 + double(mi % 4) * (width - 48) / 4,
                 ly = kPanelH + 8 + kLegendH * double(mi / 4) + 12;
    svg << "<circle cx='" << num(lx) << "' cy='" << num(ly - 4) << "' r='5' fill='"
        << colorOf(methods[mi], mi) << "'/>\n<text x='" << num(lx + 10) << "' y='" << num(ly) << "'>"
        << escape(methods[mi]) << "</text>\n";
  }
  svg << "</svg>\n";
  return svg.str();
}

}  // namespace tetraprobe::cli
