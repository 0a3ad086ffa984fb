#include "raster.h"

#include <png.h>
#include <stb/stb_easy_font.h>

#include <algorithm>
#include <cstdlib>
#include <ostream>

#include "semioctree/octomap_ext/file_io.h"

namespace semioctree {

Raster::Raster(int width, int height, Rgb bg)
    : w_(width), h_(height), px_(std::size_t(width) * height * 3) {
  for (std::size_t i = 0; i < px_.size(); i += 3) {
    px_[i] = bg.r;
    px_[i + 1] = bg.g;
    px_[i + 2] = bg.b;
  }
}

void Raster::set(int x, int y, Rgb c) {
  if (x < 0 || y < 0 || x >= w_ || y >= h_) return;
  std::uint8_t* p = &px_[(std::size_t(y) * w_ + x) * 3];
  p[0] = c.r;
  p[1] = c.g;
  p[2] = c.b;
}

Rgb Raster::get(int x, int y) const {
  const std::uint8_t* p = &px_[(std::size_t(y) * w_ + x) * 3];
  return {p[0], p[1], p[2]};
}

void Raster::fill_rect(int x0, int y0, int x1, int y1, Rgb c) {
  x0 = std::max(x0, 0);
  y0 = std::max(y0, 0);
  x1 = std::min(x1, w_);
  y1 = std::min(y1, h_);
  for (int y = y0; y < y1; ++y)
    for (int x = x0; x < x1; ++x) set(x, y, c);
}

void Raster::outline_rect(int x0, int y0, int x1, int y1, Rgb c) {
  for (int x = x0; x < x1; ++x) {
    set(x, y0, c);
    set(x, y1 - 1, c);
  }
  for (int y = y0; y < y1; ++y) {
    set(x0, y, c);
    set(x1 - 1, y, c);
  }
}

void Raster::line(int x0, int y0, int x1, int y1, Rgb c, int thickness) {
  // Bresenham, with a square brush for thickness.
  const int dx = std::abs(x1 - x0), sx = x0 < x1 ? 1 : -1;
  const int dy = -std::abs(y1 - y0), sy = y0 < y1 ? 1 : -1;
  int err = dx + dy;
  const int r0 = -(thickness - 1) / 2, r1 = thickness / 2;
  for (;;) {
    for (int oy = r0; oy <= r1; ++oy)
      for (int ox = r0; ox <= r1; ++ox) set(x0 + ox, y0 + oy, c);
    if (x0 == x1 && y0 == y1) break;
    const int e2 = 2 * err;
    if (e2 >= dy) {
      err += dy;
      x0 += sx;
    }
    if (e2 <= dx) {
      err += dx;
      y0 += sy;
    }
  }
}

void Raster::text(int x, int y, const std::string& s, Rgb c, int scale) {
  static thread_local std::vector<char> buffer(1 << 16);
  std::string copy = s;
  unsigned char color[4] = {c.r, c.g, c.b, 255};
  const int quads =
      stb_easy_font_print(0, 0, copy.data(), color, buffer.data(), int(buffer.size()));
  // Each vertex: x, y, z (float) and 4 colour bytes; 4 vertices per quad.
  for (int q = 0; q < quads; ++q) {
    const float* v0 = reinterpret_cast<const float*>(buffer.data() + q * 4 * 16);
    const float* v2 = reinterpret_cast<const float*>(buffer.data() + q * 4 * 16 + 2 * 16);
    fill_rect(x + int(v0[0] * scale), y + int(v0[1] * scale), x + int(v2[0] * scale),
              y + int(v2[1] * scale), c);
  }
}

int Raster::text_width(const std::string& s, int scale) {
  std::string copy = s;
  return stb_easy_font_width(copy.data()) * scale;
}

void Raster::write_png(const std::string& path) const {
  write_file_atomically(path, [&](std::ostream& out) {
    png_structp png = png_create_write_struct(PNG_LIBPNG_VER_STRING, nullptr, nullptr, nullptr);
    png_infop info = png ? png_create_info_struct(png) : nullptr;
    if (!png || !info) throw FileError(path + ": cannot initialise libpng");
    if (setjmp(png_jmpbuf(png))) {
      png_destroy_write_struct(&png, &info);
      throw FileError(path + ": libpng failed to write the image");
    }
    png_set_write_fn(
        png, &out,
        [](png_structp p, png_bytep data, png_size_t n) {
          static_cast<std::ostream*>(png_get_io_ptr(p))
              ->write(reinterpret_cast<const char*>(data), std::streamsize(n));
        },
        [](png_structp p) { static_cast<std::ostream*>(png_get_io_ptr(p))->flush(); });
    png_set_IHDR(png, info, png_uint_32(w_), png_uint_32(h_), 8, PNG_COLOR_TYPE_RGB,
                 PNG_INTERLACE_NONE, PNG_COMPRESSION_TYPE_DEFAULT, PNG_FILTER_TYPE_DEFAULT);
    png_write_info(png, info);
    for (int y = 0; y < h_; ++y)
      png_write_row(png, const_cast<png_bytep>(&px_[std::size_t(y) * w_ * 3]));
    png_write_end(png, nullptr);
    png_destroy_write_struct(&png, &info);
  });
}

}  // namespace semioctree
