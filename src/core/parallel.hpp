#pragma once
// Independent work split over threads by index (the Monte Carlo's runs, the held-out validation's
// sums and fits). Each index is computed whole by one thread into its own slot, so what comes out
// is the same bits for every thread count.

#include <algorithm>
#include <exception>
#include <system_error>
#include <thread>
#include <vector>

namespace accelcal::internal {

/// Threads to use for `items` independent pieces of work when `requested` were asked for (0: one
/// per hardware thread): at least 1, at most `items`.
inline int ThreadCount(int requested, int items) {
  const int hardware = static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
  return std::max(1, std::min(items, requested > 0 ? requested : hardware));
}

/// Calls f(i) for every i in [0, n) on `threads` threads: the caller's, taking i ≡ 0 (mod threads),
/// and threads − 1 started, thread t taking i ≡ t. Returns when all are done; an exception thrown
/// by f is rethrown then (the first thread's in that order). Indices of a thread that cannot be
/// started are done by the caller.
template <class F>
void ParallelFor(int n, int threads, const F& f) {
  threads = std::max(1, std::min(threads, n));
  std::vector<std::exception_ptr> failed(static_cast<std::size_t>(threads));
  const auto work = [&](int first) {
    try {
      for (int i = first; i < n; i += threads) f(i);
    } catch (...) {
      failed[static_cast<std::size_t>(first)] = std::current_exception();
    }
  };
  std::vector<std::thread> pool;
  std::vector<int> unstarted;
  for (int t = 1; t < threads; ++t) {
    try {
      pool.emplace_back(work, t);
    } catch (const std::system_error&) {
      unstarted.push_back(t);
    }
  }
  work(0);
  for (int t : unstarted) work(t);
  for (std::thread& thread : pool) thread.join();
  for (const std::exception_ptr& e : failed) {
    if (e) std::rethrow_exception(e);
  }
}

}  // namespace accelcal::internal
