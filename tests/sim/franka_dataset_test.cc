#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "core/atomic_file.h"
#include "core/config.h"
#include "core/error.h"
#include "datasets/franka_task.h"
#include "datasets/generate_config.h"
#include "datasets/generator.h"
#include "datasets/trajectory_dataset.h"
#include "sim/franka_self_collision.h"
#include "tests/support/scratch_dir.h"

namespace flowplan::datasets {
namespace {

using ::testing::HasSubstr;

GenerateOptions Options(int64_t episodes, int threads) {
  GenerateOptions o;
  o.episodes = episodes;
  o.seed = 23;
  o.threads = threads;
  o.config_yaml = "test\n";
  o.show_progress = false;
  return o;
}

TEST(FrankaDatasetTest, ThreadCountDoesNotChangeTheBytes) {
  FrankaTask task(FrankaGoals::kCross, FrankaTaskConfig{});
  const std::string one = (flowplan::testing::ScratchDir() / "franka_1_thread.h5").string();
  const std::string two = (flowplan::testing::ScratchDir() / "franka_2_threads.h5").string();
  WriteDataset(one, GenerateDataset(task, Options(16, 1)));
  WriteDataset(two, GenerateDataset(task, Options(16, 2)));
  EXPECT_EQ(ReadFile(one), ReadFile(two));
}

TEST(FrankaDatasetTest, MergedShardsEqualTheWholeFile) {
  FrankaTaskConfig config;
  config.rollout.augmentation.scheme = sim::Augmentation::kRandomPosition;  // IK per episode
  FrankaTask task(FrankaGoals::kCross, config);
  std::vector<TrajectoryDataset> shards;
  for (int k = 0; k < 3; ++k) {
    GenerateOptions o = Options(12, 2);
    o.shard_index = k;
    o.shard_count = 3;
    shards.push_back(GenerateDataset(task, o));
  }
  const std::string whole = (flowplan::testing::ScratchDir() / "franka_whole.h5").string();
  const std::string merged = (flowplan::testing::ScratchDir() / "franka_merged.h5").string();
  WriteDataset(whole, GenerateDataset(task, Options(12, 1)));
  WriteDataset(merged, MergeDatasets(shards, {"s0", "s1", "s2"}));
  EXPECT_EQ(ReadFile(whole), ReadFile(merged));
}

TEST(FrankaDatasetTest, CrossLayoutFamiliesAndEvaluationPairs) {
  FrankaTask task(FrankaGoals::kCross, FrankaTaskConfig{});
  const TrajectoryDataset d = GenerateDataset(task, Options(8, 2));
  EXPECT_EQ(d.info.env, "franka");
  EXPECT_DOUBLE_EQ(d.info.dt, 1.0 / 15.0);
  ASSERT_EQ(d.num_episodes, 8);
  ASSERT_EQ(d.info.horizon, 64);
  ASSERT_EQ(d.info.state_dim(), 14);
  EXPECT_EQ(d.info.state_labels.front(), "q1");
  EXPECT_EQ(d.info.state_labels.back(), "dq7");
  ASSERT_EQ(d.point_dim, 3);
  EXPECT_EQ(d.extras.count("tcp"), 1u);
  EXPECT_EQ(d.extras.count("torques"), 1u);
  EXPECT_EQ(d.extras.count("external_force"), 0u);
  EXPECT_EQ(d.extras.at("torques").shape, (std::vector<int64_t>{8, 64, 7}));
  const auto& tcp = d.extras.at("tcp").values;
  for (int64_t i = 0; i < d.num_episodes; ++i) {
    EXPECT_EQ(d.family[i], i % 2);
    EXPECT_EQ(d.commanded_start[3 * i], 0.5);
    EXPECT_EQ(d.commanded_start[3 * i + 1], -0.3);
    const size_t last = static_cast<size_t>((i * 64 + 63) * 3);
    const Eigen::Vector3d end(tcp[last], tcp[last + 1], tcp[last + 2]);
    const Eigen::Vector3d goal(d.commanded_goal[3 * i], d.commanded_goal[3 * i + 1], d.commanded_goal[3 * i + 2]);
    EXPECT_LT((end - goal).norm(), 0.03) << "episode " << i;
  }
  ASSERT_EQ(d.train_pairs.count(), 2);
  ASSERT_EQ(d.test_pairs.count(), 2);
  EXPECT_EQ(d.train_pairs.names[0], "(0.5,-0.3,0.2)->(0.5,0.3,0.6)");
  EXPECT_EQ(d.test_pairs.names[0], "(0.5,-0.3,0.2)->(0.5,0.3,0.2)");
  EXPECT_EQ(d.test_pairs.names[1], "(0.5,-0.3,0.6)->(0.5,0.3,0.6)");
  // Pair states start at rest.
  for (int j = 7; j < 14; ++j) EXPECT_EQ(d.test_pairs.start[j], 0.0f);
}

TEST(FrankaDatasetTest, ReachDrawsReachablePointsInTheBox) {
  FrankaTaskConfig config;
  config.rollout.augmentation.scheme = sim::Augmentation::kRandomForce;
  // Gentle pushes: at the preset's 15-20 N most reach episodes exceed a joint's velocity limit.
  config.rollout.augmentation.force_range = {2.0, 4.0};
  FrankaTask task(FrankaGoals::kReach, config);
  EXPECT_TRUE(task.Families().empty());
  const TrajectoryDataset d = GenerateDataset(task, Options(6, 2));
  EXPECT_EQ(d.extras.count("external_force"), 1u);
  EXPECT_EQ(d.train_pairs.count(), 0);
  for (int64_t i = 0; i < d.num_episodes; ++i) {
    EXPECT_EQ(d.family[i], -1);
    for (int k = 0; k < 3; ++k) {
      EXPECT_GE(d.commanded_goal[3 * i + k], config.reach_lower[k]);
      EXPECT_LE(d.commanded_goal[3 * i + k], config.reach_upper[k]);
    }
  }
}

TEST(FrankaDatasetTest, JointMotionsStayInsideTheLimitsAndClearOfTheArmAndTheFloor) {
  FrankaTaskConfig config;
  FrankaTask task(FrankaGoals::kJoint, config);
  EXPECT_TRUE(task.Families().empty());
  EXPECT_EQ(task.Layout().point_dim, 7);
  const TrajectoryDataset d = GenerateDataset(task, Options(12, 2));
  ASSERT_GE(d.num_episodes, 11);  // a rollout may still be rejected as too fast
  const sim::FrankaModel model = sim::LoadFrankaModel();
  const sim::FrankaLimits& limits = model.limits();
  const sim::FrankaCollisionModel collision_model(config.floor_height);
  sim::FrankaCollisionChecker checker(collision_model);
  double largest_move = 0.0, final_speed = 0.0;
  for (int64_t i = 0; i < d.num_episodes; ++i) {
    const double* start = &d.commanded_start[static_cast<size_t>(7 * i)];
    const double* goal = &d.commanded_goal[static_cast<size_t>(7 * i)];
    const float* states = &d.states[static_cast<size_t>(i * 64 * 14)];
    for (int j = 0; j < 7; ++j) {
      EXPECT_GE(start[j], limits.q_lower[j] + config.joint_margin);
      EXPECT_LE(goal[j], limits.q_upper[j] - config.joint_margin);
      EXPECT_NEAR(states[j], start[j], 1e-6) << "episode " << i;     // starts at the start
      EXPECT_EQ(states[7 + j], 0.0f);                                 // at rest
      EXPECT_NEAR(states[63 * 14 + j], goal[j], 0.05) << "episode " << i << ", joint " << j + 1;
      EXPECT_LT(std::abs(states[63 * 14 + 7 + j]), 0.6);             // held at the goal, under torque noise
      final_speed += std::abs(states[63 * 14 + 7 + j]) / (7.0 * static_cast<double>(d.num_episodes));
      largest_move = std::max(largest_move, std::abs(goal[j] - start[j]));
    }
    for (int t = 0; t < 64; ++t) {
      sim::JointVector q;
      for (int j = 0; j < 7; ++j) {
        q[j] = states[t * 14 + j];
        ASSERT_LE(std::abs(states[t * 14 + 7 + j]), limits.velocity[j]);
      }
      EXPECT_EQ(checker.FirstCollision(q), "") << "episode " << i << ", state " << t;
    }
  }
  EXPECT_GT(largest_move, 1.0);  // spread over the joint space, not a neighbourhood
  EXPECT_LT(final_speed, 0.1);   // rad/s, mean over episodes and joints
  const std::string one = (flowplan::testing::ScratchDir() / "joint_1_thread.h5").string();
  const std::string two = (flowplan::testing::ScratchDir() / "joint_2_threads.h5").string();
  WriteDataset(one, GenerateDataset(task, Options(6, 1)));
  WriteDataset(two, GenerateDataset(task, Options(6, 2)));
  EXPECT_EQ(ReadFile(one), ReadFile(two));
}

TEST(FrankaDatasetTest, JointSettingsThatCannotWorkNameTheirKey) {
  FrankaTaskConfig config;
  config.joint_margin = 1.6;  // joint 4's range is 3.0 rad
  EXPECT_THAT([&] { FrankaTask(FrankaGoals::kJoint, config, "generate.franka"); },
              ::testing::ThrowsMessage<Error>(HasSubstr("generate.franka.joint_margin: expected less than half of joint 4")));
  config = FrankaTaskConfig{};
  config.joint_motion.min_duration = 4.0;
  EXPECT_THAT([&] { FrankaTask(FrankaGoals::kJoint, config, "generate.franka"); },
              ::testing::ThrowsMessage<Error>(HasSubstr("generate.franka.joint_motion.min_duration: expected at most")));
}

TEST(FrankaDatasetTest, UnreachableBoxRejectsEveryEpisodeWithAReason) {
  FrankaTaskConfig config;
  config.reach_lower = {1.5, 0.0, 0.5};
  config.reach_upper = {1.6, 0.1, 0.6};
  config.max_draws = 2;
  FrankaTask task(FrankaGoals::kReach, config);
  EXPECT_THAT([&] { GenerateDataset(task, Options(3, 1)); },
              ::testing::ThrowsMessage<Error>(HasSubstr(
                  "all 3 episodes were rejected (first reason: no start/goal pair reachable with the gripper "
                  "down in 2 draws)")));
}

TEST(FrankaDatasetTest, UnreachableCrossPointIsNamedWithItsKey) {
  FrankaTaskConfig config;
  config.cross_goals[1] = {2.0, 0.0, 0.5};
  EXPECT_THAT([&] { FrankaTask(FrankaGoals::kCross, config); },
              ::testing::ThrowsMessage<Error>(AllOf(HasSubstr("generate.franka.cross_goals[1]"),
                                                    HasSubstr("target (2.0, 0.0, 0.5) is unreachable"))));
  config = FrankaTaskConfig{};
  config.cross_goals.pop_back();
  EXPECT_THAT([&] { FrankaTask(FrankaGoals::kCross, config); },
              ::testing::ThrowsMessage<Error>(HasSubstr("generate.franka.cross_goals: expected one goal per start")));
}

TEST(FrankaDatasetTest, BadConfigValuesNameTheirKey) {
  GenerateConfig config;
  const YAML::Node yaml = config::ParseYamlText(
      "dataset: franka_cross\nfranka:\n  augmentation:\n    torque_noise_sigma: [1, 1, 1, -1, 0.1, 0.1, 0.1]\n",
      "configs/bad.yaml");
  EXPECT_THAT([&] { config::Apply(yaml, config, "configs/bad.yaml"); },
              ::testing::ThrowsMessage<Error>(
                  HasSubstr("configs/bad.yaml:4: franka.augmentation.torque_noise_sigma[3]: expected a "
                            "non-negative value, got \"-1\"")));
  const YAML::Node scheme = config::ParseYamlText("franka:\n  augmentation:\n    scheme: loud\n", "x.yaml");
  EXPECT_THAT([&] { config::Apply(scheme, config, "x.yaml"); },
              ::testing::ThrowsMessage<Error>(HasSubstr("franka.augmentation.scheme: expected one of per_joint_noise")));

  GenerateConfig reversed;
  reversed.dataset = DatasetKind::kFrankaReach;
  reversed.franka.reach_lower[2] = 0.9;
  EXPECT_THAT([&] { MakeTask(reversed); },
              ::testing::ThrowsMessage<Error>(HasSubstr("generate.franka.reach_lower[2]: expected at most")));
}

TEST(FrankaDatasetTest, ConfigRoundTripsThroughYaml) {
  GenerateConfig config;
  config.dataset = DatasetKind::kFrankaCross;
  config.franka.rollout.augmentation.scheme = sim::Augmentation::kSameNoise;
  config.franka.rollout.controller.max_speed = std::numeric_limits<double>::infinity();
  GenerateConfig back;
  config::Apply(config::ParseYamlText(config::ToYaml(config), "round"), back, "round");
  EXPECT_EQ(config::ToYaml(back), config::ToYaml(config));
  EXPECT_EQ(back.franka.rollout.augmentation.scheme, sim::Augmentation::kSameNoise);
}

TEST(FrankaDatasetTest, ShippedConfigsLoadAndGenerate) {
  for (const char* name : {"franka_cross", "franka_reach", "franka_cross_same_noise", "franka_cross_no_noise",
                           "franka_cross_random_pos", "franka_cross_random_forces"}) {
    const std::string path = std::string(FLOWPLAN_SOURCE_DIR) + "/configs/" + name + ".yaml";
    const YAML::Node root = config::ParseYamlFile(path);
    GenerateConfig generate;
    config::Apply(root["generate"], generate, path);
    EXPECT_EQ(generate.out, std::string("data/") + name + ".h5") << path;
    EXPECT_EQ(root["data"]["path"].as<std::string>(), generate.out) << path;
    EXPECT_EQ(generate.episodes, 10000) << path;
    const std::unique_ptr<EpisodeTask> task = MakeTask(generate);
    const TrajectoryDataset d = GenerateDataset(*task, Options(8, 2));
    ASSERT_GT(d.num_episodes, 0) << path;
    // Kept episodes obey the arm's velocity limits (recorded states included).
    const sim::FrankaLimits limits = sim::LoadFrankaModel().limits();
    for (int64_t i = 0; i < d.num_episodes * d.info.horizon; ++i) {
      for (int j = 0; j < 7; ++j) {
        ASSERT_LE(std::abs(d.states[static_cast<size_t>(i * 14 + 7 + j)]), limits.velocity[j] + 1e-6)
            << path << ", joint " << j + 1;
      }
    }
    EXPECT_EQ(d.extras.count("external_force") == 1,
              generate.franka.rollout.augmentation.scheme == sim::Augmentation::kRandomForce)
        << path;
  }
  const std::string joint = std::string(FLOWPLAN_SOURCE_DIR) + "/configs/franka_joint.yaml";
  GenerateConfig generate;
  config::Apply(config::ParseYamlFile(joint)["generate"], generate, joint);
  EXPECT_EQ(generate.dataset, DatasetKind::kFrankaJoint);
  EXPECT_GT(GenerateDataset(*MakeTask(generate), Options(4, 2)).num_episodes, 0);
}

}  // namespace
}  // namespace flowplan::datasets
