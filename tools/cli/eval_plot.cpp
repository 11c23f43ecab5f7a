// Two-panel chart of error against bytes and against run time (tetraprobe eval --plot), drawn once with
// cairo's path and toy text API onto either its SVG surface or its image surface (written with cairo's PNG
// writer). Contract: eval_plot.h.
#include "eval_plot.h"

#include <cairo-svg.h>
#include <cairo.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <memory>
#include <numbers>
#include <stdexcept>
#include <utility>

namespace tetraprobe::cli {

namespace {

constexpr double kPanelW = 460, kPanelH = 320, kMarginL = 64, kMarginR = 16, kMarginT = 48, kMarginB = 56,
                 kLegendH = 28;
constexpr uint32_t kBlack = 0x000000, kWhite = 0xffffff, kFrame = 0x444444, kMajorGrid = 0xcccccc,
                   kMinorGrid = 0xeeeeee, kGreyText = 0x555555, kPareto = 0x222222;

enum class Anchor { kStart, kMiddle, kEnd };

// The few primitives the chart needs, in SVG user units (x right, y down) on a cairo context.
class Pen {
 public:
  explicit Pen(cairo_t* cr) : cr_(cr) {
    cairo_select_font_face(cr_, "sans-serif", CAIRO_FONT_SLANT_NORMAL, CAIRO_FONT_WEIGHT_NORMAL);
    // Unhinted outlines and metrics: the PNG's text has the SVG's widths, and anchors agree between the two.
    cairo_font_options_t* fo = cairo_font_options_create();
    cairo_font_options_set_hint_style(fo, CAIRO_HINT_STYLE_NONE);
    cairo_font_options_set_hint_metrics(fo, CAIRO_HINT_METRICS_OFF);
    cairo_font_options_set_antialias(fo, CAIRO_ANTIALIAS_GRAY);
    cairo_set_font_options(cr_, fo);
    cairo_font_options_destroy(fo);
    cairo_set_line_join(cr_, CAIRO_LINE_JOIN_ROUND);
  }

  void color(uint32_t c) {
    cairo_set_source_rgb(cr_, double((c >> 16) & 255) / 255.0, double((c >> 8) & 255) / 255.0,
                         double(c & 255) / 255.0);
  }

  // An open polyline through xy = {x0, y0, x1, y1, ...}; dash > 0: `dash` drawn, `dash` skipped, along it.
  void polyline(const std::vector<double>& xy, uint32_t c, double width, double dashOn = 0.0,
                double dashOff = 0.0) {
    cairo_move_to(cr_, xy[0], xy[1]);
    for (size_t i = 2; i + 1 < xy.size(); i += 2) cairo_line_to(cr_, xy[i], xy[i + 1]);
    stroke(c, width, dashOn, dashOff);
  }

  void fillRect(double x, double y, double w, double h, uint32_t c) {
    cairo_rectangle(cr_, x, y, w, h);
    color(c);
    cairo_fill(cr_);
  }
  void strokeRect(double x, double y, double w, double h, uint32_t c, double width) {
    cairo_rectangle(cr_, x, y, w, h);
    stroke(c, width);
  }
  void fillCircle(double cx, double cy, double r, uint32_t c) {
    cairo_new_sub_path(cr_);
    cairo_arc(cr_, cx, cy, r, 0.0, 2.0 * std::numbers::pi);
    color(c);
    cairo_fill(cr_);
  }
  void strokeCircle(double cx, double cy, double r, uint32_t c, double width) {
    cairo_new_sub_path(cr_);
    cairo_arc(cr_, cx, cy, r, 0.0, 2.0 * std::numbers::pi);
    stroke(c, width);
  }

  // The advance width of `s` at font size `size`.
  double textWidth(const std::string& s, double size) {
    cairo_save(cr_);
    cairo_set_font_size(cr_, size);
    cairo_text_extents_t e;
    cairo_text_extents(cr_, s.c_str(), &e);
    cairo_restore(cr_);
    return e.x_advance;
  }

  // One line of text, y on its baseline; `vertical` turns it a quarter turn counter-clockwise about (x, y).
  void text(double x, double y, const std::string& s, Anchor anchor, double size, uint32_t c = kBlack,
            bool vertical = false) {
    if (s.empty()) return;
    cairo_save(cr_);
    cairo_translate(cr_, x, y);
    if (vertical) cairo_rotate(cr_, -0.5 * std::numbers::pi);
    cairo_set_font_size(cr_, size);
    cairo_text_extents_t e;
    cairo_text_extents(cr_, s.c_str(), &e);
    const double dx = anchor == Anchor::kStart    ? 0.0
                      : anchor == Anchor::kMiddle ? -0.5 * e.x_advance
                                                  : -e.x_advance;
    cairo_move_to(cr_, dx, 0.0);
    color(c);
    cairo_show_text(cr_, s.c_str());
    cairo_restore(cr_);
  }

