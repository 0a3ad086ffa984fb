// Internal: the worker pool of the occlusion study and the NBV scorer.
#pragma once

#include <time.h>

#include <algorithm>
#include <atomic>
#include <cstddef>
#include <cstdint>
#include <exception>
#include <mutex>
#include <thread>
#include <vector>

namespace semioctree::detail {

// `requested`, or one per hardware thread (at most 8) when it is 0.
inline unsigned thread_count(unsigned requested) {
  if (requested > 0) return requested;
  return std::max(1u, std::min(8u, std::thread::hardware_concurrency()));
}

inline double thread_cpu_seconds() {
  timespec ts{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return double(ts.tv_sec) + 1e-9 * double(ts.tv_nsec);
}

// Calls f(i, worker) for i in [0, n) on up to `threads` workers (worker <
// threads), in chunks handed out in order; f must only write to slots of its
// own i (or of its worker). Returns the CPU time of all workers (seconds),
// which unlike the wall time hardly depends on the machine's load.
// The first exception thrown by f stops the loop (no worker starts another i)
// and is rethrown here once every worker has ended. A worker thread that
// cannot be started leaves its share to the others.
template <class F>
double parallel_for(std::size_t n, unsigned threads, std::size_t chunk, F&& f) {
  std::atomic<std::size_t> next{0};
  std::atomic<std::int64_t> cpu_ns{0};
  std::atomic<bool> failed{false};
  std::exception_ptr error;  // the first exception of f, set under error_mutex
  std::mutex error_mutex;
  auto work = [&](unsigned worker) {
    const double c0 = thread_cpu_seconds();
    try {
      for (std::size_t i;
           !failed.load(std::memory_order_relaxed) && (i = next.fetch_add(chunk)) < n;)
        for (std::size_t j = i; j < std::min(i + chunk, n); ++j) {
          if (failed.load(std::memory_order_relaxed)) break;
          f(j, worker);
        }
    } catch (...) {
      std::lock_guard<std::mutex> lock(error_mutex);
      if (!error) error = std::current_exception();
      failed.store(true, std::memory_order_relaxed);
    }
    cpu_ns += std::int64_t((thread_cpu_seconds() - c0) * 1e9);
  };
  std::vector<std::thread> pool;
  const unsigned t = static_cast<unsigned>(std::min<std::size_t>(threads, (n + chunk - 1) / chunk));
  try {
    pool.reserve(t);
    for (unsigned i = 1; i < t; ++i) pool.emplace_back(work, i);
  } catch (...) {  // no thread (or no memory for one): fewer workers
  }
  work(0);
  for (auto& th : pool) th.join();
  if (error) std::rethrow_exception(error);
  return 1e-9 * double(cpu_ns.load());
}

}  // namespace semioctree::detail
