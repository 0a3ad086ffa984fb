// A small RGB raster for the PNG figures (slices, charts): rectangles, lines,
// text (stb_easy_font's quads) and a PNG writer (libpng). Internal to src/.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "semioctree/octomap_ext/labels.h"

namespace semioctree {

class Raster {
 public:
  Raster(int width, int height, Rgb background = {255, 255, 255});
  int width() const { return w_; }
  int height() const { return h_; }
  void set(int x, int y, Rgb c);
  Rgb get(int x, int y) const;
  // Inclusive-exclusive pixel rectangle [x0, x1) × [y0, y1), clipped.
  void fill_rect(int x0, int y0, int x1, int y1, Rgb c);
  void outline_rect(int x0, int y0, int x1, int y1, Rgb c);
  void line(int x0, int y0, int x1, int y1, Rgb c, int thickness = 1);
  // Text with its top-left corner at (x, y); `scale` pixels per font unit.
  void text(int x, int y, const std::string& s, Rgb c, int scale = 2);
  static int text_width(const std::string& s, int scale = 2);
  static int text_height(int scale = 2) { return 7 * scale; }
  // Written atomically; throws FileError.
  void write_png(const std::string& path) const;

 private:
  int w_, h_;
  std::vector<std::uint8_t> px_;
};

}  // namespace semioctree
