#include "core/parallel.hpp"

#include <gtest/gtest.h>

#include <atomic>
#include <set>
#include <stdexcept>
#include <thread>
#include <vector>

namespace lasercell {
namespace {

TEST(ParallelForChunks, VisitsEveryIndexOnceForAnyThreadCountAndGrain) {
  for (const int threads : {0, 1, 2, 3, 8}) {
    for (const std::size_t n : {1u, 7u, 64u, 1000u}) {
      for (const std::size_t grain : {0u, 1u, 5u, 64u}) {
        std::vector<std::atomic<int>> seen(n);
        ParallelForChunks(threads, n, grain, [&](std::size_t begin, std::size_t end) {
          for (std::size_t i = begin; i < end; ++i) ++seen[i];
        });
        for (std::size_t i = 0; i < n; ++i)
          ASSERT_EQ(seen[i], 1) << "threads " << threads << " n " << n << " grain " << grain;
      }
    }
  }
}

TEST(ParallelForChunks, SumsByIndexAreTheSameForAnyThreadCount) {
  const std::size_t n = 10000;
  auto run = [&](int threads) {
    std::vector<double> out(n);
    ParallelForChunks(threads, n, 16, [&](std::size_t begin, std::size_t end) {
      for (std::size_t i = begin; i < end; ++i) out[i] = 1.0 / static_cast<double>(i + 1);
    });
    return out;
  };
  const std::vector<double> one = run(1);
  EXPECT_EQ(run(2), one);
  EXPECT_EQ(run(0), one);
  EXPECT_EQ(run(5), one);
}

TEST(ParallelForChunks, AnExceptionInABodyReachesTheCaller) {
  for (const int threads : {1, 2, 0}) {
    EXPECT_THROW(ParallelForChunks(threads, 100, 3,
                                   [](std::size_t begin, std::size_t end) {
                                     for (std::size_t i = begin; i < end; ++i)
                                       if (i == 50) throw std::runtime_error("item 50");
                                   }),
                 std::runtime_error)
        << "threads " << threads;
  }
  // Nothing to do: the body is never called.
  bool called = false;
  ParallelForChunks(2, 0, 4, [&](std::size_t, std::size_t) { called = true; });
  EXPECT_FALSE(called);
}

TEST(WorkerLocal, EachWorkerGetsItsOwnObjectMadeOnce) {
  std::atomic<int> made{0};
  WorkerLocal<std::vector<int>> scratch([&] {
    ++made;
    return std::vector<int>(4, 0);
  });
  std::vector<int> owner(2000, -1);
  ParallelForChunks(2, owner.size(), 10, [&](std::size_t begin, std::size_t end) {
    std::vector<int>& mine = scratch.local();
    // A worker's object is touched by that worker only: the writes race if it were shared.
    for (std::size_t i = begin; i < end; ++i) mine[i % 4] += 1;
    owner[begin] = mine[0];
  });
  EXPECT_GE(made, 1);
  EXPECT_LE(made, static_cast<int>(std::max(2u, std::thread::hardware_concurrency())) + 1);
  // The same thread gets the same object back.
  EXPECT_EQ(&scratch.local(), &scratch.local());
}

}  // namespace
}  // namespace lasercell
