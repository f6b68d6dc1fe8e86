#include "combabc/core/thread_pool.hpp"

#include <gtest/gtest.h>

#include <atomic>
#include <stdexcept>

namespace combabc {
namespace {

TEST(ThreadPool, EveryIndexRunsExactlyOnce) {
  for (int threads : {1, 2, 4}) {
    ThreadPool pool(threads);
    for (std::size_t n : {1u, 7u, 1000u}) {
      std::vector<std::atomic<int>> hits(n);
      pool.ParallelFor(n, 3, [&](std::size_t b, std::size_t e) {
        for (std::size_t i = b; i < e; ++i) hits[i]++;
      });
      for (auto& h : hits) EXPECT_EQ(h.load(), 1);
    }
  }
}

TEST(ThreadPool, RethrowsTheBodysException) {
  ThreadPool pool(2);
  EXPECT_THROW(pool.ParallelFor(100,
                                1,
                                [](std::size_t b, std::size_t) {
                                  if (b == 37) throw std::runtime_error("boom");
                                }),
               std::runtime_error);
  // Still usable afterwards.
  std::atomic<int> count{0};
  pool.ParallelFor(10, 1, [&](std::size_t, std::size_t) { count++; });
  EXPECT_EQ(count.load(), 10);
}

}  // namespace
}  // namespace combabc
