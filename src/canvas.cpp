#include "canvas.h"

#include <cairo-svg.h>

#include <ostream>
#include <stdexcept>

#include "semioctree/octomap_ext/file_io.h"

namespace semioctree {

namespace {

constexpr double kPi = 3.14159265358979323846;

cairo_status_t append_to_string(void* closure, const unsigned char* data, unsigned int length) {
  static_cast<std::string*>(closure)->append(reinterpret_cast<const char*>(data), length);
  return CAIRO_STATUS_SUCCESS;
}

cairo_status_t write_to_stream(void* closure, const unsigned char* data, unsigned int length) {
  std::ostream& out = *static_cast<std::ostream*>(closure);
  out.write(reinterpret_cast<const char*>(data), std::streamsize(length));
  return out ? CAIRO_STATUS_SUCCESS : CAIRO_STATUS_WRITE_ERROR;
}

}  // namespace

Canvas::Canvas(Format format, int width, int height)
    : format_(format), width_(width), height_(height) {
  if (width <= 0 || height <= 0) throw std::invalid_argument("canvas of no size");
  surface_ = format == Format::kSvg
                 ? cairo_svg_surface_create_for_stream(append_to_string, &svg_, width, height)
                 : cairo_image_surface_create(CAIRO_FORMAT_RGB24, width, height);
  cr_ = cairo_create(surface_);
  if (cairo_status(cr_) != CAIRO_STATUS_SUCCESS) {
    const std::string why = cairo_status_to_string(cairo_status(cr_));
    cairo_destroy(cr_);
    cairo_surface_destroy(surface_);
    throw std::runtime_error("cairo: cannot create a " + std::to_string(width) + " × " +
                             std::to_string(height) + " canvas: " + why);
  }
  fill_rect(0, 0, width, height, {255, 255, 255});
}

Canvas::~Canvas() {
  cairo_destroy(cr_);
  cairo_surface_destroy(surface_);
}

Canvas::Format Canvas::format_of(const std::string& path) {
  return path.size() >= 4 && path.compare(path.size() - 4, 4, ".svg") == 0 ? Format::kSvg
                                                                           : Format::kPng;
}

void Canvas::set_color(Rgb c, double alpha) {
  cairo_set_source_rgba(cr_, c.r / 255.0, c.g / 255.0, c.b / 255.0, alpha);
}

void Canvas::fill_rect(double x0, double y0, double x1, double y1, Rgb c) {
  set_color(c);
  cairo_rectangle(cr_, x0, y0, x1 - x0, y1 - y0);
  cairo_fill(cr_);
}

void Canvas::outline_rect(double x0, double y0, double x1, double y1, Rgb c, double width) {
  set_color(c);
  cairo_set_line_width(cr_, width);
  const double h = width / 2;
  cairo_rectangle(cr_, x0 + h, y0 + h, x1 - x0 - width, y1 - y0 - width);
  cairo_stroke(cr_);
}

void Canvas::line(double x0, double y0, double x1, double y1, Rgb c, double width) {
  set_color(c);
  cairo_set_line_width(cr_, width);
  cairo_set_line_cap(cr_, CAIRO_LINE_CAP_ROUND);
  cairo_move_to(cr_, x0, y0);
  cairo_line_to(cr_, x1, y1);
  cairo_stroke(cr_);
}

void Canvas::disc(double x, double y, double radius, Rgb fill, Rgb outline) {
  cairo_new_sub_path(cr_);
  cairo_arc(cr_, x, y, radius, 0, 2 * kPi);
  set_color(fill);
  cairo_fill_preserve(cr_);
  set_color(outline);
  cairo_set_line_width(cr_, 1.5);
  cairo_stroke(cr_);
}

void Canvas::text(double x, double y, const std::string& s, double size, Rgb c, double anchor,
                  bool bold) {
  cairo_select_font_face(cr_, "sans-serif", CAIRO_FONT_SLANT_NORMAL,
                         bold ? CAIRO_FONT_WEIGHT_BOLD : CAIRO_FONT_WEIGHT_NORMAL);
  cairo_set_font_size(cr_, size);
  cairo_text_extents_t e;
  cairo_text_extents(cr_, s.c_str(), &e);
  cairo_font_extents_t f;
  cairo_font_extents(cr_, &f);
  set_color(c);
  // Baseline so that the font's ascent and descent are centred on y.
  cairo_move_to(cr_, x - anchor * e.x_advance, y + (f.ascent - f.descent) / 2);
  cairo_show_text(cr_, s.c_str());
  cairo_new_path(cr_);
}

double Canvas::text_width(const std::string& s, double size, bool bold) {
  cairo_select_font_face(cr_, "sans-serif", CAIRO_FONT_SLANT_NORMAL,
                         bold ? CAIRO_FONT_WEIGHT_BOLD : CAIRO_FONT_WEIGHT_NORMAL);
  cairo_set_font_size(cr_, size);
  cairo_text_extents_t e;
  cairo_text_extents(cr_, s.c_str(), &e);
  return e.x_advance;
}

void Canvas::vertical_text(double x, double y, const std::string& s, double size, Rgb c) {
  cairo_save(cr_);
  cairo_translate(cr_, x, y);
  cairo_rotate(cr_, -kPi / 2);
  text(0, 0, s, size, c, 0.5);
  cairo_restore(cr_);
}

void Canvas::boxed_text(double x, double y, const std::string& s, double size, Rgb c) {
  const double w = text_width(s, size, true);
  cairo_rectangle(cr_, x - 2, y - 0.7 * size, w + 4, 1.4 * size);
  set_color({255, 255, 255}, 0.85);
  cairo_fill(cr_);
  text(x, y, s, size, c, 0.0, true);
}

void Canvas::set_dashed(bool dashed) {
  const double pattern[2] = {6, 4};
  cairo_set_dash(cr_, dashed ? pattern : nullptr, dashed ? 2 : 0, 0);
}

void Canvas::write(const std::string& path) {
  cairo_surface_flush(surface_);
  if (format_ == Format::kSvg) {
    cairo_surface_finish(surface_);  // the SVG document is complete only now
    if (cairo_surface_status(surface_) != CAIRO_STATUS_SUCCESS)
      throw FileError(path + ": cairo failed to draw the SVG: " +
                      cairo_status_to_string(cairo_surface_status(surface_)));
    write_file_atomically(path, [&](std::ostream& out) { out << svg_; });
    return;
  }
  write_file_atomically(path, [&](std::ostream& out) {
    const cairo_status_t st = cairo_surface_write_to_png_stream(surface_, write_to_stream, &out);
    if (st != CAIRO_STATUS_SUCCESS)
      throw FileError(path + ": cairo failed to write the PNG: " + cairo_status_to_string(st));
  });
}

}  // namespace semioctree
