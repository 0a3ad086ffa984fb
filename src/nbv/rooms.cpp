#include "semioctree/nbv/rooms.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "label_roles.h"
#include "plane_grid.h"

namespace semioctree {

using nbv_detail::cells_at_height;
using nbv_detail::free_space;
using nbv_detail::Plane;
using nbv_detail::plane_over;

namespace {

// How far from an opening's centre its rooms are looked for, each way: past the wall's
// thickness (and the leaf of unseen space often left in front of it).
constexpr double kOpeningReach = 0.5;  // m

// How far an opening's sill line is drawn past its detected edges, in leaves: the
// detection places an edge within a leaf of the jamb, and rays that pass the gap are
// seen directly (empty), which would join the rooms on both sides. Past the jamb the
// line lies in the wall, where nothing is free anyway.
constexpr double kOpeningOverhangLeaves = 2.0;

// Marks the plane cells under each opening that spans `height` (its sill line, drawn
// past both edges) as no room cell: the barrier between the rooms it joins.
void close_openings(std::vector<std::uint8_t>& room_cell, const Plane& plane, double r,
                    double height, const std::vector<DetectedOpening>& openings) {
  for (const DetectedOpening& o : openings) {
    const double bottom = std::min(o.corners[0].z(), o.corners[1].z());
    const double top = std::max(o.corners[2].z(), o.corners[3].z());
    if (!(bottom <= height && height <= top)) continue;
    const Eigen::Vector2d a = o.corners[0].head<2>(), b = o.corners[1].head<2>();
    const double length = (b - a).norm();
    if (!(length > 0)) continue;
    const Eigen::Vector2d u = (b - a) / length;
    const double reach = kOpeningOverhangLeaves * r;
    // Steps of a quarter leaf: every cell the line crosses is met (a 4-connected barrier).
    const int steps = int(std::ceil((length + 2 * reach) / (0.25 * r)));
    for (int i = 0; i <= steps; ++i) {
      const Eigen::Vector2d p = a + (-reach + (length + 2 * reach) * double(i) / steps) * u;
      const std::int64_t x = std::int64_t(std::floor(p.x() / r)) - plane.x0;
      const std::int64_t y = std::int64_t(std::floor(p.y() / r)) - plane.y0;
      if (x >= 0 && y >= 0 && x < plane.nx && y < plane.ny)
        room_cell[plane.index(int(x), int(y))] = 0;
    }
  }
}

// Each room's outline: its cells' edges facing a cell of another room or none, joined
// along rows (edges below and above) and columns (edges left and right). The plane's
// border cells belong to no room, so every neighbour looked at lies on the plane.
void trace_outlines(std::vector<Room>& rooms, const std::vector<std::int32_t>& room_of,
                    const Plane& plane, double r) {
  const auto metres = [r](std::int64_t cell) { return float(double(cell) * r); };
  // Along rows (along = x, across = y) and along columns (along = y, across = x): the
  // edges on either side (side ±1 across) of each run of cells.
  for (const bool rows : {true, false}) {
    const int n_along = rows ? plane.nx : plane.ny, n_across = rows ? plane.ny : plane.nx;
    const std::int64_t o_along = rows ? plane.x0 : plane.y0, o_across = rows ? plane.y0 : plane.x0;
    const auto at = [&](int along, int across) {
      return room_of[rows ? plane.index(along, across) : plane.index(across, along)];
    };
    for (const int side : {-1, 1})
      for (int c = 1; c + 1 < n_across; ++c)
        for (int u = 1; u + 1 < n_along;) {
          const std::int32_t id = at(u, c);
          if (id < 0 || at(u, c + side) == id) {
            ++u;
            continue;
          }
          const int start = u;
          while (u + 1 < n_along && at(u, c) == id && at(u, c + side) != id) ++u;
          const float e = metres(c + o_across + (side > 0 ? 1 : 0));
          const float u0 = metres(start + o_along), u1 = metres(u + o_along);
          rooms[std::size_t(id)].outline.push_back(rows ? std::array<float, 4>{u0, e, u1, e}
                                                        : std::array<float, 4>{e, u0, e, u1});
        }
  }
}

// Each room's cell nearest the centre of its bounds.
void find_inner_points(std::vector<Room>& rooms, const std::vector<std::int32_t>& room_of,
                       const Plane& plane, double r) {
  std::vector<double> best(rooms.size(), std::numeric_limits<double>::infinity());
  for (int y = 0; y < plane.ny; ++y)
    for (int x = 0; x < plane.nx; ++x) {
      const std::int32_t id = room_of[plane.index(x, y)];
      if (id < 0) continue;
      Room& room = rooms[std::size_t(id)];
      const Point3 c((double(x + plane.x0) + 0.5) * r, (double(y + plane.y0) + 0.5) * r, 0.0);
      const double d =
          std::hypot(c.x - 0.5 * (room.min.x + room.max.x), c.y - 0.5 * (room.min.y + room.max.y));
      if (d < best[std::size_t(id)]) best[std::size_t(id)] = d, room.inner = c;
    }
}

}  // namespace

std::optional<std::size_t> RoomMap::room_at(const Point3& p) const {
  if (room_of_.empty()) return std::nullopt;
  const std::int64_t x = std::int64_t(std::floor(p.x / leaf_)) - x0_;
  const std::int64_t y = std::int64_t(std::floor(p.y / leaf_)) - y0_;
  if (x < 0 || y < 0 || x >= nx_ || y >= ny_) return std::nullopt;
  const std::int32_t id = room_of_[std::size_t(y) * std::size_t(nx_) + std::size_t(x)];
  if (id < 0) return std::nullopt;
  return std::size_t(id);
}

std::optional<std::size_t> RoomMap::room_near(const Point3& p, double radius) const {
  if (room_of_.empty()) return std::nullopt;
  const std::int64_t px = std::int64_t(std::floor(p.x / leaf_)) - x0_;
  const std::int64_t py = std::int64_t(std::floor(p.y / leaf_)) - y0_;
  const auto reach = std::int64_t(std::ceil(radius / leaf_));
  std::optional<std::size_t> best;
  std::int64_t best_d2 = 0;
  for (std::int64_t y = std::max<std::int64_t>(0, py - reach);
       y <= std::min<std::int64_t>(ny_ - 1, py + reach); ++y)
    for (std::int64_t x = std::max<std::int64_t>(0, px - reach);
         x <= std::min<std::int64_t>(nx_ - 1, px + reach); ++x) {
      const std::int32_t id = room_of_[std::size_t(y) * std::size_t(nx_) + std::size_t(x)];
      const std::int64_t d2 = (x - px) * (x - px) + (y - py) * (y - py);
      if (id < 0 || double(d2) * leaf_ * leaf_ > radius * radius) continue;
      if (!best || d2 < best_d2) best = std::size_t(id), best_d2 = d2;
    }
  return best;
}

RoomMap segment_rooms(const SemiOcTree& tree, double height, double floor_z, double ceiling_z,
                      const std::vector<DetectedOpening>& openings) {
  RoomMap m;
  if (tree.coarse_count() == 0) return m;
  const double r = tree.leaf_size();
  const Plane plane = plane_over(tree);
  m.leaf_ = r, m.x0_ = plane.x0, m.y0_ = plane.y0, m.nx_ = plane.nx, m.ny_ = plane.ny;
  std::vector<std::uint8_t> free_cell = cells_at_height(
      tree, plane, height, [](Label l) { return free_space(l) || l == Label::kOut; });
  close_openings(free_cell, plane, r, height, openings);
  m.room_of_.assign(plane.cells(), -1);
  std::vector<std::size_t> stack;
  for (int y = 0; y < plane.ny; ++y)
    for (int x = 0; x < plane.nx; ++x) {
      const std::size_t start = plane.index(x, y);
      if (!free_cell[start] || m.room_of_[start] >= 0) continue;
      const auto id = std::int32_t(m.rooms_.size());
      Room room;
      room.min = Point3(double(x + plane.x0) * r, double(y + plane.y0) * r, floor_z);
      room.max = Point3(room.min.x + r, room.min.y + r, ceiling_z);
      m.room_of_[start] = id;
      stack.push_back(start);
      while (!stack.empty()) {
        const std::size_t i = stack.back();
        stack.pop_back();
        ++room.cells;
        const int cx = int(i % std::size_t(plane.nx)), cy = int(i / std::size_t(plane.nx));
        room.min.x = std::min(room.min.x, double(cx + plane.x0) * r);
        room.min.y = std::min(room.min.y, double(cy + plane.y0) * r);
        room.max.x = std::max(room.max.x, double(cx + plane.x0 + 1) * r);
        room.max.y = std::max(room.max.y, double(cy + plane.y0 + 1) * r);
        // The plane's border cells are never free: no bounds checks needed.
        for (const std::size_t j :
             {i + 1, i - 1, i + std::size_t(plane.nx), i - std::size_t(plane.nx)})
          if (free_cell[j] && m.room_of_[j] < 0) {
            m.room_of_[j] = id;
            stack.push_back(j);
          }
      }
      room.area_m2 = double(room.cells) * r * r;
      m.rooms_.push_back(room);
    }
  trace_outlines(m.rooms_, m.room_of_, plane, r);
  find_inner_points(m.rooms_, m.room_of_, plane, r);

  const int steps = int(std::ceil(kOpeningReach / r));
  for (std::size_t i = 0; i < openings.size(); ++i) {
    const DetectedOpening& o = openings[i];
    const Eigen::Vector3d c = o.centre();
    OpeningLink link;
    link.opening = i;
    for (const int side : {1, -1}) {
      std::optional<std::size_t> found;
      for (int s = 1; s <= steps && !found; ++s) {
        const Eigen::Vector3d p = c + double(side * s) * r * o.wall_normal;
        found = m.room_at(Point3(p.x(), p.y(), height));
      }
      (side > 0 ? link.front : link.back) = found;
      if (found) {
        std::vector<std::size_t>& list = m.rooms_[*found].openings;
        if (std::find(list.begin(), list.end(), i) == list.end()) list.push_back(i);
      }
    }
    m.links_.push_back(link);
  }
  return m;
}

}  // namespace semioctree
