#include "planning_options.h"

#include <stdexcept>
#include <string>

#include "option_checks.h"

namespace semioctree::cli {

void add_planning_options(CLI::App& cmd, PlanningOptions& o) {
  cmd.add_option("--leaf", o.leaf, "leaf (finest octant) size r, m")
      ->check(finite_positive())
      ->capture_default_str();
  cmd.add_option("--coarse", o.coarse, "coarse voxel size L = r*2^k, m")
      ->check(finite_positive())
      ->capture_default_str();
  cmd.add_option("--stop", o.stop, "stop percentage threshold (Eq 5), %")
      ->check(finite_in(0, 100))
      ->capture_default_str();
  cmd.add_option(
         "--method", o.method,
         "NBV scoring: 1 = occluded volume, all levels (paper), 2 = one level (--level), 3 = "
         "area of the occlusion frontier facing the position (surface, ours)")
      ->check(CLI::IsMember({1, 2, 3}))
      ->capture_default_str();
  cmd.add_option("--level", o.level,
                 "method 2: the octree level scored, 0 = coarse voxels ... k = leaf (default: the "
                 "leaf)")
      ->check(whole_in(0, 16));
  cmd.add_option(
         "--candidate-spacing", o.candidate_spacing,
         "spacing of the NBV candidate grid at scanner height (a grid through the first scan "
         "position), m")
      ->check(finite_positive(10))
      ->capture_default_str();
  cmd.add_option("--target-points", o.target_points,
                 "decimate each scan to about this many points (paper: 400 000; 0: keep all; "
                 "else at least 1000)")
      ->check(zero_or_whole_in(1000, 1000000000))
      ->capture_default_str();
  cmd.add_option(
         "--scope", o.scope,
         "what the NBV targets and the stop percentage count: room = the room the scans stand "
         "in (its walls, floor and ceiling; space behind the walls or seen through a window "
         "does not count), the survey ends when it is complete; floor = room by room: the "
         "robot's room until it is complete, then the nearest room it can reach through a door "
         "that is not, until every reachable room is complete; map = the whole map as one "
         "room, as the paper's Eq 5 reads when the grid is the room")
      ->check(CLI::IsMember({"room", "floor", "map"}))
      ->capture_default_str();
  cmd.add_option("--ceiling", o.ceiling,
                 "ceiling height above the floor, m: the map's top (default: the first scan's "
                 "ceiling, or without one the top of its points)")
      ->check(finite_positive(100));
  cmd.add_option("--min-overlap", o.min_overlap,
                 "share (0-1) of a next scan's returns predicted to lie on surfaces already "
                 "mapped, below which a candidate is passed over for the next best (rays every "
                 "1.5 degrees through the map); default: the share registration needs (0.25); 0: "
                 "no prediction limit")
      ->check(finite_in(0, 1));
  cmd.add_option("--travel-weight", o.travel_weight,
                 "λ, 1/m: a candidate's score is weighed by exp(-λ × its path from the robot), "
                 "for surveys where driving costs time; 0: the best score wherever it is")
      ->check(finite_in(0, 100))
      ->capture_default_str();
  cmd.add_option(
         "--octants", o.octants,
         "how the occlusion study labels an octant larger than a leaf: sampled = with the "
         "label its centre and 8 corners agree on (the paper's test; a table leg's shadow "
         "or a slit thinner than the octant can slip between them); exact = only with a "
         "label proven for every point of it, else it is split, so that every leaf gets the "
         "label it would get alone (about 1.5 times the study's time)")
      ->check(CLI::IsMember({"exact", "sampled"}))
      ->capture_default_str();
  cmd.add_option("--threads", o.threads, "worker threads (0: one per core; at most 256)")
      ->check(thread_count())
      ->capture_default_str();
}

void apply_planning_options(const PlanningOptions& o, SurveyParams& p, bool homogeneous) {
  // L = r·2^k, or a clear error (the homogeneous grid's region snaps to L too);
  // the homogeneous grid has one level.
  const unsigned semioctree_k = SemiOcTree::leaf_level_for(o.leaf, o.coarse);
  const unsigned k = homogeneous ? 0 : semioctree_k;
  if (o.level > int(k))
    throw std::invalid_argument("--level " + std::to_string(o.level) +
                                " is finer than the leaf: the grid has levels 0 (coarse voxels) "
                                "to " +
                                std::to_string(k) + " (leaf)");
  if (o.level >= 0 && o.method != 2)
    throw std::invalid_argument("--level applies to --method 2 only");
  // The homogeneous grid spans the same coarse-aligned region as the semioctree.
  p.map.grid = homogeneous ? DiscretizeParams{o.leaf, o.leaf, o.coarse}
                           : DiscretizeParams{o.leaf, o.coarse, 0.0};
  p.map.threads = o.threads;
  p.registration.threads = o.threads;
  p.preprocess.threads = o.threads;
  p.map.exact_octants = o.octants == "exact";
  p.preprocess.target_points = o.target_points;
  p.preprocess.ceiling_height = o.ceiling;
  p.nbv.method = o.method;
  if (o.level >= 0) p.nbv.level = unsigned(o.level);
  p.nbv.candidate_spacing = o.candidate_spacing;
  p.nbv.threads = o.threads;
  p.nbv.limits = p.map.limits;
  p.stop_percent = o.stop;
  p.scope = survey_scope_from_string(o.scope);
  if (o.min_overlap >= 0) p.min_overlap = o.min_overlap;
  p.nbv.travel_weight = o.travel_weight;
}

}  // namespace semioctree::cli
