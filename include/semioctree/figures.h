// The paper's figures of a discretization: statistics of one run (octants per
// level and label, volume % per label — Table 1 —, memory), and the comparison
// of the semioctree against the homogeneous grid over resolutions: octant
// counts (Fig 15), increment factor per halving (Table 2), as JSON, Markdown
// and a chart (SVG and PNG).
#pragma once

#include <string>
#include <vector>

#include "semioctree/octomap_ext/semioctree.h"
#include "semioctree/openings.h"

namespace semioctree {

struct DiscretizationRun {
  std::string method;  // "semioctree" or "homogeneous"
  double leaf = 0, coarse = 0;
  OctantStatistics stats;
  std::size_t memory_bytes = 0;
  double seconds = 0;
};

// A run's figures from its tree (method from the tree: k = 0 is the homogeneous grid).
DiscretizationRun describe_run(const SemiOcTree& tree, double seconds);

// Volume % per label over all labelled octants (Table 1 columns).
double volume_percent(const OctantStatistics& s, Label l);

// stats.json of one run (written atomically).
void write_run_json(const DiscretizationRun& run, const std::string& path);

// comparison.json, comparison.md and fig15_octants.svg / .png in `dir`. `runs` holds
// both methods at each resolution.
void write_comparison(const std::vector<DiscretizationRun>& runs, const std::string& dir);

// openings.json: kind, 4 corners, width, height, sill and LOS share of each opening.
void write_openings_json(const std::vector<DetectedOpening>& openings, const std::string& path);

// Increment factors count(r/2) / count(r) of one method, runs ordered by
// decreasing resolution size; used by write_comparison and tests.
std::vector<double> increment_factors(const std::vector<DiscretizationRun>& runs_of_one_method);

}  // namespace semioctree
