#include "semioctree/nbv/room.h"

#include <algorithm>
#include <cmath>
#include <cstdint>

#include "label_roles.h"
#include "plane_grid.h"

namespace semioctree {

using nbv_detail::cells_at_height;
using nbv_detail::flood_fill_4;
using nbv_detail::free_space;
using nbv_detail::Plane;
using nbv_detail::plane_over;

bool RoomBox::contains(const Point3& p) const {
  return p.x >= min.x && p.x <= max.x && p.y >= min.y && p.y <= max.y && p.z >= min.z &&
         p.z <= max.z;
}

double RoomBox::overlap(const Point3& c, double size) const {
  const double h = 0.5 * size;
  auto along = [h](double lo, double hi, double v) {
    return std::max(0.0, std::min(hi, v + h) - std::max(lo, v - h));
  };
  return along(min.x, max.x, c.x) * along(min.y, max.y, c.y) * along(min.z, max.z, c.z);
}

std::optional<RoomBox> room_box(const SemiOcTree& tree, const std::vector<Point3>& scanners,
                                double height, double floor_z, double ceiling_z) {
  if (tree.coarse_count() == 0 || !(ceiling_z > floor_z)) return std::nullopt;
  const double r = tree.leaf_size();
  const Plane plane = plane_over(tree);
  const std::int64_t x0 = plane.x0, y0 = plane.y0, nx = plane.nx, ny = plane.ny;
  const std::vector<std::uint8_t> free_cell = cells_at_height(tree, plane, height, free_space);
  auto idx = [&](std::int64_t x, std::int64_t y) { return plane.index(int(x), int(y)); };
  // Seeds: the free cells within kRoomSeedRadius of each scanner.
  const std::int64_t reach = std::llround(std::ceil(kRoomSeedRadius / r));
  std::vector<std::size_t> seeds;
  for (const Point3& s : scanners) {
    octomap::OcTreeKey key;
    if (!tree.key_of(Point3(s.x, s.y, height), key)) continue;
    const std::int64_t sx = leaf_cell(key.k[0]) - x0;
    const std::int64_t sy = leaf_cell(key.k[1]) - y0;
    for (std::int64_t y = sy - reach; y <= sy + reach; ++y)
      for (std::int64_t x = sx - reach; x <= sx + reach; ++x) {
        if (x < 0 || y < 0 || x >= nx || y >= ny || !free_cell[idx(x, y)]) continue;
        if ((x - sx) * (x - sx) + (y - sy) * (y - sy) > reach * reach) continue;
        seeds.push_back(idx(x, y));
      }
  }
  if (seeds.empty()) return std::nullopt;
  const std::vector<std::uint8_t> reached = flood_fill_4(
      std::size_t(nx), std::size_t(ny), seeds, [&](std::size_t j) { return free_cell[j] != 0; });
  std::int64_t bx0 = nx, by0 = ny, bx1 = -1, by1 = -1;
  for (std::int64_t y = 0; y < ny; ++y)
    for (std::int64_t x = 0; x < nx; ++x)
      if (reached[idx(x, y)])
        bx0 = std::min(bx0, x), by0 = std::min(by0, y), bx1 = std::max(bx1, x),
        by1 = std::max(by1, y);
  // Cells bx0..bx1 span [bx0, bx1 + 1) leaves; one more leaf on each side.
  RoomBox box;
  box.min = Point3(double(bx0 + x0 - 1) * r, double(by0 + y0 - 1) * r, floor_z);
  box.max = Point3(double(bx1 + x0 + 2) * r, double(by1 + y0 + 2) * r, ceiling_z);
  return box;
}

}  // namespace semioctree
