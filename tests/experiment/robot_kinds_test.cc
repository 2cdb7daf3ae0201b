// The kinds of robot that `plan --execute` and `render` simulate (experiment/robot_kinds.h): the built-in Franka
// found by its kinematics and simulated from its MJCF, a robot folder only when its folder is given (read once), a
// folder whose robot moves otherwise refused naming its file, and the robot a file carries resolved to the built-in
// Franka's collision body with the file's limits.

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>

#include "core/error.h"
#include "experiment/robot_kinds.h"
#include "robotfiles/robot_folder.h"
#include "sim/franka_model.h"
#include "tests/support/smooth_move.h"

namespace flowplan::experiment {
namespace {

namespace fs = std::filesystem;
using ::testing::HasSubstr;

constexpr double kDt = 1.0 / 15.0;
constexpr int kT = 40;

std::string Folder(const std::string& name) { return std::string(FLOWPLAN_SOURCE_DIR) + "/robots/" + name; }

/// A plan (T, 2J) from q0 to q1 with a smooth (cosine) time profile and consistent velocities.
std::vector<double> SmoothMove(const std::vector<double>& q0, const std::vector<double>& q1) {
  return flowplan::testing::SmoothMove(q0, q1, kT, kDt);
}

/// Executes a move of `robot` from home, turning its first joint by 0.3 rad, in `simulator`'s scene without
/// obstacles, and returns how far each joint ends from where the plan ends (rad).
std::vector<double> EndError(const RobotSimulator& simulator, const kinematics::RobotDescription& robot) {
  const std::vector<double> q0 = robot.home;
  std::vector<double> q1 = q0;
  q1[0] += 0.3;
  const std::unique_ptr<SimulatedScene> scene = simulator.Scene({}, {});
  const std::unique_ptr<sim::ArmExecutor> executor = scene->Executor();
  EXPECT_EQ(executor->num_joints(), robot.num_joints);
  const sim::ExecutionResult executed = executor->Execute(SmoothMove(q0, q1), kT, kDt, Eigen::Vector3d::Zero());
  const size_t J = q0.size(), last = static_cast<size_t>(executed.num_states - 1) * 2 * J;
  std::vector<double> error(J);
  for (size_t j = 0; j < J; ++j) error[j] = std::abs(executed.states[last + j] - q1[j]);
  return error;
}

TEST(RobotKindsTest, TheBuiltInFrankaIsSimulatedFromItsMjcfWithoutAFolder) {
  const kinematics::RobotDescription franka = sim::LoadFrankaModel().description();
  const std::unique_ptr<RobotSimulator> simulator = FindSimulator(franka, "", ExperimentConfig{});
  ASSERT_NE(simulator, nullptr);
  EXPECT_EQ(simulator->drawn_by(), "its MJCF's capsules");
  for (double error : EndError(*simulator, franka)) EXPECT_LT(error, 0.01);
}

TEST(RobotKindsTest, ARobotFolderIsSimulatedOnlyWhenItsFolderIsGiven) {
  const kinematics::RobotDescription ur5 = robotfiles::LoadRobot(Folder("ur5"));
  EXPECT_EQ(FindSimulator(ur5, "", ExperimentConfig{}), nullptr);
  try {
    RequireSimulator(ur5, "", ExperimentConfig{}, "--execute");
    ADD_FAILURE() << "expected an error";
  } catch (const Error& e) {
    EXPECT_THAT(e.what(), HasSubstr("--execute: the robot \"" + ur5.name + "\" is not the built-in Franka"));
  }
  const std::unique_ptr<RobotSimulator> simulator = FindSimulator(ur5, Folder("ur5"), ExperimentConfig{});
  ASSERT_NE(simulator, nullptr);
  EXPECT_EQ(simulator->drawn_by(), "its collision spheres");
  for (double error : EndError(*simulator, ur5)) EXPECT_LT(error, 0.01);
}

TEST(RobotKindsTest, AFolderIsReadOnceForEveryScene) {
  // A copy of the UR5 folder whose robot.yaml is gone once the simulator is made: its scenes still come.
  const fs::path copy = fs::path(::testing::TempDir()) / "robot_kinds_ur5";
  fs::remove_all(copy);
  fs::copy(Folder("ur5"), copy, fs::copy_options::recursive);
  const kinematics::RobotDescription ur5 = robotfiles::LoadRobot(copy.string());
  const std::unique_ptr<RobotSimulator> simulator = FindSimulator(ur5, copy.string(), ExperimentConfig{});
  ASSERT_NE(simulator, nullptr);
  fs::remove(copy / "robot.yaml");
  for (double error : EndError(*simulator, ur5)) EXPECT_LT(error, 0.01);
  fs::remove_all(copy);
}

TEST(RobotKindsTest, AFolderWhoseRobotMovesOtherwiseIsRefusedNamingItsFile) {
  const kinematics::RobotDescription ur5 = robotfiles::LoadRobot(Folder("ur5"));
  const std::unique_ptr<RobotSimulator> simulator = FindSimulator(ur5, Folder("franka_panda"), ExperimentConfig{});
  ASSERT_NE(simulator, nullptr);
  try {
    simulator->Scene({}, {});
    ADD_FAILURE() << "expected an error";
  } catch (const Error& e) {
    EXPECT_THAT(e.what(), HasSubstr(Folder("franka_panda") + "/robot.yaml: its robot"));
    EXPECT_THAT(e.what(), HasSubstr("does not move as the planned \"" + ur5.name + "\""));
  }
}

TEST(RobotKindsTest, TheFrankaAFileCarriesGetsTheBuiltInBodyWithTheFilesLimits) {
  const kinematics::RobotDescription builtin = sim::LoadFrankaModel().description();
  kinematics::RobotDescription carried = builtin;
  carried.spheres.resize(3);  // an older file's coarser body
  carried.self_collision = false;
  carried.joint_upper[3] = -0.1;
  carried.velocity_limit[6] = 1.0;
  const kinematics::RobotDescription resolved = ResolveRobot(carried);
  EXPECT_EQ(resolved.spheres.size(), builtin.spheres.size());
  EXPECT_EQ(resolved.self_collision, builtin.self_collision);
  EXPECT_EQ(resolved.joint_upper, carried.joint_upper);
  EXPECT_EQ(resolved.velocity_limit, carried.velocity_limit);
  // Any other robot is planned as carried.
  const kinematics::RobotDescription ur5 = robotfiles::LoadRobot(Folder("ur5"));
  EXPECT_EQ(kinematics::RobotToYaml(ResolveRobot(ur5)), kinematics::RobotToYaml(ur5));
  kinematics::RobotDescription bent = builtin;
  bent.links[2].pos[0] += 0.01;  // not the Franka's tree
  bent.spheres.resize(3);
  EXPECT_EQ(ResolveRobot(bent).spheres.size(), 3u);
}

}  // namespace
}  // namespace flowplan::experiment
