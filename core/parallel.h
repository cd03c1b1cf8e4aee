#pragma once
// The one way photopose runs independent work items on several threads: resection of many images
// (solvers/resection/resection.h) and the trials of the comparison tool use it.

#include <algorithm>
#include <atomic>
#include <cstddef>
#include <thread>
#include <vector>

namespace photopose {

// Calls fn(i) for every i in [0, count) on num_threads threads (0: all cores; never more threads
// than items). Items are handed out in increasing order as threads become free, so fn must only
// write to its own item's slots. Returns when every call has returned. fn must not throw.
template <typename Fn>
void ParallelFor(size_t count, int num_threads, const Fn& fn) {
  if (num_threads <= 0) num_threads = static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
  num_threads = static_cast<int>(std::min<size_t>(num_threads, std::max<size_t>(1, count)));
  std::atomic<size_t> next{0};
  const auto worker = [&]() {
    for (size_t i = next++; i < count; i = next++) fn(i);
  };
  std::vector<std::thread> threads;
  threads.reserve(num_threads - 1);
  for (int t = 1; t < num_threads; ++t) threads.emplace_back(worker);
  worker();
  for (std::thread& thread : threads) thread.join();
}

}  // namespace photopose
