// The survey parameters `semioctree survey` uses for a scene, for the benchmarks that
// run the survey stage themselves (bench_floor, bench_update): the scene's robot and
// scanner, the CLI's planning defaults, a scan budget. Needs src/cli on the include path
// and planning_options.cpp linked.
#pragma once

#include <cstddef>

#include "planning_options.h"
#include "semioctree/sim_platform/simulated_platform.h"
#include "semioctree/survey.h"

namespace semioctree::testing {

inline SurveyParams cli_survey_params(const sim::Scene& scene, unsigned threads,
                                      std::size_t max_scans) {
  SurveyParams p;
  sim_platform::apply_scene(scene, p);
  cli::PlanningOptions planning;  // the CLI's defaults
  planning.threads = threads;
  cli::apply_planning_options(planning, p);
  p.max_scans = max_scans;
  return p;
}

}  // namespace semioctree::testing
