#include "datasets/trajectory_loader.h"

#include <gtest/gtest.h>

#include "datasets/generator.h"
#include "datasets/particle_task.h"

namespace flowplan::datasets {
namespace {

TrajectoryDataset Particles(int64_t n) {
  ParticleCrossTask task{sim::ParticleConfig{}};
  GenerateOptions o;
  o.episodes = n;
  o.seed = 5;
  o.show_progress = false;
  return GenerateDataset(task, o);
}

TEST(LoaderTest, SplitIsAPartitionOfTheEpisodes) {
  const TrajectoryDataset d = Particles(100);
  const TrajectorySplits s = SplitTrajectories(d, 0.1, 3, "test");
  ASSERT_EQ(s.train.sizes(), (std::vector<int64_t>{90, 64, 4}));
  ASSERT_EQ(s.val.sizes(), (std::vector<int64_t>{10, 64, 4}));
  // Every episode appears exactly once across the two splits.
  const torch::Tensor all = torch::cat({s.train, s.val}).reshape({100, -1});
  const torch::Tensor original = torch::from_blob(const_cast<float*>(d.states.data()), {100, 64 * 4});
  for (int64_t i = 0; i < 100; ++i) {
    const torch::Tensor matches = (all == original[i]).all(1);
    EXPECT_EQ(matches.sum().item<int64_t>(), 1) << "episode " << i;
  }
}

TEST(LoaderTest, SplitDependsOnSeedOnly) {
  const TrajectoryDataset d = Particles(50);
  EXPECT_TRUE(torch::equal(SplitTrajectories(d, 0.2, 9, "t").val, SplitTrajectories(d, 0.2, 9, "t").val));
  EXPECT_FALSE(torch::equal(SplitTrajectories(d, 0.2, 9, "t").val, SplitTrajectories(d, 0.2, 10, "t").val));
}

TEST(LoaderTest, EvalPairsBecomeTensors) {
  const TrajectorySplits s = SplitTrajectories(Particles(10), 0.0, 1, "t");
  EXPECT_EQ(s.val.size(0), 0);
  EXPECT_EQ(s.test_pairs.start.sizes(), (std::vector<int64_t>{2, 4}));
  EXPECT_EQ(s.test_pairs.names.size(), 2u);
}

}  // namespace
}  // namespace flowplan::datasets
