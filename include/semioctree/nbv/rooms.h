// Rooms of a map: its free space on the horizontal plane at scanner height, split into
// regions by walls and by the doors and windows found in them (docs/nbv.md, "Rooms").
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <vector>

#include "semioctree/octomap_ext/semioctree.h"
#include "semioctree/openings.h"

namespace semioctree {

// One region of free leaf cells, 4-connected on the plane.
struct Room {
  std::size_t cells = 0;              // free leaf cells on the plane
  double area_m2 = 0;                 // cells × leaf²
  Point3 min, max;                    // its cells' bounds (x, y); z: the floor and ceiling given
  std::vector<std::size_t> openings;  // openings (indices into those given) on its border
  // Its border on the plane: the edges between its cells and the others, each a segment
  // (x0, y0, x1, y1 in metres) joined along its row or column of cells.
  std::vector<std::array<float, 4>> outline;
  Point3 inner;  // the centre of its cell nearest the centre of its bounds (z: 0)
};

// An opening and the rooms on its two sides (none: no room within reach there, e.g.
// space seen through a window that is not free at the plane's height).
struct OpeningLink {
  std::size_t opening = 0;
  std::optional<std::size_t> front, back;  // along the opening's wall normal, then against it
};

class RoomMap {
 public:
  const std::vector<Room>& rooms() const { return rooms_; }
  const std::vector<OpeningLink>& links() const { return links_; }
  // The room whose free cell holds p (x, y; z ignored); none elsewhere.
  std::optional<std::size_t> room_at(const Point3& p) const;
  // The room of the room cell nearest p (x, y) within `radius` m (centre to centre; ties
  // in grid order); none without one. A scanner's own cell is not free until another
  // scan sees it (its blind zone): its room is the one around it.
  std::optional<std::size_t> room_near(const Point3& p, double radius) const;

 private:
  friend RoomMap segment_rooms(const SemiOcTree&, double, double, double,
                               const std::vector<DetectedOpening>&);
  double leaf_ = 0;
  std::int64_t x0_ = 0, y0_ = 0;  // cell (x, y) is leaf column (x + x0, y + y0)
  int nx_ = 0, ny_ = 0;
  std::vector<std::int32_t> room_of_;  // per cell: room index, −1 for none
  std::vector<Room> rooms_;
  std::vector<OpeningLink> links_;
};

// The rooms of `tree` on the plane z = `height` (the scanner's height): the 4-connected
// components of its leaf cells whose octant there is free (empty, scan, nbv) or seen
// only through an opening (out). Walls, and door and window octants, separate them.
// Rooms are numbered in grid order of their first cell (y, then x). Each of `openings`
// is linked to the room on either side of it: the first room met within half a metre
// of its centre (x, y) along its wall normal, each way. A map without coarse voxels
// gives no rooms.
RoomMap segment_rooms(const SemiOcTree& tree, double height, double floor_z, double ceiling_z,
                      const std::vector<DetectedOpening>& openings = {});

}  // namespace semioctree
