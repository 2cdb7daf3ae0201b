// Executing a robot folder's plans in MuJoCo (robotfiles::LoadExecutionModel
// and sim::ArmExecutor): the UR5 folder tracks a move with the computed-torque
// law, touches an obstacle placed on its path and only that one, and MuJoCo's
// distances between the arm's spheres and an obstacle equal the ones flowplan's
// own collision checker computes.

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <memory>

#include "collision/body_model.h"
#include "collision/checker.h"
#include "core/error.h"
#include "robotfiles/robot_model.h"
#include "sim/arm_execution.h"

namespace flowplan::robotfiles {
namespace {

constexpr double kDt = 1.0 / 15.0;
constexpr int kT = 48;

const std::string& Ur5Folder() {
  static const std::string folder = std::string(FLOWPLAN_SOURCE_DIR) + "/robots/ur5";
  return folder;
}

/// A plan (T, 2J) from q0 to q1 with a smooth (cosine) time profile and consistent velocities.
std::vector<double> SmoothMove(const std::vector<double>& q0, const std::vector<double>& q1) {
  const size_t J = q0.size();
  std::vector<double> plan(kT * 2 * J);
  const double duration = (kT - 1) * kDt;
  for (int t = 0; t < kT; ++t) {
    const double s = 0.5 - 0.5 * std::cos(M_PI * t / (kT - 1));
    const double ds = 0.5 * M_PI / duration * std::sin(M_PI * t / (kT - 1));
    for (size_t j = 0; j < J; ++j) {
      plan[t * 2 * J + j] = q0[j] + s * (q1[j] - q0[j]);
      plan[t * 2 * J + J + j] = ds * (q1[j] - q0[j]);
    }
  }
  return plan;
}

class RobotExecutionTest : public ::testing::Test {
 protected:
  Eigen::Vector3d Tcp(const std::vector<double>& q) {
    Eigen::Vector3d tcp;
    body_.Tcp(q.data(), tcp.data());
    return tcp;
  }
  sim::ExecutionResult Execute(const RobotFile& file, const geometry::Scene& scene, const std::vector<double>& plan,
                               const Eigen::Vector3d& goal) {
    const ExecutionModel model = LoadExecutionModel(file, Ur5Folder(), scene, DriveSettings{}, config_, "ur5");
    sim::ArmExecutor executor(*model.model, model.drives, static_cast<int>(scene.size()), config_);
    return executor.Execute(plan, kT, kDt, goal);
  }

  RobotFile file_ = LoadRobotFile(Ur5Folder());
  collision::BodyModel body_{file_.Description("ur5")};
  sim::ExecutionConfig config_;
  std::vector<double> q0_ = {0.0, -1.2, 1.4, -1.8, -1.57, 0.0}, q1_ = {1.6, -1.2, 1.4, -1.8, -1.57, 0.0};
};

TEST_F(RobotExecutionTest, TracksAMoveToTheGoalWithoutObstacles) {
  const sim::ExecutionResult r = Execute(file_, {}, SmoothMove(q0_, q1_), Tcp(q1_));
  EXPECT_EQ(r.num_states, kT + 15);
  EXPECT_LT(r.goal_distance, 1e-3);
  EXPECT_LT(r.max_tracking_error, 1e-3);
  EXPECT_TRUE(r.contacts.empty());
  EXPECT_EQ(r.warnings, 0);
  // The recorded states follow the plan: half-way, joint 1 is half-way.
  EXPECT_NEAR(r.states[(kT / 2) * 12 + 0], SmoothMove(q0_, q1_)[(kT / 2) * 12 + 0], 1e-3);
}

TEST_F(RobotExecutionTest, AnObstacleOnThePathIsTouchedAndAFarOneIsNot) {
  const std::vector<double> plan = SmoothMove(q0_, q1_);
  const std::vector<double> middle(plan.begin() + (kT / 2) * 12, plan.begin() + (kT / 2) * 12 + 6);
  geometry::Scene scene;
  const Eigen::Vector3d on_path = Tcp(middle);
  scene.spheres.push_back({{on_path.x(), on_path.y(), on_path.z()}, 0.05});
  scene.spheres.push_back({{2.0, 2.0, 2.0}, 0.05});
  const sim::ExecutionResult r = Execute(file_, scene, plan, Tcp(q1_));
  ASSERT_FALSE(r.contacts.empty());
  for (const sim::ContactEvent& contact : r.contacts) {
    EXPECT_EQ(contact.obstacle, 0);
    EXPECT_GT(contact.max_depth, 0.0);
    EXPECT_GT(contact.first_time, 0.3 * (kT - 1) * kDt);  // reached along the way, not at the start
  }
  EXPECT_LT(r.min_distance[0], 0.0);
  EXPECT_GE(r.min_distance[1], sim::kMeasuredDistance);
}

TEST_F(RobotExecutionTest, MujocoMeasuresTheSpheresAsTheCollisionCheckerDoes) {
  // Without collision geometry, the links carry their spheres: at rest at one configuration, MuJoCo's distance
  // from them to each obstacle is the checker's clearance (both closed forms for spheres and boxes).
  RobotFile spheres_only = file_;
  spheres_only.geometry.clear();
  const std::vector<double> q = {0.4, -1.0, 1.2, -1.5, -1.57, 0.3};
  // A sphere and a box beside the tool, a few centimetres from the arm.
  const Eigen::Vector3d tcp = Tcp(q);
  geometry::Scene scene;
  scene.spheres.push_back({{tcp.x(), tcp.y() + 0.2, tcp.z()}, 0.05});
  geometry::BoxObstacle box;
  box.centre = {tcp.x() - 0.2, tcp.y(), tcp.z()};
  box.size = {0.1, 0.2, 0.3};
  scene.boxes.push_back(box);
  const sim::ExecutionResult r = Execute(spheres_only, scene, SmoothMove(q, q), Tcp(q));
  ASSERT_EQ(r.min_distance.size(), 2u);
  EXPECT_LT(r.max_tracking_error, 1e-6);  // held still: the distances are those of q
  for (int k = 0; k < 2; ++k) {
    geometry::Scene one;
    if (k == 0) one.spheres = scene.spheres;
    if (k == 1) one.boxes = scene.boxes;
    const collision::Checker checker(std::make_shared<collision::BodyModel>(body_),
                                     std::make_shared<collision::World>(one, 3), {});
    const double clearance = checker.Clearance(q.data());
    ASSERT_GT(clearance, 0.0) << "obstacle " << k << " touches the arm: contact forces would move it";
    ASSERT_LT(clearance, 0.2) << "obstacle " << k << " is too far from the arm to test anything";
    EXPECT_NEAR(r.min_distance[k], clearance, 1e-6) << "obstacle " << k;
  }
}

TEST_F(RobotExecutionTest, JointPdIsTheFrankasGainsAndRefusedForAFolder) {
  config_.controller = sim::TrackingLaw::kJointPd;
  EXPECT_THAT([&] { LoadExecutionModel(file_, Ur5Folder(), {}, DriveSettings{}, config_, "robots/ur5/robot.yaml"); },
              ::testing::ThrowsMessage<Error>(::testing::HasSubstr(
                  "execute.controller: joint_pd tracks with execute.kp and execute.kd, the Franka's gains; "
                  "robots/ur5/robot.yaml's arm tracks with computed_torque")));
}

}  // namespace
}  // namespace flowplan::robotfiles
