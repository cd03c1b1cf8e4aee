#pragma once
// The one way photopose runs independent work items on several threads, and the one reading of a
// thread count (0: every core). For work that splits into items which share nothing but read-only
// inputs and write to their own slots (images, trials, chunks of rows); no other file starts a
// std::thread. Code that hands the threads to a library (Ceres) takes only the count from here.

#include <algorithm>
#include <atomic>
#include <cstddef>
#include <thread>
#include <vector>

namespace photopose {

// The number of threads `num_threads` asks for: itself when positive, else every core the
// machine reports (at least 1).
inline int ResolveThreadCount(int num_threads) {
  if (num_threads > 0) return num_threads;
  return static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
}

// Calls fn(i) for every i in [0, count) on ResolveThreadCount(num_threads) threads, never more
// threads than chunks (the calling thread is one of them). Items are handed out in chunks of
// `chunk_size` consecutive indices (0 counts as 1), in increasing order as threads become free
// (dynamic scheduling: a thread that finishes early takes the next chunk), so fn must only write
// to its own item's slots. Larger chunks cost fewer atomic operations, smaller ones balance
// uneven items better. Returns when every call has returned. fn must not throw.
template <typename Fn>
void ParallelForChunks(size_t count, int num_threads, size_t chunk_size, const Fn& fn) {
  const size_t chunk = std::max<size_t>(1, chunk_size);
  const size_t num_chunks = count / chunk + (count % chunk != 0 ? 1 : 0);
  num_threads = static_cast<int>(
      std::min<size_t>(ResolveThreadCount(num_threads), std::max<size_t>(1, num_chunks)));
  std::atomic<size_t> next{0};
  const auto worker = [&]() {
    for (size_t c = next++; c < num_chunks; c = next++) {
      const size_t begin = c * chunk, end = std::min(count, begin + chunk);
      for (size_t i = begin; i < end; ++i) fn(i);
    }
  };
  std::vector<std::thread> threads;
  threads.reserve(num_threads - 1);
  for (int t = 1; t < num_threads; ++t) threads.emplace_back(worker);
  worker();
  for (std::thread& thread : threads) thread.join();
}

// ParallelForChunks one item at a time.
template <typename Fn>
void ParallelFor(size_t count, int num_threads, const Fn& fn) {
  ParallelForChunks(count, num_threads, 1, fn);
}

}  // namespace photopose
