#include "semioctree/slice_image.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <stdexcept>

#include "raster.h"

namespace semioctree {

namespace {

Rgb darker(Rgb c, double f) {
  return {std::uint8_t(c.r * f), std::uint8_t(c.g * f), std::uint8_t(c.b * f)};
}

}  // namespace

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
  const int margin = 20, left = 56, title_h = 36, legend_w = 230, bottom = 80;
  Raster img(map_w + left + margin + legend_w, std::max(map_h + title_h + bottom, 520));
  const int ox = left, oy = title_h;
  const double r = tree.leaf_size();
  // Pixel of the world point (x, y): y grows upwards in the world, down in the image.
  auto px = [&](double x) { return ox + int(std::lround((x / r - double(min_cell[0])) * ppl)); };
  auto py = [&](double y) {
    return oy + map_h - int(std::lround((y / r - double(min_cell[1])) * ppl));
  };

  img.fill_rect(ox, oy, ox + map_w, oy + map_h, {235, 235, 235});
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
  auto disc = [&](const Point3& p, Rgb c) {
    const int cx = px(p.x), cy = py(p.y), rad = std::max(4, ppl * 2);
    for (int y = -rad; y <= rad; ++y)
      for (int x = -rad; x <= rad; ++x)
        if (x * x + y * y <= rad * rad) img.set(cx + x, cy + y, c);
  };
  // A label on a white box beside a disc: scans by their index (scan_NN), the NBV.
  auto tag = [&](const Point3& p, const std::string& text, Rgb c) {
    const int x = px(p.x) + std::max(4, ppl * 2) + 3, y = py(p.y) - Raster::text_height() - 2;
    img.fill_rect(x - 2, y - 2, x + Raster::text_width(text) + 2, y + Raster::text_height() + 2,
                  {255, 255, 255});
    img.text(x, y, text, c, 2);
  };
  for (const Point3& s : opt.scans) disc(s, label_color(Label::kScan));
  if (opt.nbv) disc(*opt.nbv, label_color(Label::kNbv));
  for (std::size_t i = 0; i < opt.scans.size(); ++i)
    tag(opt.scans[i], std::to_string(i), label_color(Label::kScan));
  if (opt.nbv) tag(*opt.nbv, "NBV", label_color(Label::kNbv));
  img.outline_rect(ox - 1, oy - 1, ox + map_w + 1, oy + map_h + 1, {0, 0, 0});
  // Axes: map coordinates in metres, a tick every 1, 2, 5 or 10 m.
  const double x_min = double(min_cell[0]) * r, y_min = double(min_cell[1]) * r;
  const double extent = double(std::max(nx, ny)) * r;
  double tick = 1.0;
  for (double t : {2.0, 5.0, 10.0, 20.0})
    if (extent / tick > 15) tick = t;
  for (double x = std::ceil(x_min / tick) * tick; x <= x_min + double(nx) * r + 1e-9; x += tick) {
    const int X = px(x);
    img.fill_rect(X, oy + map_h + 1, X + 1, oy + map_h + 6, {0, 0, 0});
    char t[16];
    std::snprintf(t, sizeof t, "%g", std::abs(x) < 1e-9 ? 0.0 : x);  // never "-0"
    img.text(X - Raster::text_width(t) / 2, oy + map_h + 9, t, {0, 0, 0}, 2);
  }
  for (double y = std::ceil(y_min / tick) * tick; y <= y_min + double(ny) * r + 1e-9; y += tick) {
    const int Y = py(y);
    img.fill_rect(ox - 6, Y, ox - 1, Y + 1, {0, 0, 0});
    char t[16];
    std::snprintf(t, sizeof t, "%g", std::abs(y) < 1e-9 ? 0.0 : y);
    img.text(ox - 9 - Raster::text_width(t), Y - Raster::text_height() / 2, t, {0, 0, 0}, 2);
  }

  // Title.
  char buf[200];
  std::snprintf(buf, sizeof(buf), "%s  cut at z = %.2f m, octants %.2f to %.2f m",
                opt.title.empty() ? "semioctree" : opt.title.c_str(), opt.height,
                tree.coarse_size(), tree.leaf_size());
  img.text(ox, 10, buf, {0, 0, 0}, 2);
  // Scale bar: the largest of 0.5/1/2/5 m that fits in a quarter of the map.
  double bar_m = 0.5;
  for (double m : {1.0, 2.0, 5.0, 10.0})
    if (m / r * ppl <= map_w / 4.0) bar_m = m;
  const int bar_px = int(std::lround(bar_m / r * ppl)), by = oy + map_h + 48;
  img.fill_rect(ox, by, ox + bar_px, by + 6, {0, 0, 0});
  for (int i = 0; i <= 1; ++i)
    img.fill_rect(ox + i * bar_px - (i ? 2 : 0), by - 5, ox + i * bar_px + (i ? 0 : 2), by + 11,
                  {0, 0, 0});
  std::snprintf(buf, sizeof(buf), "%g m      axes: x, y in m (map frame)", bar_m);
  img.text(ox + bar_px + 10, by - 4, buf, {0, 0, 0}, 2);
  // Legend.
  const int lx = ox + map_w + 20;
  int ly = oy;
  for (int l = 1; l < kLabelCount; ++l) {
    const Rgb c = label_color(Label(l));
    img.fill_rect(lx, ly, lx + 22, ly + 18, c);
    img.outline_rect(lx, ly, lx + 22, ly + 18, {0, 0, 0});
    img.text(lx + 30, ly + 2, std::string(kLabelNames[std::size_t(l)]), {0, 0, 0}, 2);
    ly += 28;
  }
  img.fill_rect(lx, ly, lx + 22, ly + 18, {235, 235, 235});
  img.outline_rect(lx, ly, lx + 22, ly + 18, {0, 0, 0});
  img.text(lx + 30, ly + 2, "not mapped", {0, 0, 0}, 2);
  // The disc of `occluded` around a scan position is not a shadow: the scanner
  // measures nothing closer than its minimum range (nor below its lowest
  // elevation) until another scan sees that space.
  ly += 40;
  for (const char* line :
       {"Black dots: scans (index as", "in scan_NN); red: the NBV.", "The occluded disc around a",
        "scan is its blind zone", "(closer than the minimum", "range), not a shadow."}) {
    img.text(lx, ly, line, {0, 0, 0}, 1);
    ly += 12;
  }
  img.write_png(path);
}

}  // namespace semioctree
