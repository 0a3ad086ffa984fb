// What the benchmark programs share: the wall-clock timer and the --rounds option.
#pragma once

#include <CLI/CLI.hpp>
#include <chrono>
#include <limits>

namespace semioctree::bench {

inline double seconds_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

// --rounds R (R ≥ 1): each method is timed R times and its best round reported.
inline void add_rounds_option(CLI::App& app, int& rounds) {
  app.add_option("--rounds", rounds,
                 "number of timed rounds; the best (shortest) round of each method is reported")
      ->check(CLI::Range(1, std::numeric_limits<int>::max(), "POSITIVE"))
      ->capture_default_str();
}

}  // namespace semioctree::bench
