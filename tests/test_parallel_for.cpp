// The worker pool (src/parallel_for.h): every index once, and an exception
// thrown by the loop body reaches the caller and stops the loop.
#include <gtest/gtest.h>

#include <atomic>
#include <cstddef>
#include <new>
#include <stdexcept>
#include <vector>

#include "src/parallel_for.h"

namespace semioctree::detail {
namespace {

TEST(ParallelFor, VisitsEveryIndexOnce) {
  for (unsigned threads : {1u, 2u, 4u}) {
    std::vector<std::atomic<int>> visits(1000);
    std::atomic<bool> bad_worker{false};
    const double cpu = parallel_for(visits.size(), threads, 7, [&](std::size_t i, unsigned w) {
      if (w >= threads) bad_worker = true;
      ++visits[i];
    });
    EXPECT_GE(cpu, 0.0);
    EXPECT_FALSE(bad_worker);
    for (const auto& v : visits) EXPECT_EQ(v.load(), 1) << threads << " threads";
  }
}

struct Failure {
  std::size_t index;
};

TEST(ParallelFor, AnExceptionReachesTheCallerAndStopsTheLoop) {
  const std::size_t n = 1000000, throwing = 10;
  for (unsigned threads : {1u, 2u, 4u}) {
    for (std::size_t chunk : {std::size_t(1), std::size_t(4)}) {
      std::atomic<std::size_t> calls{0};
      try {
        parallel_for(n, threads, chunk, [&](std::size_t i, unsigned) {
          ++calls;
          if (i == throwing) throw Failure{i};
        });
        ADD_FAILURE() << "no exception with " << threads << " threads";
      } catch (const Failure& f) {
        EXPECT_EQ(f.index, throwing);
      }
      // Indices are handed out in order, so the throwing one comes early; the
      // other workers stop at their next index.
      EXPECT_LT(calls.load(), n / 2) << threads << " threads, chunk " << chunk;
      if (threads == 1) {
        EXPECT_EQ(calls.load(), throwing + 1);
      }
    }
  }
}

TEST(ParallelFor, OneOfSeveralExceptionsArrives) {
  for (unsigned threads : {1u, 2u, 4u}) {
    // Every index from 100 on throws; one of them arrives (as a bad_alloc,
    // which scoring can run into), and nothing terminates the program.
    EXPECT_THROW(parallel_for(10000, threads, 16,
                              [&](std::size_t i, unsigned) {
                                if (i >= 100) throw std::bad_alloc();
                              }),
                 std::bad_alloc);
  }
}

TEST(ParallelFor, ThreadCountDefaultsToTheHardware) {
  EXPECT_EQ(thread_count(3), 3u);
  EXPECT_GE(thread_count(0), 1u);
  EXPECT_LE(thread_count(0), 8u);
}

}  // namespace
}  // namespace semioctree::detail
