// The surveyed room the NBV counts (docs/nbv.md, "Room").
#pragma once

#include <optional>
#include <vector>

#include "semioctree/octomap_ext/semioctree.h"

namespace semioctree {

// An axis-aligned box in the map frame. With NbvParams::room set, the score's
// targets and both volumes of Eq 5 are counted inside it only.
struct RoomBox {
  Point3 min, max;
  // Inside or on the boundary.
  bool contains(const Point3& p) const;
  // Volume of the part of the cube of side `size` centred at `c` inside the box.
  double overlap(const Point3& c, double size) const;
};

// A scanner's own cell is not free until another scan sees it (the blind zone of its
// minimum range): the room it stands in is found from the free cells within this
// distance of it, m.
constexpr double kRoomSeedRadius = 1.0;

// The room the scanners stand in, read from the map: the bounding box of the
// free (empty, scan, nbv) leaf cells of the plane at `height` 4-connected to
// the free cells within kRoomSeedRadius of a scanner, grown by one leaf on each side, from
// floor_z to ceiling_z. std::nullopt when the map is empty, ceiling_z <= floor_z,
// or no scanner has a free cell within 1 m at that height.
std::optional<RoomBox> room_box(const SemiOcTree& tree, const std::vector<Point3>& scanners,
                                double height, double floor_z, double ceiling_z);

}  // namespace semioctree