 private:
  void stroke(uint32_t c, double width, double dashOn = 0.0, double dashOff = 0.0) {
    color(c);
    cairo_set_line_width(cr_, width);
    const double dashes[2] = {dashOn, dashOff};
    cairo_set_dash(cr_, dashes, dashOn > 0.0 ? 2 : 0, 0.0);
    cairo_stroke(cr_);
  }

  cairo_t* cr_;
};

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

void panel(Pen& pen, const std::vector<PlotPoint>& points, bool bytesAxis, double ox,
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
  pen.text(x0 + w / 2, y0 + h + 40, xTitle, Anchor::kMiddle, 12);
  pen.text(ox + 16, y0 + h / 2, "error", Anchor::kMiddle, 12, kBlack, true);
  if (!(xmax > 0.0)) {
    pen.strokeRect(x0, y0, w, h, kFrame, 1.0);
    pen.text(x0 + w / 2, y0 + h / 2, "not measured", Anchor::kMiddle, 12, 0x888888);
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
  // Tick labels: every 10^d first, then 2 and 5 x 10^d where they keep 6 units from every label placed.
  std::vector<std::pair<double, double>> placed;  // [left, right] of the labels drawn
  for (const bool major : {true, false})
    for (double d = std::floor(lx0); d <= lx1; d += 1.0)
      for (const double m : {1.0, 2.0, 5.0}) {
        const double v = m * std::pow(10.0, d);
        if ((m == 1.0) != major || std::log10(v) < lx0 || std::log10(v) > lx1) continue;
        pen.polyline({X(v), y0, X(v), y0 + h}, major ? kMajorGrid : kMinorGrid, 1.0);
        const std::string label = tickLabel(v, bytesAxis);
        const double half = 0.5 * pen.textWidth(label, 11), l = X(v) - half, r = X(v) + half;
        if (!major && std::any_of(placed.begin(), placed.end(), [&](const std::pair<double, double>& p) {
              return l < p.second + 6 && r > p.first - 6;
            }))
          continue;
        placed.push_back({l, r});
        pen.text(X(v), y0 + h + 16, label, Anchor::kMiddle, 11);
      }
  for (double v = 0.0; v <= ymax + 1e-9; v += ystep) {
    char buf[16];
    std::snprintf(buf, sizeof buf, "%g", std::round(v * 1000.0) / 1000.0);
    pen.polyline({x0, Y(v), x0 + w, Y(v)}, kMinorGrid, 1.0);
    pen.text(x0 - 6, Y(v) + 4, buf, Anchor::kEnd, 11);
  }
  pen.strokeRect(x0, y0, w, h, kFrame, 1.0);
  // Series: per method, points joined in x order, circles for mean_rel, open squares for gross.
  for (size_t mi = 0; mi < methods.size(); ++mi) {
    const uint32_t color = evalPlotColor(methods[mi], mi);
    std::vector<size_t> idx;
    for (size_t i = 0; i < points.size(); ++i)
      if (points[i].method == methods[mi] && xs[i] > 0.0) idx.push_back(i);
    std::sort(idx.begin(), idx.end(), [&](size_t a, size_t b) { return xs[a] < xs[b]; });
    for (int measure = 0; measure < 2; ++measure) {
      auto yv = [&](size_t i) { return measure == 0 ? points[i].meanRel : points[i].gross; };
      if (idx.size() > 1) {
        std::vector<double> line;
        for (size_t i : idx) line.insert(line.end(), {X(xs[i]), Y(yv(i))});
        pen.polyline(line, color, 1.5, measure == 1 ? 2.0 : 0.0, measure == 1 ? 2.0 : 0.0);
      }
      for (size_t i : idx) {
        if (measure == 0) {
          pen.fillCircle(X(xs[i]), Y(yv(i)), 4, color);
        } else {
          pen.fillRect(X(xs[i]) - 3.5, Y(yv(i)) - 3.5, 7, 7, kWhite);
          pen.strokeRect(X(xs[i]) - 3.5, Y(yv(i)) - 3.5, 7, 7, color, 1.5);
        }
      }
    }
    // Labels right of their point, or left of it where they would cross the frame.
    for (size_t i : idx) {
      if (points[i].label.empty()) continue;
      const bool right = X(xs[i]) + 6 + pen.textWidth(points[i].label, 10) <= x0 + w - 2;
      pen.text(X(xs[i]) + (right ? 6 : -6), Y(points[i].meanRel) - 6, points[i].label,
               right ? Anchor::kStart : Anchor::kEnd, 10, color);
    }
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
      if (step.size() >= 4) pen.polyline(step, kPareto, 1.0, 5.0, 3.0);
      for (size_t i : front) pen.strokeCircle(X(xs[i]), Y(ys[i]), 7, kPareto, 1.0);
    }
  }
}

std::vector<std::string> methodsOf(const std::vector<PlotPoint>& points) {
  std::vector<std::string> methods;
  for (const PlotPoint& p : points)
    if (std::find(methods.begin(), methods.end(), p.method) == methods.end()) methods.push_back(p.method);
  return methods;
}

void drawEvalPlot(cairo_t* cr, const std::vector<PlotPoint>& points, const PlotOptions& options) {
  Pen pen(cr);
  const std::vector<std::string> methods = methodsOf(points);
  const double width = evalPlotWidth();
  pen.fillRect(0.0, 0.0, width, evalPlotHeight(methods.size()), kWhite);
  pen.text(width / 2, 20, options.title, Anchor::kMiddle, 14);
  pen.text(width / 2, 36,
           std::string(
               "filled circles: mean_rel_error; open squares: gross_error (fraction off by more than 2x)") +
               (options.pareto ? "; ringed, dashed black: Pareto front" : ""),
           Anchor::kMiddle, 11, kGreyText);
  panel(pen, points, true, 0.0, "bytes the lookup touches", options, methods);
  panel(pen, points, false, kPanelW, options.timeAxis, options, methods);
  for (size_t mi = 0; mi < methods.size(); ++mi) {
    const double lx = 24 + double(mi % 4) * (width - 48) / 4,
                 ly = kPanelH + 8 + kLegendH * double(mi / 4) + 12;
    pen.fillCircle(lx, ly - 4, 5, evalPlotColor(methods[mi], mi));
    pen.text(lx + 10, ly, methods[mi], Anchor::kStart, 12);
  }
}

cairo_status_t appendTo(void* closure, const unsigned char* data, unsigned int length) {
  static_cast<std::string*>(closure)->append(reinterpret_cast<const char*>(data), length);
  return CAIRO_STATUS_SUCCESS;
}

void check(cairo_status_t status, const char* what) {
  if (status != CAIRO_STATUS_SUCCESS)
    throw std::runtime_error(std::string("eval plot: ") + what + ": " + cairo_status_to_string(status));
}

using Surface = std::unique_ptr<cairo_surface_t, decltype(&cairo_surface_destroy)>;
using Context = std::unique_ptr<cairo_t, decltype(&cairo_destroy)>;

}  // namespace

double evalPlotWidth() {
  return 2 * kPanelW;
}

double evalPlotHeight(size_t methods) {
  return kPanelH + kLegendH * double((std::max<size_t>(methods, 1) + 3) / 4) + 24;
}

uint32_t evalPlotColor(const std::string& method, size_t index) {
  static const std::map<std::string, uint32_t> known = {{"tet", 0x1b9e77},
                                                        {"tet (no occlusion)", 0x7570b3},
                                                        {"nearest", 0xd95f02},
                                                        {"grid (equal bytes)", 0xe7298a},
                                                        {"grid (probe count)", 0x66a61e},
                                                        {"tet+occlusion", 0xe6ab02}};
  static constexpr uint32_t spare[] = {0xa6761d, 0x666666, 0x1f78b4, 0xb2df8a};
  const auto it = known.find(method);
  return it != known.end() ? it->second : spare[index % 4];
}

std::string evalPlot(const std::vector<PlotPoint>& points, const PlotOptions& options, PlotFormat format,
                     double scale) {
  const double width = evalPlotWidth(), height = evalPlotHeight(methodsOf(points).size());
  std::string out;
  if (format == PlotFormat::kSvg) {
    Surface surface(cairo_svg_surface_create_for_stream(appendTo, &out, width, height),
                    cairo_surface_destroy);
    check(cairo_surface_status(surface.get()), "SVG surface");
    cairo_svg_surface_restrict_to_version(surface.get(), CAIRO_SVG_VERSION_1_1);
    cairo_svg_surface_set_document_unit(surface.get(), CAIRO_SVG_UNIT_USER);
    {
      Context cr(cairo_create(surface.get()), cairo_destroy);
      drawEvalPlot(cr.get(), points, options);
      check(cairo_status(cr.get()), "drawing");
    }
    cairo_surface_finish(surface.get());  // writes the document's end
    check(cairo_surface_status(surface.get()), "SVG output");
    return out;
  }
  if (!(scale > 0.0)) throw std::runtime_error("eval plot: the PNG scale must be positive");
  Surface surface(cairo_image_surface_create(CAIRO_FORMAT_RGB24, int(std::lround(width * scale)),
                                             int(std::lround(height * scale))),
                  cairo_surface_destroy);
  check(cairo_surface_status(surface.get()), "image surface");
  {
    Context cr(cairo_create(surface.get()), cairo_destroy);
    cairo_scale(cr.get(), scale, scale);
    drawEvalPlot(cr.get(), points, options);
    check(cairo_status(cr.get()), "drawing");
  }
  cairo_surface_flush(surface.get());
  check(cairo_surface_write_to_png_stream(surface.get(), appendTo, &out), "PNG output");
  return out;
}

}  // namespace tetraprobe::cli
