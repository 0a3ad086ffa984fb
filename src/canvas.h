// A cairo drawing surface for the figures (slices, charts, plans): PNG or SVG,
// anti-aliased text and lines, colours from the label palette, written atomically.
// Internal to src/.
#pragma once

#include <cairo.h>

#include <string>

#include "semioctree/octomap_ext/labels.h"

namespace semioctree {

class Canvas {
 public:
  enum class Format { kPng, kSvg };
  // A white canvas of width × height pixels (PNG: RGB; SVG: points, 1 px = 1 pt).
  Canvas(Format format, int width, int height);
  ~Canvas();
  Canvas(const Canvas&) = delete;
  Canvas& operator=(const Canvas&) = delete;

  // The format an output path asks for: .svg → SVG, anything else PNG.
  static Format format_of(const std::string& path);

  cairo_t* cr() { return cr_; }
  int width() const { return width_; }
  int height() const { return height_; }
  void set_color(Rgb c, double alpha = 1.0);
  // Filled and outlined rectangles [x0, x1) × [y0, y1); an outline is a 1 px line
  // drawn just inside the rectangle (pixel-aligned when the corners are integers).
  void fill_rect(double x0, double y0, double x1, double y1, Rgb c);
  void outline_rect(double x0, double y0, double x1, double y1, Rgb c, double width = 1.0);
  void line(double x0, double y0, double x1, double y1, Rgb c, double width = 1.0);
  void disc(double x, double y, double radius, Rgb fill, Rgb outline);

  // Text, sans-serif of `size` px, placed by its anchor: horizontal 0 (left end at x),
  // 0.5 (centred), 1 (right end at x); vertically centred on y.
  void text(double x, double y, const std::string& s, double size, Rgb c, double anchor = 0.0,
            bool bold = false);
  double text_width(const std::string& s, double size, bool bold = false);
  // Text reading upwards, centred on (x, y) (a y axis's name).
  void vertical_text(double x, double y, const std::string& s, double size, Rgb c);
  // Bold text on a translucent white box, left end at x (labels over a map).
  void boxed_text(double x, double y, const std::string& s, double size, Rgb c);
  // Lines and outlines drawn from now on dashed (6 on, 4 off) or solid.
  void set_dashed(bool dashed);

  // Writes the canvas to `path` (atomically; throws FileError). Once only.
  void write(const std::string& path);

 private:
  Format format_;
  int width_, height_;
  std::string svg_;  // the SVG surface's output so far
  cairo_surface_t* surface_ = nullptr;
  cairo_t* cr_ = nullptr;
};

}  // namespace semioctree
