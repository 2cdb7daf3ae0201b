// The plan checker against closed-form cases and against a slow, obviously
// correct reference (every segment sampled at 2,000 points), the motion bound
// against forward kinematics, and the quality metrics against hand values.

#include "validity/plan_check.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <atomic>
#include <cmath>
#include <iostream>
#include <set>

#include "core/error.h"
#include "sim/franka_model.h"
#include "validity/plan_quality.h"

namespace flowplan::validity {
namespace {

using ::testing::HasSubstr;

/// A disc of radius 0.05 in [-1, 1]², at most 2 per s along each axis.
std::shared_ptr<const kinematics::Robot> Disc() {
  kinematics::RobotDescription disc = kinematics::PointRobot("disc", 2, 0.05, -1.0, 1.0);
  disc.velocity_limit = {2.0, 2.0};
  return kinematics::MakeRobot(disc);
}

std::shared_ptr<const kinematics::Robot> Franka() {
  static const auto robot = kinematics::MakeRobot(sim::LoadFrankaModel().description());
  return robot;
}

geometry::SceneRows Spheres(const std::vector<std::vector<double>>& rows) {
  geometry::Scene scene;
  for (const auto& r : rows) scene.spheres.push_back({{r.begin(), r.end() - 1}, r.back()});
  return geometry::Rows(scene, static_cast<int>(rows[0].size()) - 1, "test");
}

/// A plan (1, T, 2J) of the disc's positions `points` (T, 2), velocities zero.
torch::Tensor DiscPlan(const std::vector<std::vector<double>>& points) {
  torch::Tensor plan = torch::zeros({1, static_cast<int64_t>(points.size()), 4}, torch::kFloat32);
  for (size_t t = 0; t < points.size(); ++t) {
    plan[0][static_cast<int64_t>(t)][0] = points[t][0];
    plan[0][static_cast<int64_t>(t)][1] = points[t][1];
  }
  return plan;
}

TEST(PlanCheckTest, AStepOverAnObstacleIsCaughtBetweenTheStates) {
  CheckConfig config;
  config.max_speed_ratio = INFINITY;
  const PlanChecker checker(Disc(), 0.1, config);
  const geometry::SceneRows scene = Spheres({{0.0, 0.0, 0.05}});
  // Both states keep 0.25 from the small sphere; the segment between them crosses it.
  const torch::Tensor over = DiscPlan({{-0.4, 0.0}, {0.4, 0.0}});
  const torch::Tensor start = over[0][0], goal = over[0][1];
  const PlanVerdict v = checker.Check(over, start, goal, scene)[0];
  EXPECT_EQ(v.failure, Failure::kMotion);
  EXPECT_THAT(v.reason, HasSubstr("between states 0 and 1"));
  EXPECT_THAT(v.reason, HasSubstr("obstacle 0"));
  EXPECT_GT(v.motion_checks, 0);
  // Around it: valid, and the clearance is that of the nearest state.
  const torch::Tensor around = DiscPlan({{-0.4, 0.0}, {-0.2, 0.3}, {0.2, 0.3}, {0.4, 0.0}});
  const PlanVerdict ok = checker.Check(around, around[0][0], around[0][3], scene)[0];
  EXPECT_TRUE(ok.valid()) << ok.reason;
  EXPECT_NEAR(ok.clearance, std::hypot(0.2, 0.3) - 0.1, 1e-6);
  // A margin larger than the detour's clearance makes it a collision at a state.
  CheckConfig wide = config;
  wide.margin = 0.3;
  const PlanVerdict near = PlanChecker(Disc(), 0.1, wide).Check(around, around[0][0], around[0][3], scene)[0];
  EXPECT_EQ(near.failure, Failure::kCollision);
  EXPECT_THAT(near.reason, HasSubstr("state 1"));
  // No obstacles: nothing to hit.
  const PlanVerdict free = checker.Check(over, start, goal, geometry::SceneRows())[0];
  EXPECT_TRUE(free.valid());
  EXPECT_TRUE(std::isinf(free.clearance));
}

TEST(PlanCheckTest, EachFailureIsNamedInOrder) {
  CheckConfig config;
  config.joint_tolerance = 0.01;
  config.max_speed_ratio = 1.0;
  const PlanChecker checker(Disc(), 0.1, config);
  const geometry::SceneRows none;
  const torch::Tensor plan = DiscPlan({{0.0, 0.0}, {0.1, 0.0}, {0.2, 0.0}});
  const torch::Tensor start = plan[0][0].clone(), goal = plan[0][2].clone();
  EXPECT_TRUE(checker.Check(plan, start, goal, none)[0].valid());
  EXPECT_EQ(checker.Check(plan, start, goal, none, torch::tensor({false}))[0].failure, Failure::kNotFound);
  torch::Tensor moved = start.clone();
  moved[1] = 0.02f;
  const PlanVerdict s = checker.Check(plan, moved, goal, none)[0];
  EXPECT_EQ(s.failure, Failure::kStart);
  EXPECT_THAT(s.reason, HasSubstr("from the start at joint 2"));
  EXPECT_EQ(checker.Check(plan, start, moved, none)[0].failure, Failure::kGoal);
  const torch::Tensor outside = DiscPlan({{0.0, 0.0}, {0.0, 1.02}, {0.2, 0.0}});
  const PlanVerdict limit = checker.Check(outside, start, goal, none)[0];
  EXPECT_EQ(limit.failure, Failure::kJointLimit);
  EXPECT_THAT(limit.reason, HasSubstr("state 1: joint 2 is 0.02"));
  const torch::Tensor fast = DiscPlan({{0.0, 0.0}, {0.0, 0.3}, {0.2, 0.0}});  // 3 per s against a limit of 2
  const PlanVerdict speed = checker.Check(fast, start, goal, none)[0];
  EXPECT_EQ(speed.failure, Failure::kSpeedLimit);
  EXPECT_THAT(speed.reason, HasSubstr("states 0-1: joint 2 moves at 1.5"));
  EXPECT_THAT([&] { checker.Check(plan.squeeze(0), start, goal, none); },
              ::testing::ThrowsMessage<Error>(HasSubstr("check: plans: expected (N, T, D)")));
  EXPECT_THAT([&] { checker.Check(plan, torch::zeros({3}), goal, none); },
              ::testing::ThrowsMessage<Error>(HasSubstr("check: start: expected (4) or (1, 4)")));
}

TEST(PlanCheckTest, NonFiniteStatesFailAtOnceWithoutAHang) {
  const PlanChecker checker(Disc(), 0.1, CheckConfig{});
  torch::Tensor plan = DiscPlan({{-0.4, 0.0}, {0.0, 0.1}, {0.4, 0.0}});
  plan[0][1][0] = NAN;
  const PlanVerdict v = checker.Check(plan, plan[0][0], plan[0][2], Spheres({{0.0, 0.0, 0.05}}))[0];
  EXPECT_EQ(v.failure, Failure::kNotFinite);
  plan[0][1][0] = INFINITY;
  EXPECT_EQ(checker.Check(plan, plan[0][0], plan[0][2], geometry::SceneRows())[0].failure, Failure::kNotFinite);
}

TEST(PlanCheckTest, TheFrankaCheckFindsTheFloorAndTheArmFoldedOntoItself) {
  CheckConfig on_floor;
  on_floor.floor_height = 0.0;
  on_floor.max_speed_ratio = INFINITY;
  const PlanChecker checker(Franka(), 1.0 / 15.0, on_floor);
  // The ready pose, then joint 2 leaning far forward: the hand goes below the floor.
  torch::Tensor plan = torch::zeros({1, 3, 14});
  const std::vector<double> ready = {0.0, -0.785398, 0.0, -2.356194, 0.0, 1.570796, 0.785398};
  for (int t = 0; t < 3; ++t) {
    for (int j = 0; j < 7; ++j) plan[0][t][j] = ready[static_cast<size_t>(j)];
  }
  plan[0][1][1] = 0.5f;
  plan[0][2][1] = 1.7f;
  plan[0][2][3] = -0.1f;
  const PlanVerdict v = checker.Check(plan, plan[0][0], plan[0][2], geometry::SceneRows())[0];
  EXPECT_EQ(v.failure, Failure::kFloor);
  EXPECT_THAT(v.reason, HasSubstr("from the floor"));
  // Without a floor (the default, and a problem's -inf) the same plan goes below z = 0 unchecked.
  CheckConfig no_floor = on_floor;
  no_floor.floor_height = -INFINITY;
  EXPECT_NE(PlanChecker(Franka(), 1.0 / 15.0, no_floor).Check(plan, plan[0][0], plan[0][2], geometry::SceneRows())[0].failure,
            Failure::kFloor);
  collision::WorldOptions world;
  world.floor_height = -INFINITY;
  EXPECT_NE(checker.Check(plan, plan[0][0], plan[0][2], geometry::SceneRows(), {}, world)[0].failure, Failure::kFloor);
  // The hand folded back onto the upper arm.
  torch::Tensor folded = plan.slice(1, 0, 1).expand({1, 2, 14}).contiguous().clone();
  const std::vector<double> fold = {0.0, 0.0, 0.0, -3.0, 0.0, 0.2, 0.0};
  for (int j = 0; j < 7; ++j) folded[0][1][j] = fold[static_cast<size_t>(j)];
  const PlanVerdict self = checker.Check(folded.slice(1, 1, 2).expand({1, 2, 14}), folded[0][1], folded[0][1],
                                         geometry::SceneRows())[0];
  EXPECT_EQ(self.failure, Failure::kSelf);
  EXPECT_THAT(self.reason, HasSubstr("overlaps"));
  // The ready pose alone is allowed.
  const torch::Tensor still = plan.slice(1, 0, 1).expand({1, 2, 14}).contiguous();
  EXPECT_TRUE(checker.Check(still, still[0][0], still[0][1], geometry::SceneRows())[0].valid());
}

TEST(PlanCheckTest, AStateAtALimitInFloat32IsAtTheLimit) {
  // A joint exactly at its limit, rounded to float32, lies up to 1.2e-7 past it: within check.limit_tolerance.
  const PlanChecker checker(Franka(), 1.0 / 15.0, CheckConfig{});
  std::vector<double> q = {0.0, -0.785398, 0.0, -2.356194, 0.0, 1.570796, 0.785398};
  q[3] = Franka()->description().joint_upper[3];  // -0.0698
  torch::Tensor plan = torch::zeros({1, 2, 14});
  for (int t = 0; t < 2; ++t) {
    for (int j = 0; j < 7; ++j) plan[0][t][j] = q[static_cast<size_t>(j)];
  }
  ASSERT_GT(static_cast<double>(plan[0][0][3].item<float>()), q[3]);  // float32 rounds it past the limit
  EXPECT_TRUE(checker.Check(plan, plan[0][0], plan[0][1], geometry::SceneRows())[0].valid());
  plan[0][1][3] = static_cast<float>(q[3] + 1e-4);
  const PlanVerdict past = checker.Check(plan, plan[0][0], plan[0][0], geometry::SceneRows())[0];
  EXPECT_EQ(past.failure, Failure::kJointLimit);
  EXPECT_THAT(past.reason, HasSubstr("state 1: panda_joint4 is"));
}

/// The reference: clearance at 2,000 points of every segment, interpolated linearly in joint space.
double DenseClearance(const kinematics::Robot& robot, const torch::Tensor& plan, const geometry::SceneRows& scene) {
  const int64_t T = plan.size(0), J = robot.num_joints();
  const torch::Tensor u = torch::linspace(0, 1, 2000, torch::kFloat64).view({-1, 1});
  double smallest = INFINITY;
  for (int64_t t = 0; t + 1 < T; ++t) {
    const torch::Tensor a = plan[t].slice(0, 0, J).to(torch::kFloat64), b = plan[t + 1].slice(0, 0, J).to(torch::kFloat64);
    const torch::Tensor q = a + u * (b - a);
    smallest = std::min(smallest, robot.Clearance(q, scene).min().item<double>());
  }
  return smallest;
}

TEST(PlanCheckTest, ArmMotionsAgreeWithDenseSampling) {
  const auto robot = Franka();
  CheckConfig config;
  config.max_speed_ratio = INFINITY;
  config.resolution = 0.001;
  const PlanChecker checker(robot, 1.0 / 15.0, config);
  // A thin board in front of the arm, and plans of 3 states that sweep the arm past it.
  geometry::Scene scene;
  scene.boxes.push_back({{0.55, 0.0, 0.45}, {0.3, 0.02, 0.5}, {1.0, 0.0, 0.0, 0.0}, NAN});
  const geometry::SceneRows rows = geometry::Rows(scene, 3, "test");
  torch::manual_seed(9);
  const torch::Tensor ready = torch::tensor({0.0, -0.785398, 0.0, -2.356194, 0.0, 1.570796, 0.785398}, torch::kFloat64);
  int agree_valid = 0, agree_invalid_motion = 0, states_in_collision = 0;
  for (int n = 0; n < 150; ++n) {
    torch::Tensor plan = torch::zeros({3, 14}, torch::kFloat64);
    for (int t = 0; t < 3; ++t) {
      torch::Tensor q = ready.clone();
      q[0] = -1.2 + 1.2 * t + 0.3 * (torch::rand({1}, torch::kFloat64).item<double>() - 0.5);  // across the board
      q.slice(0, 1, 7) += 0.4 * (torch::rand({6}, torch::kFloat64) - 0.5);
      plan[t].slice(0, 0, 7) = q;
    }
    const PlanVerdict v = checker.Check(plan.unsqueeze(0), plan[0], plan[2], rows)[0];
    const double dense = DenseClearance(*robot, plan, rows);
    if (v.failure == Failure::kCollision) {
      ++states_in_collision;
      continue;
    }
    if (v.valid()) {
      ++agree_valid;
      EXPECT_GE(dense, -config.resolution / 2) << "plan " << n;  // the guarantee
    } else {
      ASSERT_EQ(v.failure, Failure::kMotion) << v.reason;
      ++agree_invalid_motion;
      EXPECT_LT(dense, 1e-9) << "plan " << n << ": " << v.reason;  // a real overlap between the states
    }
  }
  EXPECT_GT(agree_valid, 5);
  EXPECT_GT(agree_invalid_motion, 5);
  EXPECT_GT(states_in_collision, 0);
  std::cout << agree_valid << " valid, " << agree_invalid_motion << " through the board between states, "
            << states_in_collision << " with a state in it\n";
}

TEST(PlanCheckTest, CheckingInAPreparedWorldGivesCheckVerdictsForThatWorldCallAfterCall) {
  const auto robot = Franka();
  const PlanChecker checker(robot, 1.0, CheckConfig{});  // a second between states: within the speed limits
  geometry::Scene board;
  board.boxes.push_back({{0.55, 0.0, 0.45}, {0.3, 0.02, 0.5}, {1.0, 0.0, 0.0, 0.0}, NAN});
  const geometry::SceneRows rows = geometry::Rows(board, 3, "test"), none;
  // Plans that sweep the arm across the board: some pass it, some go through it, between states or at one.
  torch::manual_seed(4);
  const torch::Tensor ready = torch::tensor({0.0, -0.785398, 0.0, -2.356194, 0.0, 1.570796, 0.785398}, torch::kFloat64);
  const int64_t N = 40, T = 4;
  torch::Tensor plans = torch::zeros({N, T, 14}, torch::kFloat64);
  for (int64_t n = 0; n < N; ++n) {
    for (int64_t t = 0; t < T; ++t) {
      torch::Tensor q = ready.clone();
      q[0] = -1.2 + 0.8 * static_cast<double>(t) + 0.3 * (torch::rand({1}, torch::kFloat64).item<double>() - 0.5);
      q.slice(0, 1, 7) += 0.6 * (torch::rand({6}, torch::kFloat64) - 0.5);
      plans[n][t].slice(0, 0, 7) = q;
    }
  }
  const torch::Tensor start = plans.select(1, 0), goal = plans.select(1, T - 1);
  // Three worlds: the board over a floor out of reach, the board over a floor some states reach, and nothing.
  collision::WorldOptions low, high;
  low.floor_height = -0.5;
  high.floor_height = 0.3;
  struct World {
    geometry::SceneRows rows;
    collision::WorldOptions options;
  };
  const std::vector<World> worlds = {{rows, low}, {rows, high}, {none, low}};
  std::vector<collision::Checker> prepared;
  std::vector<std::vector<PlanVerdict>> checked;
  for (const World& w : worlds) {
    prepared.push_back(checker.ConfigurationChecker(w.rows, w.options));
    checked.push_back(checker.Check(plans, start, goal, w.rows, {}, w.options));
  }
  std::vector<std::set<Failure>> seen(worlds.size());
  for (int call = 0; call < 2; ++call) {  // a prepared world is not changed by checking in it, or in another
    for (size_t w = 0; w < worlds.size(); ++w) {
      const std::vector<PlanVerdict> in = checker.CheckIn(prepared[w], plans, start, goal);
      for (int64_t n = 0; n < N; ++n) {
        const auto i = static_cast<size_t>(n);
        EXPECT_EQ(in[i].failure, checked[w][i].failure) << "world " << w << ", plan " << n;
        EXPECT_EQ(in[i].reason, checked[w][i].reason) << "world " << w << ", plan " << n;
        EXPECT_EQ(in[i].clearance, checked[w][i].clearance) << "world " << w << ", plan " << n;
        EXPECT_EQ(in[i].motion_checks, checked[w][i].motion_checks) << "world " << w << ", plan " << n;
        seen[w].insert(in[i].failure);
      }
    }
  }
  // The cases the equality covers, each world deciding: valid plans and plans through the board, plans that
  // reach the high floor, and no collision without the board.
  EXPECT_TRUE(seen[0].count(Failure::kNone));
  EXPECT_TRUE(seen[0].count(Failure::kMotion) || seen[0].count(Failure::kCollision));
  EXPECT_FALSE(seen[0].count(Failure::kFloor));
  EXPECT_TRUE(seen[1].count(Failure::kFloor));
  EXPECT_FALSE(seen[2].count(Failure::kMotion) || seen[2].count(Failure::kCollision));
}

TEST(PlanQualityTest, HandValuesOfALineAndACubic) {
  const auto disc = Disc();
  const double dt = 0.1;
  // A straight line at constant speed, then at rest: no jerk inside the ramp.
  const torch::Tensor line = DiscPlan({{0.0, 0.0}, {0.1, 0.0}, {0.2, 0.0}, {0.3, 0.0}, {0.3, 0.0}, {0.3, 0.0}});
  const PlanQuality q = MeasurePlans(line, *disc, dt, 1e-3)[0];
  EXPECT_NEAR(q.joint_path_length, 0.3, 1e-6);
  EXPECT_NEAR(q.tcp_path_length, 0.3, 1e-6);
  EXPECT_NEAR(q.max_speed_ratio, 1.0 / 2.0, 1e-5);  // 1 per s against the disc's limit of 2 per s
  EXPECT_NEAR(q.duration, 0.3, 1e-12);             // at the goal from state 3 on
  // Jerk of x = t³ sampled at dt: the third difference is 6 dt³ exactly.
  std::vector<std::vector<double>> cubic;
  for (int t = 0; t < 8; ++t) cubic.push_back({std::pow(t * dt, 3), 0.0});
  const PlanQuality c = MeasurePlans(DiscPlan(cubic), *disc, dt, 1e-3)[0];
  EXPECT_NEAR(c.mean_squared_jerk, 36.0 / 2.0, 1e-2);  // mean over 2 joints, one of them still
  EXPECT_NEAR(c.duration, 0.7, 1e-12);
  // An arm plan's TCP length follows its FK.
  const auto arm = Franka();
  torch::Tensor plan = torch::zeros({1, 2, 14});
  plan[0][1][0] = 0.5f;
  const torch::Tensor tcp = arm->Tcp(plan[0].slice(1, 0, 7).to(torch::kFloat64));
  EXPECT_NEAR(MeasurePlans(plan, *arm, dt, 1e-3)[0].tcp_path_length, (tcp[1] - tcp[0]).norm().item<double>(), 1e-9);
}

}  // namespace
}  // namespace flowplan::validity
