// Wall-clock timing of the stages (the seconds in survey.json and reports), and the
// process's peak memory beside them.
#pragma once

#include <sys/resource.h>

#include <chrono>

#ifdef __GLIBC__
#include <malloc.h>
#endif

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

// For a program that runs surveys, called once at the start of main: blocks of 1 MiB and
// more are mapped, and unmapped when freed (glibc's M_MMAP_THRESHOLD; a no-op with
// other C libraries). A scan's buffers run to tens of megabytes and are freed each scan;
// glibc's own threshold rises past the size of a freed mapped block and then carves such
// buffers from the heap, whose freed space stays resident (docs/data-flow.md, "Memory").
inline void map_large_allocations() {
#ifdef __GLIBC__
  mallopt(M_MMAP_THRESHOLD, 1 << 20);
#endif
}

}  // namespace semioctree
