// Internal: the occluded targets the NBV scores are counted on (docs/nbv.md,
// "Score": methods 1, 2 and 3).
#pragma once

#include <cstdint>
#include <optional>
#include <vector>

#include "semioctree/nbv/params.h"
#include "semioctree/nbv/room.h"
#include "semioctree/octomap_ext/semioctree.h"

namespace semioctree::nbv_detail {

struct Target {
  Point3 center;
  double weight = 1;
  // Method 3: half the octant's side, and its faces on free space (bit 2a for
  // the face at −half along axis a, bit 2a+1 for the one at +half).
  double half = 0;
  unsigned free_faces = 0;
  // Method 2: minimum-corner leaf cell (relative to the origin) of the level-ℓ
  // cell holding the target.
  std::int64_t cell[3] = {0, 0, 0};
};

// The level the method counts in: method 2's ℓ (kLeafLevel: the leaf), the
// leaf for methods 1 and 3. Throws std::invalid_argument for a method other
// than 1, 2 or 3, or a level finer than the leaf.
unsigned resolve_level(const SemiOcTree& tree, const NbvParams& params);

// Method 1: every occluded octant, weighted by its volume in leaf cells (inside
// `room` only, if given: its part inside).
std::vector<Target> method1_targets(const SemiOcTree& tree, const std::optional<RoomBox>& room);

// Method 2: the occluded level-`level` cells, weight 1, with their `cell`.
std::vector<Target> method2_targets(const SemiOcTree& tree, unsigned level);

// Method 3: the occluded octants with a face on free space, weighted by one
// face's area, with `half` and `free_faces`.
std::vector<Target> method3_targets(const SemiOcTree& tree);

// The targets of params.method; those of methods 2 and 3 centred outside
// params.room (if set) dropped. Throws as resolve_level.
std::vector<Target> targets_for(const SemiOcTree& tree, const NbvParams& params);

// The free faces of a target that have `a` in front of them (beyond the face's plane).
inline unsigned facing_faces(const Target& t, const Point3& a) {
  const double rel[3] = {a.x - t.center.x, a.y - t.center.y, a.z - t.center.z};
  unsigned out = 0;
  for (unsigned axis = 0; axis < 3; ++axis) {
    if (rel[axis] < -t.half) out |= 1u << (2 * axis);
    if (rel[axis] > t.half) out |= 1u << (2 * axis + 1);
  }
  return out & t.free_faces;
}

// Method 3 weight of a target seen from a: the area of its free faces facing a.
inline double facing_area(const Target& t, const Point3& a) {
  return double(__builtin_popcount(facing_faces(t, a))) * t.weight;
}

}  // namespace semioctree::nbv_detail
