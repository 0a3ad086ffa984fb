// Wall-clock timing of the stages (the seconds in survey.json and reports), and the
// process's peak memory beside them.
#pragma once

#include <sys/resource.h>

#include <chrono>

namespace semioctree {

using Clock = std::chrono::steady_clock;

// Seconds of wall time since `t0`.
inline double seconds_since(Clock::time_point t0) {
  return std::chrono::duration<double>(Clock::now() - t0).count();
}

// The process's peak resident set size so far, in MiB (getrusage; 0 if unavailable).
inline double peak_resident_mib() {
  rusage usage{};
  if (getrusage(RUSAGE_SELF, &usage) != 0) return 0.0;
  return double(usage.ru_maxrss) / 1024.0;  // Linux reports kibibytes
}

}  // namespace semioctree
