#include "datasets/trajectory_loader.h"

#include <gtest/gtest.h>

#include "core/error.h"
#include "datasets/generator.h"
#include "tests/support/scratch_dir.h"
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

TEST(LoaderTest, AProcessReadsOnlyItsOwnPartsAndGetsWhatTheWholeSplitHolds) {
  const std::string path = (flowplan::testing::ScratchDir() / "data.h5").string();
  WriteDataset(path, Particles(23));
  const DataConfig config{path, 0.2};
  const TrajectorySplits whole = LoadTrajectorySplits(config, 7);
  ASSERT_EQ(whole.num_train, 19);
  PartSelection parts;
  parts.count = 3;
  parts.mine = {1, 2};
  parts.everything = false;
  const TrajectorySplits some = LoadTrajectorySplits(config, 7, parts);
  EXPECT_FALSE(some.train.defined());
  EXPECT_EQ(some.val.size(0), 0);
  EXPECT_TRUE(some.fingerprint.empty());
  EXPECT_EQ(some.num_train, 19);
  EXPECT_EQ(some.horizon(), whole.horizon());
  EXPECT_EQ(some.state_dim(), whole.state_dim());
  EXPECT_EQ(some.test_pairs.names, whole.test_pairs.names);
  ASSERT_EQ(some.parts, (std::vector<int>{1, 2}));
  // Part p: training episodes p, p + 3, ... of the whole split, read from the file row by row.
  for (size_t k = 0; k < 2; ++k) {
    const torch::Tensor expected = whole.train.slice(0, some.parts[k], 19, 3);
    EXPECT_EQ(some.train_parts[k].size(0), expected.size(0));
    EXPECT_TRUE(torch::equal(some.train_parts[k], expected)) << "part " << some.parts[k];
  }
  // The process that reads everything gets the same parts, plus the whole split.
  parts.everything = true;
  const TrajectorySplits lead = LoadTrajectorySplits(config, 7, parts);
  EXPECT_TRUE(torch::equal(lead.train, whole.train));
  EXPECT_EQ(lead.fingerprint, whole.fingerprint);
  for (size_t k = 0; k < 2; ++k) EXPECT_TRUE(torch::equal(lead.train_parts[k], some.train_parts[k]));
  parts.count = 20;
  parts.mine = {0};
  EXPECT_THROW(LoadTrajectorySplits(config, 7, parts), Error);
}

}  // namespace
}  // namespace flowplan::datasets
