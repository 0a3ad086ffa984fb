// Internal: what the NBV makes of each label.
#pragma once

#include "semioctree/octomap_ext/semioctree.h"

namespace semioctree::nbv_detail {

// Space seen empty (markers of scan and NBV positions included).
inline bool free_space(Label l) {
  return l == Label::kEmpty || l == Label::kScan || l == Label::kNbv;
}

// Space a ray passes: seen free, or an opening it looks through (`out`, door, window).
inline bool passable(Label l) {
  return free_space(l) || l == Label::kOut || l == Label::kDoor || l == Label::kWindow;
}

// An octant a line of sight cannot pass: occupied, unknown, door or window (a door
// passes with `doors_pass`: a doorway scan looks through it).
inline bool blocks(Label l, bool doors_pass = false) {
  return l == Label::kOccupied || l == Label::kUnknown || (l == Label::kDoor && !doors_pass) ||
         l == Label::kWindow;
}

}  // namespace semioctree::nbv_detail
