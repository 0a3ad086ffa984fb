// What the benchmark programs share: the wall-clock timer, the --rounds option, the two
// thread counts every ratio is measured at, and the headline ratios of the JSON.
//
// A ratio compares the same work on the same number of threads: each side is timed with
// 1 thread and with all of the machine's (std::thread::hardware_concurrency()), and the
// ratio is printed for both ("ratio_1_thread", "ratio_all_threads", "threads" saying how
// many "all" is). tests/run_benchmarks.sh collects the "headlines" of every program.
#pragma once

#include <CLI/CLI.hpp>
#include <algorithm>
#include <chrono>
#include <limits>
#include <nlohmann/json.hpp>
#include <string>
#include <thread>
#include <vector>

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

// The shortest of the rounds (0 for none).
inline double best_round(const std::vector<double>& seconds) {
  return seconds.empty() ? 0.0 : *std::min_element(seconds.begin(), seconds.end());
}

// "All threads": one per hardware thread (1 if the count is not known).
inline unsigned all_threads() {
  return std::max(1u, std::thread::hardware_concurrency());
}

// The thread counts every ratio is measured at: 1, then all (once, on a 1-thread machine).
inline std::vector<unsigned> thread_counts() {
  const unsigned all = all_threads();
  return all > 1 ? std::vector<unsigned>{1, all} : std::vector<unsigned>{1};
}

// Seconds of one side at the two thread counts (all_threads == one_thread on a 1-thread
// machine). A side that cannot use more threads than one leaves all_threads at -1.
struct SideSeconds {
  double one_thread = 0;
  double all_threads = -1;
};

// Seconds, or null for a side not timed (≤ 0).
inline nlohmann::ordered_json seconds_or_null(double seconds) {
  return seconds > 0 ? nlohmann::ordered_json(seconds) : nlohmann::ordered_json(nullptr);
}

// baseline / ours, or null when a side was not timed (≤ 0).
inline nlohmann::ordered_json ratio(double baseline_seconds, double our_seconds) {
  if (!(baseline_seconds > 0) || !(our_seconds > 0)) return nullptr;
  return baseline_seconds / our_seconds;
}

// One headline of a benchmark: how many times longer the baseline took than ours on the
// same work, with 1 thread and with all threads. `note` (may be empty) says what a reader
// must know, e.g. that the baseline cannot use more threads: its all-threads ratio is then
// null (never its 1-thread time against ours on all threads) and the 1-thread ratio is
// the headline.
inline nlohmann::ordered_json headline(const std::string& name, const std::string& compares,
                                       const SideSeconds& baseline, const SideSeconds& ours,
                                       const std::string& note = {}) {
  nlohmann::ordered_json h;
  h["name"] = name;
  h["compares"] = compares;
  h["threads"] = all_threads();
  h["ratio_1_thread"] = ratio(baseline.one_thread, ours.one_thread);
  h["ratio_all_threads"] = ratio(baseline.all_threads, ours.all_threads);
  h["baseline_seconds"] = {{"1_thread", seconds_or_null(baseline.one_thread)},
                           {"all_threads", seconds_or_null(baseline.all_threads)}};
  h["ours_seconds"] = {{"1_thread", seconds_or_null(ours.one_thread)},
                       {"all_threads", seconds_or_null(ours.all_threads)}};
  if (!note.empty()) h["note"] = note;
  return h;
}

}  // namespace semioctree::bench
