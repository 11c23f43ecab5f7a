// SVG and raster back ends of PlotCanvas (plot_canvas.h). The raster one draws each primitive as the set of
// fine-pixel centres inside it (rectangles, butt-capped segments with round joins, discs, rings, font cells)
// and box-filters the fine grid down: plain supersampling, enough for a chart's lines and text.
#include "plot_canvas.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <stdexcept>

#include "bitmap_font.h"

namespace tetraprobe::cli {

namespace {

std::string escape(const std::string& s) {
  std::string out;
  for (char c : s) {
    if (c == '&')
      out += "&amp;";
    else if (c == '<')
      out += "&lt;";
    else if (c == '>')
      out += "&gt;";
    else if (c == '\'')
      out += "&apos;";
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

const char* anchorName(TextAnchor a) {
  return a == TextAnchor::kStart ? "start" : a == TextAnchor::kMiddle ? "middle" : "end";
}

int hexDigit(char c) {
  if (c >= '0' && c <= '9') return c - '0';
  if (c >= 'a' && c <= 'f') return c - 'a' + 10;
  if (c >= 'A' && c <= 'F') return c - 'A' + 10;
  return -1;
}

}  // namespace

bool parsePlotColor(const std::string& s, uint8_t rgb[3]) {
  if (s == "none") return false;
  if (s == "white" || s == "black") {
    rgb[0] = rgb[1] = rgb[2] = s == "white" ? 255 : 0;
    return true;
  }
  const bool longForm = s.size() == 7, shortForm = s.size() == 4;
  if (s.empty() || s[0] != '#' || !(longForm || shortForm))
    throw std::invalid_argument("plot colour '" + s + "' is not #rrggbb, #rgb, white, black or none");
  for (int c = 0; c < 3; ++c) {
    const int hi = hexDigit(s[size_t(longForm ? 1 + 2 * c : 1 + c)]);
    const int lo = longForm ? hexDigit(s[size_t(2 + 2 * c)]) : hi;
    if (hi < 0 || lo < 0)
      throw std::invalid_argument("plot colour '" + s + "' has a character that is not hex");
    rgb[c] = uint8_t(16 * hi + lo);
  }
  return true;
}

// --- SVG -----------------------------------------------------------------------------------------------

SvgCanvas::SvgCanvas(double width, double height) {
  svg_ << "<svg xmlns='http://www.w3.org/2000/svg' width='" << num(width) << "' height='" << num(height)
       << "' viewBox='0 0 " << num(width) << " " << num(height)
       << "' font-family='Helvetica, Arial, sans-serif' font-size='12'>\n";
  svg_ << "<rect width='100%' height='100%' fill='white'/>\n";
}

void SvgCanvas::rect(double x, double y, double w, double h, const std::string& fill,
                     const std::string& stroke, double strokeWidth) {
  svg_ << "<rect x='" << num(x) << "' y='" << num(y) << "' width='" << num(w) << "' height='" << num(h)
       << "' fill='" << fill << "' stroke='" << stroke << "' stroke-width='" << num(strokeWidth) << "'/>\n";
}

void SvgCanvas::polyline(const std::vector<double>& xy, const std::string& stroke, double width,
                         double dashOn, double dashOff) {
  svg_ << "<polyline fill='none' stroke='" << stroke << "' stroke-width='" << num(width) << "'";
  if (dashOn > 0.0) svg_ << " stroke-dasharray='" << num(dashOn) << " " << num(dashOff) << "'";
  svg_ << " points='";
  for (size_t i = 0; i + 1 < xy.size(); i += 2) svg_ << (i ? " " : "") << num(xy[i]) << "," << num(xy[i + 1]);
  svg_ << "'/>\n";
}

void SvgCanvas::circle(double cx, double cy, double r, const std::string& fill, const std::string& stroke,
                       double strokeWidth) {
  svg_ << "<circle cx='" << num(cx) << "' cy='" << num(cy) << "' r='" << num(r) << "' fill='" << fill
       << "' stroke='" << stroke << "' stroke-width='" << num(strokeWidth) << "'/>\n";
}

void SvgCanvas::text(double x, double y, const std::string& s, TextAnchor anchor, double size,
                     const std::string& fill, bool vertical) {
  svg_ << "<text x='" << num(x) << "' y='" << num(y) << "' text-anchor='" << anchorName(anchor)
       << "' font-size='" << num(size) << "' fill='" << fill << "'";
  if (vertical) svg_ << " transform='rotate(-90 " << num(x) << " " << num(y) << ")'";
  svg_ << ">" << escape(s) << "</text>\n";
}

std::string SvgCanvas::finish() {
  svg_ << "</svg>\n";
  return svg_.str();
}

// --- Raster --------------------------------------------------------------------------------------------

RasterCanvas::RasterCanvas(double width, double height, double scale, int supersample) {
  if (!(width > 0.0 && height > 0.0 && scale > 0.0 && supersample >= 1 && width * scale <= 16384.0 &&
        height * scale <= 16384.0))
    throw std::invalid_argument("raster plot size out of range");
  ss_ = supersample;
  w_ = std::max(1, int(std::lround(width * scale)));
  h_ = std::max(1, int(std::lround(height * scale)));
  fineW_ = w_ * ss_;
  fineH_ = h_ * ss_;
  k_ = scale * double(ss_);
  fine_.assign(size_t(fineW_) * size_t(fineH_), Rgb{255, 255, 255});
}

template <typename Inside>
void RasterCanvas::fill(double x0, double y0, double x1, double y1, Rgb c, Inside inside) {
  const int i0 = std::max(0, int(std::floor(x0 * k_))), i1 = std::min(fineW_ - 1, int(std::ceil(x1 * k_)));
  const int j0 = std::max(0, int(std::floor(y0 * k_))), j1 = std::min(fineH_ - 1, int(std::ceil(y1 * k_)));
  for (int j = j0; j <= j1; ++j)
    for (int i = i0; i <= i1; ++i)
      if (inside((double(i) + 0.5) / k_, (double(j) + 0.5) / k_))
        fine_[size_t(j) * size_t(fineW_) + size_t(i)] = c;
}

void RasterCanvas::segment(double ax, double ay, double bx, double by, double width, Rgb c) {
  const double dx = bx - ax, dy = by - ay, len = std::hypot(dx, dy), hw = 0.5 * width;
  if (!(len > 0.0)) return;
  const double ux = dx / len, uy = dy / len;
  fill(std::min(ax, bx) - hw, std::min(ay, by) - hw, std::max(ax, bx) + hw, std::max(ay, by) + hw, c,
       [&](double x, double y) {
         const double t = (x - ax) * ux + (y - ay) * uy, d = (x - ax) * uy - (y - ay) * ux;
         return t >= 0.0 && t <= len && std::abs(d) <= hw;
       });
}

void RasterCanvas::rect(double x, double y, double w, double h, const std::string& fill,
                        const std::string& stroke, double strokeWidth) {
  uint8_t rgb[3];
  if (parsePlotColor(fill, rgb))
    this->fill(x, y, x + w, y + h, Rgb{rgb[0], rgb[1], rgb[2]},
               [&](double px, double py) { return px >= x && px <= x + w && py >= y && py <= y + h; });
  if (strokeWidth > 0.0 && parsePlotColor(stroke, rgb)) {
    const double hw = 0.5 * strokeWidth;
    this->fill(x - hw, y - hw, x + w + hw, y + h + hw, Rgb{rgb[0], rgb[1], rgb[2]},
               [&](double px, double py) {
                 const bool outer = px >= x - hw && px <= x + w + hw && py >= y - hw && py <= y + h + hw;
                 const bool inner = px > x + hw && px < x + w - hw && py > y + hw && py < y + h - hw;
                 return outer && !inner;
               });
  }
}

void RasterCanvas::polyline(const std::vector<double>& xy, const std::string& stroke, double width,
                            double dashOn, double dashOff) {
  uint8_t rgb[3];
  if (xy.size() < 4 || !parsePlotColor(stroke, rgb)) return;
  const Rgb c{rgb[0], rgb[1], rgb[2]};
  const double period = dashOn + dashOff;
  double along = 0.0;  // length drawn before the current segment (the dash phase)
  for (size_t i = 2; i + 1 < xy.size(); i += 2) {
    const double ax = xy[i - 2], ay = xy[i - 1], bx = xy[i], by = xy[i + 1];
    const double len = std::hypot(bx - ax, by - ay);
    if (!(len > 0.0)) continue;
    if (dashOn > 0.0 && period > 0.0) {
      // Each dash that overlaps this segment, clipped to it.
      for (double s = std::floor(along / period) * period; s < along + len; s += period) {
        const double t0 = std::max(s, along) - along, t1 = std::min(s + dashOn, along + len) - along;
        if (t1 > t0)
          segment(ax + (bx - ax) * t0 / len, ay + (by - ay) * t0 / len, ax + (bx - ax) * t1 / len,
                  ay + (by - ay) * t1 / len, width, c);
      }
    } else {
      segment(ax, ay, bx, by, width, c);
      if (i + 3 < xy.size()) {  // round join at the inner vertex
        const double r = 0.5 * width;
        fill(bx - r, by - r, bx + r, by + r, c,
             [&](double x, double y) { return std::hypot(x - bx, y - by) <= r; });
      }
    }
    along += len;
  }
}

void RasterCanvas::circle(double cx, double cy, double r, const std::string& fill, const std::string& stroke,
                          double strokeWidth) {
  uint8_t rgb[3];
  if (parsePlotColor(fill, rgb))
    this->fill(cx - r, cy - r, cx + r, cy + r, Rgb{rgb[0], rgb[1], rgb[2]},
               [&](double x, double y) { return std::hypot(x - cx, y - cy) <= r; });
  if (strokeWidth > 0.0 && parsePlotColor(stroke, rgb)) {
    const double hw = 0.5 * strokeWidth;
    this->fill(cx - r - hw, cy - r - hw, cx + r + hw, cy + r + hw, Rgb{rgb[0], rgb[1], rgb[2]},
               [&](double x, double y) { return std::abs(std::hypot(x - cx, y - cy) - r) <= hw; });
  }
}

void RasterCanvas::text(double x, double y, const std::string& s, TextAnchor anchor, double size,
                        const std::string& fill, bool vertical) {
  uint8_t rgb[3];
  if (s.empty() || !parsePlotColor(fill, rgb)) return;
  const Rgb c{rgb[0], rgb[1], rgb[2]};
  const double p = 0.1 * size;  // user units per font cell: 7 cells of cap height = 0.7 size
  const double width = double(s.size()) * kGlyphAdvance * p;
  const double u0 = anchor == TextAnchor::kStart    ? 0.0
                    : anchor == TextAnchor::kMiddle ? -0.5 * width
                                                    : -width;
  for (size_t g = 0; g < s.size(); ++g) {
    const uint8_t* rows = glyphRows(s[g]);
    for (int r = 0; r < kGlyphH; ++r)
      for (int col = 0; col < kGlyphW; ++col) {
        if (!((rows[r] >> (kGlyphW - 1 - col)) & 1)) continue;
        // The cell in text coordinates relative to (x, y): u along the text, v down from the baseline.
        const double ua = u0 + (double(g) * kGlyphAdvance + col) * p, ub = ua + p;
        const double va = (r - kGlyphBaseline) * p, vb = va + p;
        // rotate(-90): (u, v) -> (v, -u).
        const double xa = vertical ? x + va : x + ua, xb = vertical ? x + vb : x + ub;
        const double ya = vertical ? y - ub : y + va, yb = vertical ? y - ua : y + vb;
        this->fill(xa, ya, xb, yb, c,
                   [&](double px, double py) { return px >= xa && px < xb && py >= ya && py < yb; });
      }
  }
}

Rgb8Image RasterCanvas::finish() const {
  Rgb8Image out;
  out.width = w_;
  out.height = h_;
  out.rgb.resize(size_t(w_) * size_t(h_) * 3);
  const int n = ss_ * ss_;
  for (int j = 0; j < h_; ++j)
    for (int i = 0; i < w_; ++i) {
      int sum[3] = {0, 0, 0};
      for (int b = 0; b < ss_; ++b)
        for (int a = 0; a < ss_; ++a) {
          const Rgb& f = fine_[size_t(j * ss_ + b) * size_t(fineW_) + size_t(i * ss_ + a)];
          sum[0] += f.r;
          sum[1] += f.g;
          sum[2] += f.b;
        }
      for (int ch = 0; ch < 3; ++ch)
        out.rgb[(size_t(j) * size_t(w_) + size_t(i)) * 3 + size_t(ch)] = uint8_t((sum[ch] + n / 2) / n);
    }
  return out;
}

}  // namespace tetraprobe::cli
