#include "core/parallel.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <mutex>
#include <set>
#include <thread>
#include <vector>

namespace photopose {
namespace {

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

}  // namespace
}  // namespace photopose
