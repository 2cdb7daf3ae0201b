#include "sim/franka_rollout.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "core/error.h"
#include "sim/franka_ik.h"

namespace flowplan::sim {
namespace {

using ::testing::HasSubstr;

class FrankaRolloutTest : public ::testing::Test {
 protected:
  void SetUp() override {
    model_.SetPhysics(config_.physics_timestep(), config_.integrator);
    MjDataPtr d = MakeData(model_.mj());
    start_q_ = SolveTcpIkOrThrow(model_, *d, start_, FrankaReadyPose());
  }

  Eigen::Vector3d LastTcp(const FrankaEpisode& e) const {
    const size_t t = static_cast<size_t>(config_.horizon - 1);
    return {e.tcp[3 * t], e.tcp[3 * t + 1], e.tcp[3 * t + 2]};
  }

  FrankaRolloutConfig config_;
  FrankaModel model_ = LoadFrankaModel();
  Eigen::Vector3d start_{0.5, -0.3, 0.2};
  Eigen::Vector3d goal_{0.5, 0.3, 0.6};
  JointVector start_q_;
};

TEST_F(FrankaRolloutTest, NoiseFreeControllerReachesTheTargetInAStraightLine) {
  FrankaSimulator simulator(model_, config_);
  FrankaEpisode episode;
  Rng rng(1);
  simulator.Rollout(start_q_, goal_, Augmentation::kNone, rng, &episode);
  ASSERT_FALSE(episode.rejected) << episode.reject_reason;
  EXPECT_EQ(episode.states.size(), 64u * 14);
  EXPECT_EQ(episode.physics_steps, 63 * 2 * 2);
  EXPECT_EQ(episode.warnings, 0);
  EXPECT_LT((LastTcp(episode) - goal_).norm(), 0.02);
  // The first state is the IK configuration at rest.
  for (int j = 0; j < 7; ++j) {
    EXPECT_EQ(episode.states[j], start_q_[j]);
    EXPECT_EQ(episode.states[7 + j], 0.0);
  }
  // With J̇q̇ compensation the TCP stays close to the start-goal segment.
  const Eigen::Vector3d direction = (goal_ - start_).normalized();
  for (int t = 0; t < 64; ++t) {
    const Eigen::Vector3d p(episode.tcp[3 * t], episode.tcp[3 * t + 1], episode.tcp[3 * t + 2]);
    const Eigen::Vector3d off = (p - start_) - (p - start_).dot(direction) * direction;
    EXPECT_LT(off.norm(), 0.01) << "state " << t;
  }
}

TEST_F(FrankaRolloutTest, PerJointNoiseIsIndependentAndSameNoiseIsShared) {
  // State 0 is the same rest pose under every scheme, so the first recorded
  // torque differs from the noise-free one by exactly the first step's noise:
  // sigma_j z_j with independent z_j, or sigma_j z with one z for every joint.
  FrankaSimulator simulator(model_, config_);
  auto first_noise = [&](Augmentation scheme) {  // (7,) noise / sigma of the first physics step
    FrankaEpisode none, noisy;
    Rng rng_none(4), rng(4);
    simulator.Rollout(start_q_, goal_, Augmentation::kNone, rng_none, &none);
    simulator.Rollout(start_q_, goal_, scheme, rng, &noisy);
    std::vector<double> z(7);
    for (int j = 0; j < 7; ++j) {
      z[j] = (noisy.torques[j] - none.torques[j]) / config_.augmentation.torque_noise_sigma[j];
    }
    return z;
  };
  const std::vector<double> shared = first_noise(Augmentation::kSameNoise);
  const std::vector<double> independent = first_noise(Augmentation::kPerJointNoise);
  double spread_shared = 0.0, spread_independent = 0.0;
  for (int j = 1; j < 7; ++j) {
    spread_shared = std::max(spread_shared, std::abs(shared[j] - shared[0]));
    spread_independent = std::max(spread_independent, std::abs(independent[j] - independent[0]));
  }
  EXPECT_GT(std::abs(shared[0]), 1e-3);
  EXPECT_LT(spread_shared, 1e-9);
  EXPECT_GT(spread_independent, 0.1);
}

TEST_F(FrankaRolloutTest, TorquesStayWithinLimitsUnderEveryScheme) {
  FrankaSimulator simulator(model_, config_);
  FrankaEpisode episode;
  for (Augmentation scheme : {Augmentation::kPerJointNoise, Augmentation::kSameNoise, Augmentation::kRandomForce}) {
    for (int i = 0; i < 8; ++i) {
      Rng rng(StreamSeed(5, i));
      simulator.Rollout(start_q_, goal_, scheme, rng, &episode);
      for (size_t k = 0; k < episode.torques.size(); ++k) {
        ASSERT_LE(std::abs(episode.torques[k]), model_.limits().torque[k % 7]) << "scheme " << int(scheme);
      }
    }
  }
}

TEST_F(FrankaRolloutTest, NoisyEpisodesEndNearTheGoal) {
  FrankaSimulator simulator(model_, config_);
  FrankaEpisode episode;
  int near = 0;
  const int n = 40;
  for (int i = 0; i < n; ++i) {
    Rng rng(StreamSeed(9, i));
    simulator.Rollout(start_q_, goal_, Augmentation::kPerJointNoise, rng, &episode);
    ASSERT_FALSE(episode.rejected) << episode.reject_reason;
    near += (LastTcp(episode) - goal_).norm() < 0.02;
  }
  EXPECT_GE(near, n * 90 / 100);
}

TEST_F(FrankaRolloutTest, SameSeedSameEpisodeAndForcesAreRecorded) {
  FrankaSimulator simulator(model_, config_);
  FrankaEpisode a, b;
  Rng rng_a(42), rng_b(42);
  simulator.Rollout(start_q_, goal_, Augmentation::kRandomForce, rng_a, &a);
  simulator.Rollout(start_q_, goal_, Augmentation::kRandomForce, rng_b, &b);
  EXPECT_EQ(a.states, b.states);
  EXPECT_EQ(a.external_force, b.external_force);
  const double magnitude = Eigen::Vector3d(a.external_force[0], a.external_force[1], a.external_force[2]).norm();
  EXPECT_GE(magnitude, 15.0);
  EXPECT_LE(magnitude, 20.0);
}

TEST_F(FrankaRolloutTest, FastJointsRejectTheEpisode) {
  FrankaRolloutConfig config = config_;
  config.reject_velocity_factor = 0.01;
  FrankaSimulator simulator(model_, config);
  FrankaEpisode episode;
  Rng rng(1);
  simulator.Rollout(start_q_, goal_, Augmentation::kNone, rng, &episode);
  EXPECT_TRUE(episode.rejected);
  EXPECT_THAT(episode.reject_reason, HasSubstr("exceeds 0.01 x its limit"));
  EXPECT_EQ(episode.states.size(), 64u * 14);  // the record keeps its shape
}

TEST(FrankaRolloutConfigTest, ValidateNamesTheKey) {
  const FrankaModel model = LoadFrankaModel();
  FrankaRolloutConfig config;
  config.augmentation.force_range = {20.0, 15.0};
  EXPECT_THAT([&] { config.Validate("generate.franka", model.limits()); },
              ::testing::ThrowsMessage<Error>(HasSubstr(
                  "generate.franka.augmentation.force_range: expected [min, max] with min <= max, got [20, 15]")));
  config = FrankaRolloutConfig{};
  config.controller.posture[3] = 0.5;
  EXPECT_THAT([&] { config.Validate("generate.franka", model.limits()); },
              ::testing::ThrowsMessage<Error>(HasSubstr("generate.franka.controller.posture[3]")));
}

}  // namespace
}  // namespace flowplan::sim
