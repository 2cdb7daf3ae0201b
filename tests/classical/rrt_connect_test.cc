// RRT-Connect's plans, checked without its validity checker: the particle's
// path against the disc by plain geometry, the Franka's plan executed in
// MuJoCo among obstacles that are collision bodies.

#include "classical/rrt_connect.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "core/error.h"
#include "kinematics/arm_kinematics.h"
#include "sim/franka_execution.h"
#include "sim/franka_model.h"

namespace flowplan::classical {
namespace {

constexpr double kDt = 1.0 / 15.0;

std::shared_ptr<const kinematics::Robot> Disc() {
  return kinematics::MakeRobot(kinematics::PointRobot("disc", 2, 0.05, 0.0, 1.0));
}

TEST(RrtConnectTest, ParticleGoesAroundADiscWithConsistentVelocities) {
  const RrtConnectPlanner planner(Disc(), 64, 4, kDt, RrtConnectConfig{});
  planning::PlanRequest request;
  request.start = torch::tensor({{0.1f, 0.5f, 0.0f, 0.0f}, {0.2f, 0.45f, 0.0f, 0.0f}});
  request.goal = torch::tensor({{0.9f, 0.5f, 0.0f, 0.0f}, {0.8f, 0.55f, 0.0f, 0.0f}});
  request.obstacles = torch::tensor({{0.5f, 0.5f, 0.2f}});
  request.seed = 3;
  const planning::PlanResult result = planner.Plan(request);
  ASSERT_EQ(result.plans.sizes(), torch::IntArrayRef({2, 64, 4}));
  EXPECT_TRUE(result.found.all().item<bool>());
  ASSERT_EQ(result.seconds.size(), 2u);
  const torch::Tensor plans = result.plans.to(torch::kFloat64);
  for (int64_t b = 0; b < 2; ++b) {
    const torch::Tensor p = plans[b].slice(1, 0, 2), v = plans[b].slice(1, 2, 4);
    EXPECT_LT((p[0] - request.start[b].slice(0, 0, 2)).abs().max().item<double>(), 1e-6);
    EXPECT_LT((p[-1] - request.goal[b].slice(0, 0, 2)).abs().max().item<double>(), 1e-6);
    // Every point on the straight pieces between the states keeps the disc's radius clear.
    const torch::Tensor s = torch::linspace(0, 1, 21, torch::kFloat64).view({1, -1, 1});
    const torch::Tensor dense = p.slice(0, 0, 63).unsqueeze(1) + s * (p.slice(0, 1) - p.slice(0, 0, 63)).unsqueeze(1);
    const double clearance = (dense - torch::tensor({0.5, 0.5}, torch::kFloat64)).norm(2, -1).min().item<double>();
    EXPECT_GT(clearance, 0.2 + 0.05);
    // The velocities are those of the positions' timing; the plan starts and stops at rest.
    const torch::Tensor central = (p.slice(0, 2) - p.slice(0, 0, 62)) / (2 * kDt);
    const double speed = v.norm(2, 1).max().item<double>();
    EXPECT_LT((central - v.slice(0, 1, 63)).norm(2, 1).max().item<double>(), 0.15 * speed);
    EXPECT_LT(v[0].abs().max().item<double>(), 1e-9);
    EXPECT_LT(v[-1].abs().max().item<double>(), 1e-9);
  }
}

TEST(RrtConnectTest, SameSeedSamePlansAndEachPlanIsItsOwnSearch) {
  const RrtConnectPlanner planner(Disc(), 32, 4, kDt, RrtConnectConfig{});
  planning::PlanRequest request;
  request.start = torch::tensor({{0.1f, 0.5f, 0.0f, 0.0f}, {0.1f, 0.5f, 0.0f, 0.0f}});
  request.goal = torch::tensor({{0.9f, 0.5f, 0.0f, 0.0f}, {0.9f, 0.5f, 0.0f, 0.0f}});
  request.obstacles = torch::tensor({{0.5f, 0.5f, 0.2f}});
  request.seed = 7;
  const torch::Tensor a = planner.Plan(request).plans;
  EXPECT_TRUE(torch::equal(a, planner.Plan(request).plans));
  planning::PlanRequest first = request;
  first.start = request.start.slice(0, 0, 1);
  first.goal = request.goal.slice(0, 0, 1);
  EXPECT_TRUE(torch::equal(a.slice(0, 0, 1), planner.Plan(first).plans));
}

TEST(RrtConnectTest, StartInsideAnObstacleIsNotFoundAndFallsBackToTheLine) {
  const RrtConnectPlanner planner(Disc(), 16, 4, kDt, RrtConnectConfig{});
  planning::PlanRequest request;
  request.start = torch::tensor({{0.5f, 0.5f, 0.0f, 0.0f}});
  request.goal = torch::tensor({{0.9f, 0.5f, 0.0f, 0.0f}});
  request.obstacles = torch::tensor({{0.5f, 0.5f, 0.2f}});
  const planning::PlanResult result = planner.Plan(request);
  EXPECT_FALSE(result.found[0].item<bool>());
  EXPECT_LT((result.plans[0].select(1, 1) - 0.5).abs().max().item<float>(), 1e-6);
}

TEST(RrtConnectTest, RobotsWithoutFiniteLimitsOrOddStatesAreRejected) {
  using ::testing::HasSubstr;
  using ::testing::ThrowsMessage;
  EXPECT_THAT([] { RrtConnectPlanner(Disc(), 16, 3, kDt, RrtConnectConfig{}); },
              ThrowsMessage<Error>(HasSubstr("rrt_connect: states of 3 dimensions")));
  const auto unbounded = kinematics::MakeRobot(kinematics::PointRobot("disc", 2, 0.05, -INFINITY, INFINITY));
  EXPECT_THAT([&] { RrtConnectPlanner(unbounded, 16, 4, kDt, RrtConnectConfig{}); },
              ThrowsMessage<Error>(HasSubstr("has no finite range")));
}

TEST(RrtConnectTest, FrankaAroundTheSphereExecutesInMujocoWithoutContact) {
  // The paper's scene: TCP from (0.5, −0.3, 0.2) to (0.5, 0.3, 0.2) around a 0.10 m sphere at (0.5, 0, 0.2).
  const sim::FrankaModel franka = sim::LoadFrankaModel();
  const auto robot = kinematics::MakeRobot(franka.description());
  const auto& arm = dynamic_cast<const kinematics::ArmKinematics&>(*robot);
  const kinematics::IkSolution ik =
      arm.InverseTcp(torch::tensor({{0.5, -0.3, 0.2}, {0.5, 0.3, 0.2}}, torch::kFloat64));
  ASSERT_TRUE(ik.converged.all().item<bool>());
  const RrtConnectPlanner planner(robot, 64, 14, kDt, RrtConnectConfig{});
  planning::PlanRequest request;
  request.start = torch::cat({ik.q.slice(0, 0, 1), torch::zeros({1, 7}, torch::kFloat64)}, 1).to(torch::kFloat32);
  request.goal = torch::cat({ik.q.slice(0, 1, 2), torch::zeros({1, 7}, torch::kFloat64)}, 1).to(torch::kFloat32);
  request.obstacles = torch::tensor({{0.5f, 0.0f, 0.2f, 0.1f}});
  request.seed = 1;
  const planning::PlanResult result = planner.Plan(request);
  ASSERT_TRUE(result.found[0].item<bool>());

  sim::ExecutionConfig config;
  const sim::FrankaModel scene = sim::MakeFrankaScene({{Eigen::Vector3d(0.5, 0.0, 0.2), 0.1}}, 1.0 / config.control_hz);
  sim::FrankaExecutor executor(scene, 1, config);
  const torch::Tensor plan = result.plans[0].to(torch::kFloat64).contiguous();
  const std::vector<double> states(plan.data_ptr<double>(), plan.data_ptr<double>() + plan.numel());
  const sim::ExecutionResult executed = executor.Execute(states, 64, kDt, Eigen::Vector3d(0.5, 0.3, 0.2));
  EXPECT_TRUE(executed.contacts.empty()) << executed.contacts.size() << " contacts, first with "
                                         << executed.contacts.front().arm_geom;
  EXPECT_GT(executed.min_distance[0], 0.0);
  EXPECT_LT(executed.goal_distance, 0.03);
}

}  // namespace
}  // namespace flowplan::classical
