// The options `survey` and `nbv` share: the grid, the NBV, the stop threshold,
// decimation, the room's height and threads; and how they fill the survey stage's parameters.
#pragma once

#include <CLI/CLI.hpp>
#include <cstddef>
#include <string>

#include "semioctree/survey.h"

namespace semioctree::cli {

struct PlanningOptions {
  double leaf = 0.05, coarse = 0.8;
  double stop = 0.1;
  int method = 1;
  int level = -1;  // method 2: the level scored (-1: the leaf)
  double candidate_spacing = 0.5;
  std::size_t target_points = 400000;
  unsigned threads = 0;
  std::string scope = "floor";      // SurveyScope: room, floor or map
  double ceiling = 0;               // > 0: the room's height above the floor (--ceiling)
  double min_overlap = -1;          // < 0: registration's own bound (SurveyParams::min_overlap)
  double travel_weight = 0;         // 1/m (NbvParams::travel_weight)
  std::string octants = "sampled";  // sampled or exact (SurveyMapParams::exact_octants)
};
void add_planning_options(CLI::App& cmd, PlanningOptions& o);

// Fills `p` from them (the grid is the semioctree, or with `homogeneous` the grid of
// leaf-size voxels). Set p.map.limits before: they are copied to the NBV. Throws
// std::invalid_argument on a --level the grid lacks.
void apply_planning_options(const PlanningOptions& o, SurveyParams& p, bool homogeneous = false);

}  // namespace semioctree::cli
