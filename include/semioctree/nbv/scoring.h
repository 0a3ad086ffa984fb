// Next-Best-View scores (paper Eq 3–4), the stop percentage (Eq 5) and the
// whole NBV step (docs/nbv.md, "Score", "Stop percentage").
#pragma once

#include <cstddef>
#include <optional>
#include <vector>

#include "semioctree/nbv/candidates.h"
#include "semioctree/nbv/overlap.h"
#include "semioctree/nbv/params.h"
#include "semioctree/nbv/room.h"
#include "semioctree/occlusion.h"
#include "semioctree/octomap_ext/semioctree.h"

namespace semioctree {

struct NbvCandidate {
  Point3 position;  // scanner position: (x, y) of the candidate, z = scanner height
  // Eq 3, in the method's unit: method 1 leaf cells of occluded volume (× leaf³ for
  // m³), method 2 level-ℓ cells, method 3 m² of frontier faces. Compare scores of
  // one method only.
  double score = 0;
  double path_m = 0;  // the robot's shortest path there (find_candidates), m
  // The score weighed by the path (NbvParams::travel_weight): what candidates are ranked
  // by; the score itself with a weight of 0.
  double value = 0;
  // Predicted overlap (NbvParams::overlap_top): set on the candidates tried, best first.
  std::optional<double> predicted_overlap;
};

struct ScoringStats {
  std::size_t targets = 0;           // occluded targets (method 2: level-ℓ cells)
  std::size_t segments = 0;          // candidate–target lines within the scanner's limits
  std::size_t blocked_by_cache = 0;  // of which found blocked without a traversal
  std::size_t blocked_by_walls = 0;  // of which proven blocked on the plane (wall shadows)
  std::size_t visible = 0;           // of which not blocked (score > 0)
  double cpu_seconds = 0;            // CPU time of all scoring threads (hardly load-dependent)
};

struct NbvResult {
  // Highest value (first in grid order on ties) among the candidates whose predicted
  // overlap is not below NbvParams::min_overlap (all, without a prediction). Candidates
  // of score 0 are not predicted; none is best once a better one was passed over.
  // With NbvParams::travel_weight 0, the value is the score (paper Eq 3).
  std::optional<NbvCandidate> best;
  std::vector<NbvCandidate> candidates;  // all feasible candidates, scored, in grid order
  CandidateReport candidate_report;
  ScoringStats scoring;
  // The best one's (NbvParams::overlap_top; none for a best of score 0).
  std::optional<OverlapPrediction> best_overlap;
  std::size_t low_overlap = 0;  // candidates passed over for their predicted overlap
  // From the best candidate; 0 when there is none. Weighed by the path (travel_weight),
  // from the highest-scoring candidate not passed over instead if that is larger: a far
  // view of much hidden space keeps the survey going.
  double stop_percent = 0;
  double seconds_candidates = 0, seconds_scoring = 0, seconds_overlap = 0,
         seconds_stop = 0;  // wall time
};

// Eq 3 score of each scanner position (any positions, feasible or not), in the
// order given. Throws std::invalid_argument for a method other than 1, 2 or 3,
// or a method-2 level finer than the tree's leaf.
std::vector<double> score_positions(const SemiOcTree& tree, const std::vector<Point3>& positions,
                                    const NbvParams& params, ScoringStats* stats = nullptr);

// Candidates (find_candidates), their scores, the best candidate and its stop
// percentage. Throws std::invalid_argument as find_candidates and best_view_among do.
NbvResult next_best_view(const SemiOcTree& tree, const RobotGeometry& robot,
                         const Point3& robot_position, const std::vector<Point3>& past_scans,
                         const NbvParams& params = {});

// The NBV step after the candidates: scores `candidates` (positions and paths as
// find_candidates gives them; scores and predictions are set here), the best one under
// the overlap rule and its stop percentage. candidate_report and seconds_candidates are
// left empty. Throws as score_positions, and std::invalid_argument for a travel_weight < 0.
NbvResult best_view_among(const SemiOcTree& tree, std::vector<NbvCandidate> candidates,
                          const NbvParams& params = {});

// Eq 5 for a scanner at `nbv` (its optical centre), in percent: the method-1
// expected occluded volume seen over the volume of all but unknown space;
// inside `room` only if given. 0 for a map without counted volume.
double stop_percentage(const SemiOcTree& tree, const Point3& nbv, const ScannerView& limits = {},
                       unsigned threads = 0, const std::optional<RoomBox>& room = std::nullopt);

}  // namespace semioctree
