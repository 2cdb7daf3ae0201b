#include "datasets/generator.h"

#include <gtest/gtest.h>

#include <cmath>

#include "core/atomic_file.h"
#include "datasets/particle_task.h"
#include "datasets/trajectory_dataset.h"
#include "tests/support/scratch_dir.h"

namespace flowplan::datasets {
namespace {

GenerateOptions Options(int64_t episodes, int threads) {
  GenerateOptions o;
  o.episodes = episodes;
  o.seed = 17;
  o.threads = threads;
  o.config_yaml = "test\n";
  o.show_progress = false;
  return o;
}

TEST(GeneratorTest, ThreadCountDoesNotChangeTheBytes) {
  ParticleCrossTask task{sim::ParticleConfig{}};
  const std::string one = (flowplan::testing::ScratchDir() / "gen_1_thread.h5").string();
  const std::string two = (flowplan::testing::ScratchDir() / "gen_2_threads.h5").string();
  WriteDataset(one, GenerateDataset(task, Options(200, 1)));
  WriteDataset(two, GenerateDataset(task, Options(200, 2)));
  EXPECT_EQ(ReadFile(one), ReadFile(two));
}

TEST(GeneratorTest, MergedShardsEqualTheWholeFile) {
  ParticleCrossTask task{sim::ParticleConfig{}};
  std::vector<TrajectoryDataset> shards;
  for (int k = 0; k < 3; ++k) {
    GenerateOptions o = Options(100, 2);
    o.shard_index = k;
    o.shard_count = 3;
    shards.push_back(GenerateDataset(task, o));
  }
  const std::string whole = (flowplan::testing::ScratchDir() / "gen_whole.h5").string();
  const std::string merged = (flowplan::testing::ScratchDir() / "gen_merged.h5").string();
  WriteDataset(whole, GenerateDataset(task, Options(100, 1)));
  WriteDataset(merged, MergeDatasets(shards, {"s0", "s1", "s2"}));
  EXPECT_EQ(ReadFile(whole), ReadFile(merged));
}

TEST(GeneratorTest, ParticleCrossHasTheXShapeAndEvalPairs) {
  ParticleCrossTask task{sim::ParticleConfig{}};
  const TrajectoryDataset d = GenerateDataset(task, Options(400, 2));
  ASSERT_EQ(d.num_episodes, 400);
  ASSERT_EQ(d.info.horizon, 64);
  ASSERT_EQ(d.info.state_dim(), 4);
  // Each family ends near its commanded goal corner.
  for (int64_t i = 0; i < d.num_episodes; ++i) {
    const float* last = &d.states[(i * 64 + 63) * 4];
    const double gx = d.commanded_goal[i * 2], gy = d.commanded_goal[i * 2 + 1];
    EXPECT_LT(std::hypot(last[0] - gx, last[1] - gy), 0.15) << "episode " << i;
    EXPECT_EQ(d.family[i], i % 2);
    for (int t = 0; t < 64; ++t) {
      const float* s = &d.states[(i * 64 + t) * 4];
      ASSERT_GE(s[0], 0.0f);
      ASSERT_LE(s[0], 1.0f);
    }
  }
  ASSERT_EQ(d.train_pairs.count(), 2);
  ASSERT_EQ(d.test_pairs.count(), 2);
  EXPECT_EQ(d.test_pairs.names[0], "(0,0)->(1,0)");
  EXPECT_EQ(d.test_pairs.names[1], "(0,1)->(1,1)");
  // Test pair 0 starts at (0,0) at rest and ends where family 1 ends, near (1,0).
  EXPECT_FLOAT_EQ(d.test_pairs.start[0], 0.0f);
  EXPECT_FLOAT_EQ(d.test_pairs.start[1], 0.0f);
  EXPECT_NEAR(d.test_pairs.goal[0], 1.0, 0.05);
  EXPECT_NEAR(d.test_pairs.goal[1], 0.0, 0.05);
}

TEST(GeneratorTest, NoiseFreeEpisodesOfAFamilyAreIdentical) {
  sim::ParticleConfig quiet;
  quiet.accel_noise = quiet.position_noise = quiet.start_jitter = 0.0;
  ParticleCrossTask task{quiet};
  const TrajectoryDataset d = GenerateDataset(task, Options(4, 1));
  for (int j = 0; j < 64 * 4; ++j) EXPECT_EQ(d.states[j], d.states[2 * 64 * 4 + j]);
}

}  // namespace
}  // namespace flowplan::datasets
