// Registration of a scan without a pose (no odometry, no pose given): a global
// search over the planar pose (x, y, yaw) of the levelled source in the target's
// frame gives a guess, which register_scan then refines with its usual failure
// bounds. How the search works, why it is planar and what can go wrong:
// docs/registration.md.
#pragma once

#include <Eigen/Geometry>
#include <cstddef>

#include "semioctree/registration.h"
#include "semioctree/scan_io.h"

namespace semioctree {

struct GlobalAlignParams {
  // Cell of the 2-D grid the vertical surfaces are projected on, m. A guess is off by
  // up to half a cell (plus the yaw step's lever, kept at half a cell too), so
  // RegistrationParams::max_correspondence must exceed it: see check in global_align.
  double cell = 0.2;
  // A point is on a vertical surface (wall, cabinet side, column) when its normal's
  // z component is at most this (|n_z| ≤ sin 30°).
  double max_vertical_normal_z = 0.5;
  // Placements screened by a coarse ICP: the best distinct peaks, skipping those
  // that ICP brought to a placement already screened.
  std::size_t hypotheses = 8;
  // Two distinct placements that both pass registration's bounds are told apart when
  // the runner-up's overlap is below this share of the best's; otherwise the scan is
  // ambiguous (RegistrationError).
  double ambiguity_ratio = 0.85;
};

// One placement the search proposed, after the coarse ICP that screened it.
struct GlobalHypothesis {
  double x = 0, y = 0, yaw_deg = 0;  // the search's placement (source → target)
  double votes = 0;      // share of the source's wall cells within a cell of a target wall cell
  std::size_t rank = 0;  // among the distinct peaks by votes (0: most)
  Eigen::Isometry3d screened = Eigen::Isometry3d::Identity();  // after the coarse ICP
  double overlap = 0;  // of the coarse ICP, within 2 × final_correspondence (0: ICP failed)
};

struct GlobalAlignResult {
  // The chosen placement: `guess` from the search and its screening, `icp` its
  // refinement by register_scan (the failure bounds of a scan with a pose), and
  // transform = icp.correction · guess (source → target).
  Eigen::Isometry3d guess = Eigen::Isometry3d::Identity();
  RegistrationResult icp;
  Eigen::Isometry3d transform = Eigen::Isometry3d::Identity();
  std::size_t yaw_steps = 0;  // yaws searched over the full turn
  double yaw_step_deg = 0;
  std::size_t source_cells = 0, target_cells = 0;  // wall cells of the search grid
  std::size_t candidates = 0;                      // distinct peaks of the search
  std::vector<GlobalHypothesis> screened;          // best first (by screened overlap)
  std::size_t chosen = 0;                          // index into `screened`
  std::size_t verified = 0;                        // placements refined by register_scan
  double chosen_overlap = 0;                       // screened[chosen].overlap
  // The best placement distinct from the chosen one: its screened overlap (0: none).
  double runner_up_overlap = 0;
  // Its overlap after register_scan when it passed the bounds (0: it did not, or none).
  double runner_up_refined_overlap = 0;
  double seconds_search = 0, seconds_screen = 0, seconds_verify = 0, seconds = 0;
};

// Places `source` (levelled, floor at z = 0, any x, y, yaw) in `target`'s frame
// (levelled alike): an exhaustive search of yaw and translation over the outline of
// their vertical surfaces, the best distinct placements screened by a coarse ICP,
// then register_scan from the best, with registration's failure bounds.
// Deterministic (no random sampling). Throws RegistrationError when either cloud has
// too few points on vertical surfaces, when no placement passes the bounds, or when a
// placement distinct from the chosen one also passes them with at least
// ambiguity_ratio of its overlap (ambiguous, e.g. a symmetric empty room);
// std::invalid_argument for inconsistent parameters. `facing` (may be null; its
// viewpoint in `source`'s frame): register_scan pairs surfaces facing the same way.
GlobalAlignResult global_align(const Cloud& source, const Cloud& target,
                               const RegistrationParams& registration = {},
                               const GlobalAlignParams& params = {},
                               const SurfaceFacing* facing = nullptr);

}  // namespace semioctree
