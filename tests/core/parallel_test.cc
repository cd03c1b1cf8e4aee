#include "core/parallel.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <map>
#include <string>
#include <mutex>
#include <set>
#include <thread>
#include <vector>

namespace photopose {
namespace PHOTOPOSE_UNITY_ID {

TEST(ResolveThreadCount, PositiveIsKeptZeroOrLessIsEveryCore) {
  EXPECT_EQ(ResolveThreadCount(1), 1);
  EXPECT_EQ(ResolveThreadCount(7), 7);
  const int cores = static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
  EXPECT_EQ(ResolveThreadCount(0), cores);
  EXPECT_EQ(ResolveThreadCount(-3), cores);
}

TEST(ParallelFor, CallsEveryItemExactlyOnce) {
  for (const int threads : {0, 1, 2, 4, 16}) {
    SCOPED_TRACE(threads);
    constexpr size_t kCount = 1000;
    std::vector<std::atomic<int>> calls(kCount);
    for (auto& c : calls) c = 0;
    ParallelFor(kCount, threads, [&](size_t i) { ++calls[i]; });
    for (size_t i = 0; i < kCount; ++i) ASSERT_EQ(calls[i].load(), 1) << i;
  }
}

TEST(ParallelFor, NoItemsNoCalls) {
  int calls = 0;
  ParallelFor(0, 4, [&](size_t) { ++calls; });
  EXPECT_EQ(calls, 0);
}

TEST(ParallelFor, OneThreadRunsInOrderOnTheCaller) {
  std::vector<size_t> order;
  const std::thread::id caller = std::this_thread::get_id();
  bool elsewhere = false;
  ParallelFor(5, 1, [&](size_t i) {
    order.push_back(i);
    elsewhere |= std::this_thread::get_id() != caller;
  });
  EXPECT_EQ(order, (std::vector<size_t>{0, 1, 2, 3, 4}));
  EXPECT_FALSE(elsewhere);
}

TEST(ParallelFor, NeverMoreThreadsThanItems) {
  std::mutex mutex;
  std::set<std::thread::id> ids;
  ParallelFor(2, 8, [&](size_t) {
    std::lock_guard<std::mutex> lock(mutex);
    ids.insert(std::this_thread::get_id());
  });
  EXPECT_LE(ids.size(), 2u);
  EXPECT_GE(ids.size(), 1u);
}

TEST(ParallelFor, UsesSeveralThreadsWhenAsked) {
  // Two items that each wait for the other to start can only both finish on two threads.
  std::atomic<int> started{0};
  std::atomic<bool> both{true};
  ParallelFor(2, 2, [&](size_t) {
    ++started;
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(10);
    while (started.load() < 2 && std::chrono::steady_clock::now() < deadline)
      std::this_thread::yield();
    if (started.load() < 2) both = false;
  });
  EXPECT_TRUE(both.load());
}

TEST(ParallelForChunks, EveryItemOnceEachChunkOnOneThreadInOrder) {
  constexpr size_t kCount = 1003;  // not a multiple of the chunk sizes
  for (const int threads : {1, 2, 4})
    for (const size_t chunk : {size_t{0}, size_t{1}, size_t{7}, size_t{64}, size_t{5000}}) {
      SCOPED_TRACE(std::to_string(threads) + " threads, chunk " + std::to_string(chunk));
      std::vector<std::atomic<int>> calls(kCount);
      for (auto& c : calls) c = 0;
      std::vector<std::thread::id> thread_of(kCount);
      std::vector<size_t> sequence(kCount);  // per item: its position among its thread's calls
      std::mutex mutex;
      std::map<std::thread::id, size_t> calls_of_thread;
      ParallelForChunks(kCount, threads, chunk, [&](size_t i) {
        ++calls[i];
        std::lock_guard<std::mutex> lock(mutex);
        thread_of[i] = std::this_thread::get_id();
        sequence[i] = calls_of_thread[thread_of[i]]++;
      });
      const size_t step = std::max<size_t>(1, chunk);
      for (size_t i = 0; i < kCount; ++i) {
        ASSERT_EQ(calls[i].load(), 1) << i;
        if (i % step == 0) continue;
        // Within a chunk: the same thread, one call after the other.
        EXPECT_EQ(thread_of[i], thread_of[i - 1]) << i;
        EXPECT_EQ(sequence[i], sequence[i - 1] + 1) << i;
      }
      // Never more threads than chunks.
      EXPECT_LE(calls_of_thread.size(), (kCount + step - 1) / step);
    }
}

TEST(ParallelForChunks, OneChunkRunsOnTheCaller) {
  const std::thread::id caller = std::this_thread::get_id();
  std::atomic<bool> elsewhere{false};
  ParallelForChunks(10, 4, 10, [&](size_t) {
    if (std::this_thread::get_id() != caller) elsewhere = true;
  });
  EXPECT_FALSE(elsewhere.load());
}

}  // namespace PHOTOPOSE_UNITY_ID
}  // namespace photopose
