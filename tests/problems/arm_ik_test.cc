// sim::SolveArmIk for every shipped arm, on targets that are reachable by
// construction: the TCP pose of a random configuration within the limits,
// from MuJoCo's forward kinematics. Each solution is checked by a second
// kinematics that shares no code with MuJoCo (collision::BodyModel::Tcp,
// from robot.yaml's joint tree) and by MuJoCo on a fresh mjData. The Franka
// (7 joints) and the UR5 (6) take the fixed-size solver, the arm on a lift
// (8, one prismatic) the dynamic-size one.

#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <cmath>
#include <cstdio>
#include <string>

#include "collision/body_model.h"
#include "core/random.h"
#include "problems/scene_families.h"
#include "sim/arm_ik.h"
#include "sim/mujoco_util.h"

namespace flowplan::problems {
namespace {

struct Pose {
  Eigen::Vector3d position;
  Eigen::Matrix3d rotation;
};

/// The TCP site's pose at q, by MuJoCo's forward kinematics on its own data.
Pose SitePose(const sim::ArmIkModel& arm, const Eigen::VectorXd& q) {
  auto d = sim::MakeData(*arm.model);
  for (size_t j = 0; j < arm.qpos.size(); ++j) d->qpos[arm.qpos[j]] = q[static_cast<Eigen::Index>(j)];
  mj_kinematics(arm.model, d.get());
  Pose pose;
  pose.position = Eigen::Map<const Eigen::Vector3d>(d->site_xpos + 3 * arm.tcp_site);
  pose.rotation = Eigen::Map<const Eigen::Matrix<double, 3, 3, Eigen::RowMajor>>(d->site_xmat + 9 * arm.tcp_site);
  return pose;
}

const FamilyArm& Arm(const std::string& robot) {
  static const FamilyArm franka = FrankaFamilyArm();
  static const FamilyArm ur5 = FolderFamilyArm(std::string(FLOWPLAN_SOURCE_DIR) + "/robots/ur5");
  static const FamilyArm fetch = FolderFamilyArm(std::string(FLOWPLAN_SOURCE_DIR) + "/robots/fetch_arm");
  return robot == "franka" ? franka : robot == "ur5" ? ur5 : fetch;
}

class ArmIkTest : public ::testing::TestWithParam<std::string> {};

// Random configurations kept 0.05 inside the limits (IK keeps 0.01 from them), their TCP poses solved for from
// home with seeded restarts (from home alone a random wrist orientation is often out of reach of the descent:
// the test prints how many converge without them). Every solution the solver calls converged must be one: its
// TCP where asked by both kinematics, pointing as asked, its joints inside the limits by IK's margin. A solve
// that does not converge must report the error of what it returns. At least two in three must converge (each
// target has a solution, the configuration it was made from; 56, 59 and 50 of 60 do): the arm on a lift stalls
// on about one in six, some within 0.05 mm of the target, with its step size and stall rule the same as every
// arm's.
TEST_P(ArmIkTest, ReachesTheTcpPosesOfRandomConfigurations) {
  const FamilyArm& arm = Arm(GetParam());
  const sim::ArmIkModel& ik = arm.ik;
  const int J = arm.robot.num_joints;
  ASSERT_EQ(static_cast<int>(ik.qpos.size()), J);
  const collision::BodyModel body(arm.robot, GetParam());
  sim::IkSettings settings;
  settings.restarts = 10;
  settings.restart_seed = 3;
  auto d = sim::MakeData(*ik.model);
  Rng rng(29);
  constexpr int kTargets = 60;
  int converged = 0, from_home = 0;
  for (int trial = 0; trial < kTargets; ++trial) {
    Eigen::VectorXd drawn(J);
    for (int j = 0; j < J; ++j) drawn[j] = rng.Uniform(ik.lower[j] + 0.05, ik.upper[j] - 0.05);
    const Pose target = SitePose(ik, drawn);
    const sim::ArmIkResult result =
        sim::SolveArmIk(ik, *d, target.position, target.rotation, arm.home, arm.home, settings);
    SCOPED_TRACE("target " + std::to_string(trial));
    // Restarts only ever follow a solve from home that did not converge: one that did is returned as it was.
    const sim::ArmIkResult home_only = sim::SolveArmIk(ik, *d, target.position, target.rotation, arm.home, arm.home);
    if (home_only.converged) {
      ++from_home;
      EXPECT_TRUE(result.q == home_only.q);
    }
    ASSERT_EQ(result.q.size(), J);
    if (!result.converged) {
      EXPECT_TRUE(result.position_error >= settings.position_tolerance ||
                  result.orientation_error >= settings.orientation_tolerance);
      // What it reports is the pose of the configuration it returns.
      const Pose reached = SitePose(ik, result.q);
      EXPECT_NEAR((reached.position - target.position).norm(), result.position_error, 1e-9);
      continue;
    }
    ++converged;
    const Pose reached = SitePose(ik, result.q);
    EXPECT_LT((reached.position - target.position).norm(), settings.position_tolerance);
    const Eigen::AngleAxisd turn(target.rotation * reached.rotation.transpose());
    EXPECT_LT(std::abs(turn.angle()), settings.orientation_tolerance);
    double tcp[3];
    body.Tcp(result.q.data(), tcp);
    EXPECT_LT((Eigen::Map<const Eigen::Vector3d>(tcp) - target.position).norm(), 1e-6 + settings.position_tolerance)
        << "robot.yaml's kinematics disagree with MuJoCo's";
    for (int j = 0; j < J; ++j) {
      EXPECT_GE(result.q[j], ik.lower[j] + settings.limit_margin - 1e-12) << "joint " << j;
      EXPECT_LE(result.q[j], ik.upper[j] - settings.limit_margin + 1e-12) << "joint " << j;
    }
  }
  std::printf("%s: %d of %d reachable targets solved from home, %d with %d restarts\n", GetParam().c_str(),
              from_home, kTargets, converged, settings.restarts);
  EXPECT_GE(converged, kTargets * 2 / 3) << converged << " of " << kTargets << " reachable targets solved";
}

// Same target, same seed, same restarts: the same bits (the families' problems rest on it).
TEST_P(ArmIkTest, SolutionsAreDeterministic) {
  const FamilyArm& arm = Arm(GetParam());
  const int J = arm.robot.num_joints;
  Eigen::VectorXd drawn = 0.5 * (arm.ik.lower + arm.ik.upper);
  for (int j = 0; j < J; ++j) drawn[j] += 0.1 * (j % 2 == 0 ? 1 : -1);
  const Pose target = SitePose(arm.ik, drawn);
  auto d1 = sim::MakeData(*arm.ik.model);
  auto d2 = sim::MakeData(*arm.ik.model);
  for (const int restarts : {0, 10}) {
    sim::IkSettings settings;
    settings.restarts = restarts;
    settings.restart_seed = 4;
    // A home far from the target, so that the restarts are used when there are any.
    const Eigen::VectorXd far = arm.ik.lower.array() + 0.02;
    const auto a = sim::SolveArmIk(arm.ik, *d1, target.position, target.rotation, far, far, settings);
    sim::SolveArmIk(arm.ik, *d2, target.position + Eigen::Vector3d(0.05, 0, 0), target.rotation, far, far, settings);
    const auto b = sim::SolveArmIk(arm.ik, *d2, target.position, target.rotation, far, far, settings);
    EXPECT_TRUE(a.q == b.q) << restarts << " restarts";
    EXPECT_EQ(a.converged, b.converged);
  }
}

INSTANTIATE_TEST_SUITE_P(ShippedArms, ArmIkTest, ::testing::Values("franka", "ur5", "fetch_arm"),
                         [](const auto& info) { return info.param; });

}  // namespace
}  // namespace flowplan::problems
