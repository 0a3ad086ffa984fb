// Point clouds from the synthetic scanner for the commands that accept
// --scene (only built with sim/).
#pragma once

#include <cstdint>
#include <string>

#include "cloud_input.h"
#include "semioctree/sim/ground_truth.h"

namespace semioctree::cli {

// Loads the scene, scans it from the robot's start with the scene's scanner
// (true pose known, so no registration), and preprocesses the cloud.
PreparedCloud scan_scene_at_start(const std::string& scene_path, std::uint64_t seed,
                                  const PreprocessParams& params);

// Throws std::invalid_argument unless the robot's start is on the floor the
// robot can reach (the survey area of `plan`) and clear of obstacles by its
// radius: where `survey` must begin. `scene_path` names the scene in the message.
void check_robot_start(const sim::Scene& scene, const sim::GroundTruth& truth,
                       const sim::FloorPlan& plan, const std::string& scene_path);

}  // namespace semioctree::cli
