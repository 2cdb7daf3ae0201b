#include "core/parallel.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <thread>
#include <vector>

#include "core/error.h"
#include "core/random.h"

namespace flowplan {
namespace {

std::vector<double> DrawPerIndex(int threads) {
  std::vector<double> out(1000);
  ParallelFor(1000, threads, [&](int, int i) {
    Rng rng(StreamSeed(11, i));
    out[i] = rng.Normal();
  });
  return out;
}

TEST(ParallelTest, ResultsDoNotDependOnThreadCount) {
  const auto one = DrawPerIndex(1);
  EXPECT_EQ(one, DrawPerIndex(2));
  EXPECT_EQ(one, DrawPerIndex(7));
}

TEST(ParallelTest, EveryIndexRunsOnceOnAValidWorker) {
  std::vector<std::atomic<int>> hits(500);
  std::atomic<bool> bad_worker{false};
  ParallelFor(500, 3, [&](int worker, int i) {
    if (worker < 0 || worker >= 3) bad_worker = true;
    ++hits[i];
  });
  EXPECT_FALSE(bad_worker);
  for (auto& h : hits) EXPECT_EQ(h.load(), 1);
}

TEST(ParallelTest, FirstExceptionIsRethrown) {
  EXPECT_THROW(ParallelFor(100, 2,
                           [](int, int i) {
                             if (i == 17) throw Error("episode 17 failed");
                           }),
               Error);
}

TEST(ParallelTest, ZeroMeansAllCores) {
  EXPECT_EQ(ResolveThreadCount(0), static_cast<int>(std::max(1u, std::thread::hardware_concurrency())));
  EXPECT_EQ(ResolveThreadCount(3), 3);
}

}  // namespace
}  // namespace flowplan
