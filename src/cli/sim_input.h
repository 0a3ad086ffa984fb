// Point clouds from the synthetic scanner for the commands that accept
// --scene (only built with sim/).
#pragma once

#include <cstdint>
#include <string>

#include "cloud_input.h"

namespace semioctree::cli {

// Loads the scene, scans it from the robot's start with the scene's scanner
// (true pose known, so no registration), and preprocesses the cloud.
PreparedCloud scan_scene_at_start(const std::string& scene_path, std::uint64_t seed,
                                  const PreprocessParams& params);

}  // namespace semioctree::cli
