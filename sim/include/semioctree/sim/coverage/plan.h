// Survey plans made with perfect knowledge of what each scan position would cover: an
// upper reference for a planner that only knows what it has scanned so far
// (docs/coverage.md, "The planner behind coverage-bound").
#pragma once

#include <cstddef>
#include <vector>

namespace semioctree::sim {

// `covered[v]` holds the covered_samples of a scan from position v (all the same size).
struct CoveragePlan {
  std::vector<std::size_t> views;  // positions, in scan order; views[0] is the given first
  double percent = 0.0;            // samples covered by their union, % of all samples
};

// Greedy: after `first`, each scan is the position that adds most samples (lowest index on
// ties), until `scans` scans or until no position adds a sample (the plan is then shorter
// than `scans`: every position is in it or adds nothing). Throws std::invalid_argument on
// empty or unequal sets or a `first` out of range.
CoveragePlan greedy_coverage_plan(const std::vector<std::vector<bool>>& covered, std::size_t first,
                                  std::size_t scans);

// Local search from `plan`: replaces one scan (never views[0]) at a time by the position
// that covers most together with the others, while that strictly improves the union. Covers
// at least as much as `plan`; a local optimum. Throws std::invalid_argument as above or on
// an empty plan.
CoveragePlan improve_coverage_plan(const std::vector<std::vector<bool>>& covered,
                                   CoveragePlan plan);

}  // namespace semioctree::sim
