#include "semioctree/slice_image.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <stdexcept>

#include "canvas.h"

namespace semioctree {

namespace {

Rgb darker(Rgb c, double f) {
  return {std::uint8_t(c.r * f), std::uint8_t(c.g * f), std::uint8_t(c.b * f)};
}

constexpr Rgb kBlack{0, 0, 0}, kWhite{255, 255, 255}, kNotMapped{235, 235, 235};
constexpr Rgb kRoomOutline{200, 90, 0};

std::string metres(double v) {
  char t[32];
  std::snprintf(t, sizeof t, "%g", std::abs(v) < 1e-9 ? 0.0 : v);  // never "-0"
  return t;
}

}  // namespace

Rgb slice_room_color() {
  return kRoomOutline;
}

void write_slice_png(const SemiOcTree& tree, const std::string& path, const SliceOptions& opt) {
  if (tree.coarse_count() == 0) throw std::invalid_argument("slice of an empty map");
  octomap::OcTreeKey hkey;
  if (!tree.key_of({0, 0, opt.height}, hkey))
    throw std::invalid_argument("slice height out of range");
  // Extent of the coarse grid in xy (leaf cells), from the coarse voxels.
  long min_cell[2] = {1L << 20, 1L << 20}, max_cell[2] = {-(1L << 20), -(1L << 20)};
  const long cells_per_coarse = 1L << tree.leaf_level();
  tree.for_each_coarse([&](const CoarseIndex& c, SemiOcTreeNode*) {
    min_cell[0] = std::min(min_cell[0], long(c.x) * cells_per_coarse);
    min_cell[1] = std::min(min_cell[1], long(c.y) * cells_per_coarse);
    max_cell[0] = std::max(max_cell[0], long(c.x + 1) * cells_per_coarse);
    max_cell[1] = std::max(max_cell[1], long(c.y + 1) * cells_per_coarse);
  });
  const long nx = max_cell[0] - min_cell[0], ny = max_cell[1] - min_cell[1];
  const int ppl = opt.pixels_per_leaf > 0
                      ? opt.pixels_per_leaf
                      : std::max(1, int(std::lround(1200.0 / double(std::max(nx, ny)))));
  const int map_w = int(nx) * ppl, map_h = int(ny) * ppl;
  // The map's top-left corner at (left, title_h); the axes' labels left of and below it,
  // the legend right of it.
  const int margin = 20, left = 56, title_h = 36, legend_w = 250, bottom = 84;
  Canvas img(Canvas::Format::kPng, map_w + left + margin + legend_w,
             std::max(map_h + title_h + bottom, 560));
  const int ox = left, oy = title_h;
  const double r = tree.leaf_size();
  // Pixel of the world point (x, y): y grows upwards in the world, down in the image.
  auto px = [&](double x) { return ox + (x / r - double(min_cell[0])) * ppl; };
  auto py = [&](double y) { return oy + map_h - (y / r - double(min_cell[1])) * ppl; };

  // The octants crossing the cut, in their label colours; antialiasing off so that each
  // octant's square covers whole pixels in exactly its colour.
  img.fill_rect(ox, oy, ox + map_w, oy + map_h, kNotMapped);
  cairo_set_antialias(img.cr(), CAIRO_ANTIALIAS_NONE);
  const unsigned hz = hkey.k[2];
  tree.for_each_octant([&](const Octant& o) {
    const unsigned span = 1u << (tree.leaf_level() - o.level);
    if (!(o.key.k[2] <= hz && hz < o.key.k[2] + span)) return;  // does not cross the cut
    const long cx = leaf_cell(o.key.k[0]) - min_cell[0], cy = leaf_cell(o.key.k[1]) - min_cell[1];
    const int x0 = ox + int(cx) * ppl, x1 = x0 + int(span) * ppl;
    const int y1 = oy + map_h - int(cy) * ppl, y0 = y1 - int(span) * ppl;
    const Rgb c = label_color(o.label());
    img.fill_rect(x0, y0, x1, y1, c);
    if (opt.outlines && span * unsigned(ppl) >= 4)
      img.outline_rect(x0, y0, x1, y1, darker(c, 0.75));
  });
  cairo_set_antialias(img.cr(), CAIRO_ANTIALIAS_DEFAULT);
  img.outline_rect(ox - 1, oy - 1, ox + map_w + 1, oy + map_h + 1, kBlack);

  // Scans (black discs, numbered as scan_NN) joined in their order, and the NBV (red).
  // Discs of a size that reads at any scale (a leaf may be 1 or 30 pixels).
  const double rad = std::clamp(ppl * 2.0, 5.0, 9.0);
  for (const SliceRoom& room : opt.rooms)
    for (const std::array<float, 4>& e : room.outline)
      img.line(px(e[0]), py(e[1]), px(e[2]), py(e[3]), kRoomOutline, 2.5);
  if (opt.routes.empty())
    for (std::size_t i = 0; i + 1 < opt.scans.size(); ++i)
      img.line(px(opt.scans[i].x), py(opt.scans[i].y), px(opt.scans[i + 1].x),
               py(opt.scans[i + 1].y), kBlack, 1.5);
  for (const std::vector<Point3>& route : opt.routes)
    for (std::size_t i = 0; i + 1 < route.size(); ++i)
      img.line(px(route[i].x), py(route[i].y), px(route[i + 1].x), py(route[i + 1].y), kBlack, 1.5);
  if (opt.nbv && !opt.scans.empty()) {
    img.set_dashed(true);
    img.line(px(opt.scans.back().x), py(opt.scans.back().y), px(opt.nbv->x), py(opt.nbv->y),
             label_color(Label::kNbv), 1.5);
    img.set_dashed(false);
  }
  int doors = 0, windows = 0;
  for (const SliceOpening& o : opt.openings) {
    const Rgb c = label_color(o.door ? Label::kDoor : Label::kWindow);
    const double x0 = px(o.from.x), y0 = py(o.from.y), x1 = px(o.to.x), y1 = py(o.to.y);
    img.line(x0, y0, x1, y1, kBlack, std::max(7.0, ppl * 1.6) + 3);
    img.line(x0, y0, x1, y1, c, std::max(7.0, ppl * 1.6));
    const std::string name =
        o.door ? "D" + std::to_string(++doors) : "W" + std::to_string(++windows);
    img.boxed_text((x0 + x1) / 2 + 10, (y0 + y1) / 2 - 12, name, 13, darker(c, 0.8));
  }
  auto tag = [&](const Point3& p, const std::string& text, Rgb c) {
    img.boxed_text(px(p.x) + rad + 3, py(p.y) - rad - 2, text, 13, c);
  };
  for (const Point3& s : opt.scans)
    img.disc(px(s.x), py(s.y), rad, label_color(Label::kScan), kWhite);
  if (opt.nbv) img.disc(px(opt.nbv->x), py(opt.nbv->y), rad, label_color(Label::kNbv), kWhite);
  for (std::size_t i = 0; i < opt.scans.size(); ++i)
    tag(opt.scans[i], std::to_string(i), label_color(Label::kScan));
  if (opt.nbv) tag(*opt.nbv, "NBV", label_color(Label::kNbv));
  for (const SliceRoom& room : opt.rooms)
    img.boxed_text(px(room.label_at.x), py(room.label_at.y), room.label, 12, kRoomOutline);

  // Axes: map coordinates in metres, a tick every 1, 2, 5 or 10 m.
  const double x_min = double(min_cell[0]) * r, y_min = double(min_cell[1]) * r;
  const double extent = double(std::max(nx, ny)) * r;
  double tick = 1.0;
  for (double t : {2.0, 5.0, 10.0, 20.0})
    if (extent / tick > 15) tick = t;
  for (double x = std::ceil(x_min / tick) * tick; x <= x_min + double(nx) * r + 1e-9; x += tick) {
    img.line(px(x), oy + map_h + 1, px(x), oy + map_h + 6, kBlack);
    img.text(px(x), oy + map_h + 16, metres(x), 12, kBlack, 0.5);
  }
  for (double y = std::ceil(y_min / tick) * tick; y <= y_min + double(ny) * r + 1e-9; y += tick) {
    img.line(ox - 6, py(y), ox - 1, py(y), kBlack);
    img.text(ox - 9, py(y), metres(y), 12, kBlack, 1.0);
  }
  img.text(ox + map_w / 2.0, oy + map_h + 34, "x (m, map frame)", 12, kBlack, 0.5);
  img.vertical_text(12, oy + map_h / 2.0, "y (m)", 12, kBlack);

  // Title.
  char buf[240];
  std::snprintf(buf, sizeof(buf), "%s — cut at z = %.2f m, octants %.2f to %.2f m",
                opt.title.empty() ? "semioctree" : opt.title.c_str(), opt.height,
                tree.coarse_size(), tree.leaf_size());
  img.text(ox, 18, buf, 15, kBlack, 0.0, true);
  // Scale bar: the largest of 0.5/1/2/5/10 m that fits in a quarter of the map.
  double bar_m = 0.5;
  for (double m : {1.0, 2.0, 5.0, 10.0})
    if (m / r * ppl <= map_w / 4.0) bar_m = m;
  const double bar_px = bar_m / r * ppl, by = oy + map_h + 60;
  img.fill_rect(ox, by, ox + bar_px / 2, by + 6, kBlack);
  img.fill_rect(ox + bar_px / 2, by, ox + bar_px, by + 6, kWhite);
  img.outline_rect(ox, by, ox + bar_px, by + 6, kBlack);
  img.text(ox, by + 16, "0", 11, kBlack, 0.5);
  img.text(ox + bar_px, by + 16, metres(bar_m) + " m", 11, kBlack, 0.5);

  // Legend.
  const int lx = ox + map_w + 24;
  int ly = oy;
  img.text(lx, ly + 6, "Labels", 13, kBlack, 0.0, true);
  ly += 20;
  auto swatch = [&](Rgb c, const std::string& name) {
    img.fill_rect(lx, ly, lx + 22, ly + 16, c);
    img.outline_rect(lx, ly, lx + 22, ly + 16, kBlack);
    img.text(lx + 30, ly + 8, name, 13, kBlack);
    ly += 24;
  };
  for (int l = 1; l < kLabelCount; ++l)
    if (Label(l) != Label::kScan && Label(l) != Label::kNbv)
      swatch(label_color(Label(l)), std::string(kLabelNames[std::size_t(l)]));
  swatch(kNotMapped, "not mapped (unknown)");
  img.disc(lx + 11, ly + 8, 6, label_color(Label::kScan), kWhite);
  img.text(lx + 30, ly + 8, "scan (number as in scan_NN)", 13, kBlack);
  ly += 24;
  img.disc(lx + 11, ly + 8, 6, label_color(Label::kNbv), kWhite);
  img.text(lx + 30, ly + 8, "next best view (NBV)", 13, kBlack);
  ly += 24;
  img.line(lx, ly + 8, lx + 22, ly + 8, kBlack, 1.5);
  img.text(lx + 30, ly + 8, opt.routes.empty() ? "scans in order" : "the robot's route", 13,
           kBlack);
  ly += 24;
  if (!opt.rooms.empty()) {
    img.line(lx, ly + 8, lx + 22, ly + 8, kRoomOutline, 2.5);
    img.text(lx + 30, ly + 8, "room (as in survey.json)", 13, kBlack);
    ly += 24;
  }
  if (!opt.openings.empty()) {
    img.text(lx, ly + 8, "Bars D1…, W1…: doors and windows", 11, kBlack);
    ly += 15;
    img.text(lx, ly + 8, "found (any height), as in survey.json", 11, kBlack);
    ly += 15;
  }
  ly += 12;
  // The disc of `occluded` around a scan position is not a shadow: the scanner
  // measures nothing closer than its minimum range (nor below its lowest
  // elevation) until another scan sees that space.
  for (const char* line : {"The occluded disc around a scan", "is its blind zone (closer than",
                           "the minimum range), not a shadow."}) {
    img.text(lx, ly, line, 11, {60, 60, 60});
    ly += 15;
  }
  img.write(path);
}

}  // namespace semioctree
