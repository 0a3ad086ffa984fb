// Threads of the sim library (internal). The sim library does not use the pipeline's
// helpers, so it keeps its own thread count and fork-join here, once.
#pragma once

#include <algorithm>
#include <thread>
#include <vector>

namespace semioctree::sim::detail {

// `requested`, or one per hardware thread (at least 1) when it is 0.
inline unsigned thread_count(unsigned requested) {
  return requested ? requested : std::max(1u, std::thread::hardware_concurrency());
}

// Runs `job(true)` on the calling thread and `job(false)` on `threads` − 1 more (each
// thread gets its own copy of `job`); returns when all have finished.
template <typename Job>
void run_on_threads(unsigned threads, const Job& job) {
  std::vector<std::thread> pool;
  for (unsigned t = 1; t < threads; ++t) pool.emplace_back(job, false);
  job(true);
  for (auto& t : pool) t.join();
}

}  // namespace semioctree::sim::detail
