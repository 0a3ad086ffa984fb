// Wall-clock timing of the stages (the seconds in survey.json and reports).
#pragma once

#include <chrono>

namespace semioctree {

using Clock = std::chrono::steady_clock;

// Seconds of wall time since `t0`.
inline double seconds_since(Clock::time_point t0) {
  return std::chrono::duration<double>(Clock::now() - t0).count();
}

}  // namespace semioctree
