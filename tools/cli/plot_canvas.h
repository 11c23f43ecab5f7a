// Drawing surfaces for tetraprobe's charts (eval --plot): the few primitives a two-panel scatter plot needs,
// written once against PlotCanvas and rendered either as SVG text or as an antialiased raster for PNG.
// Coordinates are SVG user units (x right, y down, origin top-left). Colours are "#rrggbb", "white" or
// "none" (nothing drawn); "#rgb" is short for "#rrggbb". No dependencies beyond the standard library.
#pragma once

#include <cstdint>
#include <sstream>
#include <string>
#include <vector>

#include "image_compare.h"

namespace tetraprobe::cli {

enum class TextAnchor { kStart, kMiddle, kEnd };

class PlotCanvas {
 public:
  virtual ~PlotCanvas() = default;
  // Axis-aligned rectangle, filled and/or outlined (stroke centred on the edges).
  virtual void rect(double x, double y, double w, double h, const std::string& fill,
                    const std::string& stroke, double strokeWidth) = 0;
  // Open polyline through xy = {x0, y0, x1, y1, ...} (at least two points); dashOn > 0 dashes it (dashOn
  // drawn, dashOff skipped, measured along the whole line).
  virtual void polyline(const std::vector<double>& xy, const std::string& stroke, double width,
                        double dashOn = 0.0, double dashOff = 0.0) = 0;
  virtual void circle(double cx, double cy, double r, const std::string& fill, const std::string& stroke,
                      double strokeWidth) = 0;
  // One line of text, y on its baseline, `size` the font size in user units; `vertical` turns it a quarter
  // turn counter-clockwise about (x, y) (reading bottom to top).
  virtual void text(double x, double y, const std::string& s, TextAnchor anchor, double size,
                    const std::string& fill = "#000000", bool vertical = false) = 0;
};

// An SVG document of width x height user units, white background, Helvetica/Arial 12.
class SvgCanvas final : public PlotCanvas {
 public:
  SvgCanvas(double width, double height);
  void rect(double x, double y, double w, double h, const std::string& fill, const std::string& stroke,
            double strokeWidth) override;
  void polyline(const std::vector<double>& xy, const std::string& stroke, double width, double dashOn,
                double dashOff) override;
  void circle(double cx, double cy, double r, const std::string& fill, const std::string& stroke,
              double strokeWidth) override;
  void text(double x, double y, const std::string& s, TextAnchor anchor, double size, const std::string& fill,
            bool vertical) override;
  std::string finish();  // the document (UTF-8), closed

 private:
  std::ostringstream svg_;
};

// A raster of round(width * scale) x round(height * scale) pixels on white: every primitive is drawn hard-edged
// at `supersample` x that resolution and box-filtered down (antialiasing), text with the 5x9 bitmap font
// (bitmap_font.h) scaled to the font size (cap height 0.7 size). sRGB colours are averaged as stored (the
// usual 8-bit compositing; the difference from linear averaging is at edges only).
class RasterCanvas final : public PlotCanvas {
 public:
  RasterCanvas(double width, double height, double scale = 2.0, int supersample = 3);
  void rect(double x, double y, double w, double h, const std::string& fill, const std::string& stroke,
            double strokeWidth) override;
  void polyline(const std::vector<double>& xy, const std::string& stroke, double width, double dashOn,
                double dashOff) override;
  void circle(double cx, double cy, double r, const std::string& fill, const std::string& stroke,
              double strokeWidth) override;
  void text(double x, double y, const std::string& s, TextAnchor anchor, double size, const std::string& fill,
            bool vertical) override;
  Rgb8Image finish() const;  // the downsampled image, row 0 = top

 private:
  struct Rgb {
    uint8_t r, g, b;
  };
  // Sets every fine pixel whose centre satisfies inside(x, y) (user units) within the user-unit box.
  template <typename Inside>
  void fill(double x0, double y0, double x1, double y1, Rgb c, Inside inside);
  void segment(double ax, double ay, double bx, double by, double width, Rgb c);

  double k_;  // fine pixels per user unit
  int w_, h_, fineW_, fineH_, ss_;
  std::vector<Rgb> fine_;
};

// The colour a PlotCanvas colour string names; false for "none". Throws std::invalid_argument for anything
// else than "#rrggbb", "#rgb", "white", "black" or "none".
bool parsePlotColor(const std::string& s, uint8_t rgb[3]);

}  // namespace tetraprobe::cli
