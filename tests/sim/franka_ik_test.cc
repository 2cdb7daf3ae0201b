#include "sim/franka_ik.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "core/error.h"
#include "core/random.h"

namespace flowplan::sim {
namespace {

using ::testing::HasSubstr;

class FrankaIkTest : public ::testing::Test {
 protected:
  // Checks the solution independently through MuJoCo's forward kinematics.
  void ExpectReaches(const Eigen::Vector3d& target, const JointVector& q) {
    const FrankaPose pose = FrankaForwardKinematics(model_, *check_, q);
    EXPECT_LT((pose.tcp_position - target).norm(), 1e-3) << "target " << target.transpose();
    EXPECT_LT((pose.tcp_rotation - DownwardTcpRotation()).cwiseAbs().maxCoeff(), 1e-3);
    for (int j = 0; j < kFrankaJoints; ++j) {
      EXPECT_GE(q[j], model_.limits().q_lower[j]);
      EXPECT_LE(q[j], model_.limits().q_upper[j]);
    }
  }

  FrankaModel model_ = LoadFrankaModel();
  MjDataPtr d_ = MakeData(model_.mj());
  MjDataPtr check_ = MakeData(model_.mj());
};

TEST_F(FrankaIkTest, ReachesTheCrossPointsWithTheGripperDown) {
  for (double y : {-0.3, 0.3}) {
    for (double z : {0.2, 0.6}) {
      const Eigen::Vector3d target(0.5, y, z);
      ExpectReaches(target, SolveTcpIkOrThrow(model_, *d_, target, FrankaReadyPose()));
    }
  }
}

TEST_F(FrankaIkTest, ReachesRandomTargetsOfTheSpecBoxWithinOneMillimetre) {
  // The SPEC box is x in [0.35, 0.75], y in [-0.5, 0.5], z in [0.15, 0.75]; with
  // the gripper pointing down its far top corners are out of reach, so every
  // solve must either reach within 1 mm or say it did not, and every target of
  // the inner part must be reached.
  Rng rng(11);
  int reached = 0;
  for (int trial = 0; trial < 100; ++trial) {
    const Eigen::Vector3d target(rng.Uniform(0.35, 0.75), rng.Uniform(-0.5, 0.5), rng.Uniform(0.15, 0.75));
    const IkResult result = SolveTcpIk(model_, *d_, target, FrankaReadyPose());
    if (result.converged) {
      ++reached;
      ExpectReaches(target, result.q);
    } else {
      EXPECT_GT(result.position_error + result.orientation_error, 1e-5);
    }
  }
  EXPECT_GT(reached, 50);
  for (int trial = 0; trial < 50; ++trial) {
    const Eigen::Vector3d target(rng.Uniform(0.35, 0.55), rng.Uniform(-0.3, 0.3), rng.Uniform(0.15, 0.55));
    ExpectReaches(target, SolveTcpIkOrThrow(model_, *d_, target, FrankaReadyPose()));
  }
}

TEST_F(FrankaIkTest, UnreachableTargetIsAnErrorNamingTheTarget) {
  EXPECT_THAT([&] { SolveTcpIkOrThrow(model_, *d_, Eigen::Vector3d(2.0, 0.0, 0.5), FrankaReadyPose()); },
              ::testing::ThrowsMessage<Error>(HasSubstr("franka IK: target (2.0, 0.0, 0.5) is unreachable (closest")));
}

TEST_F(FrankaIkTest, SolutionsAreDeterministic) {
  const Eigen::Vector3d target(0.45, 0.1, 0.3);
  const JointVector a = SolveTcpIkOrThrow(model_, *d_, target, FrankaReadyPose());
  SolveTcpIk(model_, *d_, Eigen::Vector3d(0.6, -0.2, 0.5), FrankaReadyPose());  // leaves d_ elsewhere
  const JointVector b = SolveTcpIkOrThrow(model_, *d_, target, FrankaReadyPose());
  EXPECT_EQ(a, b);
}

}  // namespace
}  // namespace flowplan::sim
