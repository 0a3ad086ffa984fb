// Wall tests of the visibility rule that need no ray query (docs/coverage.md, "Wall
// culling").
#include "coverage/wall_culling.h"

#include <algorithm>
#include <cmath>
#include <cstddef>

namespace semioctree::sim::detail {

namespace {

// Tolerances of the wall tests. A crossing within kHoleEps of a hole counts as in it:
// a segment that passes that close to the hole's edge is either through it or blocked by
// the jamb, and the tolerance takes the ray caster's float rounding out of the choice.
constexpr double kHoleEps = 1e-3;
constexpr double kFaceMargin = 1e-3;  // "certainly on the solid": this far inside a face
constexpr double kEndMargin = 2e-3;   // and the segment's ends this far beyond the faces

bool in_hole(const WallSlab& w, double u, double z) {
  for (const WallSlab::Rect& h : w.holes)
    if (u >= h.u0 - kHoleEps && u <= h.u1 + kHoleEps && z >= h.z0 - kHoleEps &&
        z <= h.z1 + kHoleEps)
      return true;
  return false;
}

bool inside_face(const WallSlab& w, double u, double z) {
  return u >= kFaceMargin && u <= w.length - kFaceMargin && z >= w.z0 + kFaceMargin &&
         z <= w.z1 - kFaceMargin;
}

// True if every segment from the box to `target` crosses both faces of `w` inside the
// face rectangle, with the box kEndMargin or more beyond the face on the far side
// (`wt`: the target's offset from w's centre plane).
bool box_cut_off_by(const WallSlab& w, const Eigen::Vector3d& target, double wt,
                    const PositionBox& box) {
  if (std::abs(wt) < w.half + kEndMargin) return false;
  const double side = wt > 0 ? 1.0 : -1.0;
  for (const auto& k : box.corners) {
    const double wk = w.normal.dot(k - w.origin);
    if (side * wk > -(w.half + kEndMargin)) return false;
    for (double face : {-w.half, w.half}) {
      const Eigen::Vector3d q = target + (face - wt) / (wk - wt) * (k - target);
      if (!inside_face(w, w.along.dot(q - w.origin), q.z())) return false;
    }
  }
  return true;
}

}  // namespace

std::vector<WallSlab> wall_slabs(const Scene& scene) {
  std::vector<WallSlab> out;
  out.reserve(scene.walls.size());
  for (const Wall& w : scene.walls) {
    // A wall of no length keeps a zero normal: no segment crosses it.
    const double length = w.length();
    const Eigen::Vector2d d = length > 0 ? w.direction() : Eigen::Vector2d::Zero();
    const Eigen::Vector2d n(-d.y(), d.x());
    out.push_back({{w.from.x(), w.from.y(), 0.0},
                   {d.x(), d.y(), 0.0},
                   {n.x(), n.y(), 0.0},
                   length,
                   w.z0,
                   w.z1,
                   std::max(0.0, w.thickness / 2),
                   {}});
  }
  for (const OpeningRect& r : opening_rects(scene)) {
    if (r.wall < 0 || static_cast<std::size_t>(r.wall) >= out.size()) continue;
    WallSlab& w = out[static_cast<std::size_t>(r.wall)];
    const double ua = w.along.dot(r.corners[0] - w.origin);
    const double ub = w.along.dot(r.corners[1] - w.origin);
    // The part of the opening within the wall (as the wall's mesh cuts it).
    const WallSlab::Rect h{std::max(0.0, std::min(ua, ub)), std::min(w.length, std::max(ua, ub)),
                           std::max(w.z0, r.corners[0].z()), std::min(w.z1, r.corners[3].z())};
    if (h.u1 > h.u0 && h.z1 > h.z0) w.holes.push_back(h);
  }
  return out;
}

void wall_offsets(const std::vector<WallSlab>& walls, const Eigen::Vector3d& p, double* out) {
  for (std::size_t k = 0; k < walls.size(); ++k) out[k] = walls[k].normal.dot(p - walls[k].origin);
}

// `opening`: the segment leaves the wall's slab towards b through holes only: b lies
// strictly beyond a face, a short of that face (in the room on the other side, or inside
// the slab: a position standing in a doorway), and every face the segment crosses it
// crosses within a hole of that wall. An end b inside the slab (a jamb, a sill) is not
// beyond: the segment enters the hole without leaving it. `solid`: the ends lie
// kEndMargin or more beyond the faces and the segment crosses a face kFaceMargin or more
// inside the face's rectangle and outside every hole, so that the ray caster (float
// coordinates, first and last millimetre not tested) reports that hit too.
AtWalls at_walls(const std::vector<WallSlab>& walls, const Eigen::Vector3d& a, const double* wa,
                 const Eigen::Vector3d& b, const double* wb, bool find_solid) {
  for (std::size_t k = 0; k < walls.size(); ++k) {
    const WallSlab& w = walls[k];
    const double side = wb[k] > 0 ? 1.0 : -1.0;  // the face on b's side is side · half
    const bool leaves_towards_b = side * wb[k] > w.half && side * wa[k] < w.half;
    const bool crosses_both = leaves_towards_b && side * wa[k] < -w.half;
    const bool test_opening = leaves_towards_b && !w.holes.empty();
    const bool test_solid = find_solid && crosses_both;
    if (!test_opening && !test_solid) continue;
    bool in_holes = true, on_solid = false;
    for (double face : {side * w.half, -side * w.half}) {
      if (face != side * w.half && !crosses_both) break;  // a is inside the slab
      const Eigen::Vector3d q = a + (face - wa[k]) / (wb[k] - wa[k]) * (b - a);
      const double u = w.along.dot(q - w.origin), z = q.z();
      const bool hole = in_hole(w, u, z);
      in_holes = in_holes && hole;
      on_solid = on_solid || (!hole && inside_face(w, u, z));
    }
    if (test_opening && in_holes) return AtWalls::opening;
    if (test_solid && on_solid && std::min(wa[k], wb[k]) <= -w.half - kEndMargin &&
        std::max(wa[k], wb[k]) >= w.half + kEndMargin)
      return AtWalls::solid;
  }
  return AtWalls::nothing_known;
}

PositionBox box_of(const std::vector<Eigen::Vector3d>& positions,
                   const std::vector<std::uint32_t>& members) {
  Eigen::Vector3d lo = positions[members.front()], hi = lo;
  for (std::uint32_t m : members) {
    lo = lo.cwiseMin(positions[m]);
    hi = hi.cwiseMax(positions[m]);
  }
  PositionBox box;
  for (int k = 0; k < 8; ++k) {
    const Eigen::Vector3d c((k & 1 ? hi : lo).x(), (k & 2 ? hi : lo).y(), (k & 4 ? hi : lo).z());
    if (std::find(box.corners.begin(), box.corners.end(), c) == box.corners.end())
      box.corners.push_back(c);
  }
  return box;
}

// The crossings of a face plane by the segments from the box are the hull of the
// corners' crossings (a central projection keeps convexity), and the face rectangle is
// convex, so the corners decide; so do they for facing (a half-space).
bool hidden_from_box(const SurfaceSample& sample, const Eigen::Vector3d& target,
                     const double* target_offsets, const PositionBox& box,
                     const std::vector<WallSlab>& walls) {
  bool faces = false;
  for (const auto& k : box.corners) faces = faces || sample.normal.dot(k - sample.position) > 0;
  if (!faces) return true;
  for (std::size_t i = 0; i < walls.size(); ++i)
    if (box_cut_off_by(walls[i], target, target_offsets[i], box)) return true;
  return false;
}

}  // namespace semioctree::sim::detail
