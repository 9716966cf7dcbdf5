// The work split over threads by index (core/parallel.hpp).
#include "core/parallel.hpp"

#include <atomic>
#include <stdexcept>
#include <thread>
#include <vector>

#include <gtest/gtest.h>

namespace accelcal::internal {
namespace {

TEST(ParallelFor, EveryIndexOnceOnItsThread) {
  for (int threads : {1, 2, 3, 8}) {
    for (int n : {0, 1, 2, 5, 100}) {
      std::vector<int> calls(static_cast<std::size_t>(n), 0);
      std::vector<std::thread::id> by(static_cast<std::size_t>(n));
      ParallelFor(n, threads, [&](int i) {
        ++calls[static_cast<std::size_t>(i)];
        by[static_cast<std::size_t>(i)] = std::this_thread::get_id();
      });
      for (int i = 0; i < n; ++i) {
        EXPECT_EQ(calls[static_cast<std::size_t>(i)], 1) << n << " " << threads;
        // The caller takes the indices ≡ 0 (mod the threads used), and the same thread all ≡ i.
        const int used = std::max(1, std::min(threads, n));
        if (i % used == 0) {
          EXPECT_EQ(by[static_cast<std::size_t>(i)], std::this_thread::get_id());
        }
        if (i >= used) {
          EXPECT_EQ(by[static_cast<std::size_t>(i)], by[static_cast<std::size_t>(i - used)]);
        }
      }
    }
  }
}

TEST(ParallelFor, AnExceptionReachesTheCallerAfterEveryThreadEnds) {
  std::atomic<int> done{0};
  const auto f = [&](int i) {
    if (i == 3) throw std::runtime_error("index 3");
    ++done;
  };
  try {
    ParallelFor(10, 2, f);
    FAIL() << "no exception";
  } catch (const std::runtime_error& e) {
    EXPECT_STREQ(e.what(), "index 3");
  }
  // Thread 1 (odd indices) stopped at 3; thread 0 did all five even ones.
  EXPECT_EQ(done.load(), 6);
}

TEST(ThreadCount, AtLeastOneAtMostTheItems) {
  EXPECT_EQ(ThreadCount(4, 2), 2);
  EXPECT_EQ(ThreadCount(1, 100), 1);
  EXPECT_EQ(ThreadCount(3, 100), 3);
  EXPECT_EQ(ThreadCount(0, 0), 1);
  EXPECT_GE(ThreadCount(0, 100), 1);
  EXPECT_LE(ThreadCount(0, 100),
            static_cast<int>(std::max(1u, std::thread::hardware_concurrency())));
}

}  // namespace
}  // namespace accelcal::internal
