// Parameters of the Next-Best-View computation (docs/nbv.md).
#pragma once

#include <cstddef>
#include <functional>
#include <optional>

#include "semioctree/nbv/room.h"
#include "semioctree/occlusion.h"
#include "semioctree/octomap_ext/semioctree.h"

namespace semioctree {

struct NbvParams {
  static constexpr unsigned kLeafLevel = ~0u;
  int method = 1;               // 1: all levels, volume-weighted; 2: one level; 3: frontier surface
  unsigned level = kLeafLevel;  // method 2: the level ℓ (kLeafLevel: the tree's leaf)
  double candidate_spacing = 0.5;  // m, rounded to a whole number of leaves (≥ 1)
  // A point the candidate grid passes through: the leaf cell holding it (x, y; z
  // ignored) is a grid point. Empty: the grid points are the leaf cells
  // ≡ m/2 (mod m), m = spacing in leaves. The survey anchors it at its first scan.
  std::optional<Point3> grid_anchor;
  unsigned threads = 0;  // 0: one per core; results do not depend on it
  // Range and elevation limits of the scanner (position ignored): for the
  // score, the stop percentage and the blind zone of past scans.
  ScannerView limits;
  bool blind_zone_is_free = true;  // the blind-zone rule (docs/nbv.md; false: paper only)
  // Unknown or occluded specks enclosed in free space do not block the safety cylinder:
  // a face-connected component of such octants that fits in a cube of this many leaves
  // a side and whose every face neighbour is free space (docs/nbv.md, "Specks in an
  // imported map"). 0: off (the survey's own maps); map-nbv turns it on.
  int enclosed_speck_leaves = 0;
  // The surveyed room (room_box): occluded space outside it is no target and
  // Eq 5 counts volumes inside it only. Empty: the whole map, as the paper reads.
  std::optional<RoomBox> room;
  // Where a candidate may stand (x, y of the scanner): the survey area, a room. Empty:
  // wherever the robot can reach.
  std::function<bool(const Point3&)> may_stand;
  // Candidates may also stand on space seen only through an opening (out): the rooms
  // beyond the doors of a floor survey. false: only on space seen directly.
  bool stand_beyond_openings = false;
  // Lines of sight pass door octants (the scoring's; Eq 5 keeps the paper's rule): a
  // doorway scan looks through the door into the room beyond. false: doors block, as
  // the room's boundary.
  bool see_through_doors = false;
  // Scanner positions in door openings (x, y: the door's centre), tried after the grid
  // points as they are, on door octants too: a scan from a doorway sees both rooms (the
  // floor survey's linking scan into a room not seen yet).
  std::vector<Point3> doorways;
  // Registration-safe candidates (docs/nbv.md): with `overlap_top` set (the map's top,
  // m above its floor at z = 0), the chosen candidate's scan overlap with the map is
  // predicted (predict_overlap, rays `overlap_ray_step_deg` apart, floor and ceiling
  // returns left out), and candidates predicted below `min_overlap` are passed over,
  // best score first, until one is not. Empty: no prediction.
  std::optional<double> overlap_top;
  double min_overlap = 0;  // share, 0-1
  double overlap_ray_step_deg = 1.5;
  // When the targets number at least this many times a prediction's rays, every
  // candidate's overlap is predicted first and only those predicted to register are
  // scored (the same NBV: docs/nbv.md, "Predicted first"); else after scoring, best
  // first. 0: always first; infinity: never.
  double predict_first_factor = 10;
  // The score against the robot's path (docs/nbv.md, "Travel"): candidates are ranked by
  // score · exp(−travel_weight · path) (NbvCandidate::value); 0 (1/m): by the score.
  double travel_weight = 0;
  // Called after each candidate is scored with (candidates scored, candidates),
  // from the scoring threads: it must be thread-safe. Empty: no calls.
  std::function<void(std::size_t, std::size_t)> progress;
};

}  // namespace semioctree
