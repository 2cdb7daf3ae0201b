// RRT-Connect's plans, checked without its validity checker: the particle's
// path against the disc by plain geometry, the Franka's plan executed in
// MuJoCo among obstacles that are collision bodies.

#include "classical/rrt_connect.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <set>

#include "core/error.h"
#include "core/random.h"
#include "kinematics/robot.h"
#include "sim/franka_execution.h"
#include "sim/franka_model.h"
#include "tests/support/planners.h"

namespace flowplan::classical {
namespace {

constexpr double kDt = 1.0 / 15.0;

/// A disc of radius 0.05 in the unit square, T states.
kinematics::TrajectoryInfo Disc(int64_t T) {
  kinematics::TrajectoryInfo info = testing::DiscTrajectory(T);
  info.dt = kDt;
  info.robot = kinematics::PointRobot("disc", 2, 0.05, 0.0, 1.0);
  return info;
}

geometry::SceneRows Disc05() { return geometry::SphereRows(torch::tensor({{0.5f, 0.5f, 0.2f}})); }

/// Check settings with a margin: the plans below keep 1 cm from every obstacle.
validity::CheckConfig Margin() {
  validity::CheckConfig check;
  check.margin = 0.01;
  return check;
}

TEST(RrtConnectTest, ParticleGoesAroundADiscWithConsistentVelocities) {
  const RrtConnectPlanner planner(Disc(64), RrtConnectConfig{}, Margin());
  planning::PlanRequest request;
  request.start = torch::tensor({{0.1f, 0.5f, 0.0f, 0.0f}, {0.2f, 0.45f, 0.0f, 0.0f}});
  request.goal = torch::tensor({{0.9f, 0.5f, 0.0f, 0.0f}, {0.8f, 0.55f, 0.0f, 0.0f}});
  request.scene = Disc05();
  request.seed = 3;
  const planning::PlanResult result = planner.Plan(request);
  ASSERT_EQ(result.plans.sizes(), torch::IntArrayRef({2, 64, 4}));
  EXPECT_TRUE(result.found.all().item<bool>());
  ASSERT_EQ(result.call_seconds.size(), 2u);
  EXPECT_EQ(result.call_plans, (std::vector<int64_t>{1, 1}));
  const torch::Tensor plans = result.plans.to(torch::kFloat64);
  for (int64_t b = 0; b < 2; ++b) {
    const torch::Tensor p = plans[b].slice(1, 0, 2), v = plans[b].slice(1, 2, 4);
    EXPECT_LT((p[0] - request.start[b].slice(0, 0, 2)).abs().max().item<double>(), 1e-6);
    EXPECT_LT((p[-1] - request.goal[b].slice(0, 0, 2)).abs().max().item<double>(), 1e-6);
    // Every point on the straight pieces between the states keeps the disc's radius clear.
    const torch::Tensor s = torch::linspace(0, 1, 21, torch::kFloat64).view({1, -1, 1});
    const torch::Tensor dense = p.slice(0, 0, 63).unsqueeze(1) + s * (p.slice(0, 1) - p.slice(0, 0, 63)).unsqueeze(1);
    const double clearance = (dense - torch::tensor({0.5, 0.5}, torch::kFloat64)).norm(2, -1).min().item<double>();
    EXPECT_GT(clearance, 0.2 + 0.05 + 0.01 - 0.0005);  // the margin, less half the motion check's resolution
    // The velocities are those of the positions' timing; the plan starts and stops at rest.
    const torch::Tensor central = (p.slice(0, 2) - p.slice(0, 0, 62)) / (2 * kDt);
    const double speed = v.norm(2, 1).max().item<double>();
    EXPECT_LT((central - v.slice(0, 1, 63)).norm(2, 1).max().item<double>(), 0.15 * speed);
    EXPECT_LT(v[0].abs().max().item<double>(), 1e-9);
    EXPECT_LT(v[-1].abs().max().item<double>(), 1e-9);
  }
}

TEST(RrtConnectTest, SameSeedSamePlansAndEachPlanIsItsOwnSearch) {
  const RrtConnectPlanner planner(Disc(32), RrtConnectConfig{});
  planning::PlanRequest request;
  request.start = torch::tensor({{0.1f, 0.5f, 0.0f, 0.0f}, {0.1f, 0.5f, 0.0f, 0.0f}});
  request.goal = torch::tensor({{0.9f, 0.5f, 0.0f, 0.0f}, {0.9f, 0.5f, 0.0f, 0.0f}});
  request.scene = Disc05();
  request.seed = 7;
  const torch::Tensor a = planner.Plan(request).plans;
  EXPECT_TRUE(torch::equal(a, planner.Plan(request).plans));
  planning::PlanRequest first = request;
  first.start = request.start.slice(0, 0, 1);
  first.goal = request.goal.slice(0, 0, 1);
  EXPECT_TRUE(torch::equal(a.slice(0, 0, 1), planner.Plan(first).plans));
}

/// B requests from (0.1, 0.5) to (0.9, 0.5), straight through the disc of Disc05.
planning::PlanRequest PastTheDisc(int64_t B, uint64_t seed) {
  planning::PlanRequest request;
  request.start = torch::tensor({0.1f, 0.5f, 0.0f, 0.0f}).repeat({B, 1});
  request.goal = torch::tensor({0.9f, 0.5f, 0.0f, 0.0f}).repeat({B, 1});
  request.scene = Disc05();
  request.seed = seed;
  return request;
}

/// The least distance from Disc05's centre of the straight pieces between a plan's (T, 4) states, each sampled at
/// 21 points: plain geometry.
double DiscCentreDistance(const torch::Tensor& plan) {
  const torch::Tensor p = plan.to(torch::kFloat64).slice(1, 0, 2);
  const int64_t T = p.size(0);
  const torch::Tensor s = torch::linspace(0, 1, 21, torch::kFloat64).view({1, -1, 1});
  const torch::Tensor dense = p.slice(0, 0, T - 1).unsqueeze(1) + s * (p.slice(0, 1) - p.slice(0, 0, T - 1)).unsqueeze(1);
  return (dense - torch::tensor({0.5, 0.5}, torch::kFloat64)).norm(2, -1).min().item<double>();
}

// With a budget too small for one search to go around the disc every time, further attempts find plans the first
// search did not, keep the plans it did find bit for bit, and every plan found clears the disc (plain geometry).
TEST(RrtConnectTest, FurtherAttemptsFindWhatOneSearchMissesAndKeepWhatItFound) {
  constexpr int64_t B = 24;
  RrtConnectConfig once;
  once.max_iterations = 6;
  RrtConnectConfig thrice = once;
  thrice.attempts = 3;
  const planning::PlanRequest request = PastTheDisc(B, 5);
  const planning::PlanResult one = RrtConnectPlanner(Disc(32), once).Plan(request);
  const planning::PlanResult three = RrtConnectPlanner(Disc(32), thrice).Plan(request);
  const int64_t found_once = one.found.sum().item<int64_t>(), found_thrice = three.found.sum().item<int64_t>();
  ASSERT_GT(found_once, 0);
  ASSERT_LT(found_once, B) << "the budget is large enough for every search: the test shows nothing";
  EXPECT_GT(found_thrice, found_once);
  for (int64_t b = 0; b < B; ++b) {
    if (one.found[b].item<bool>()) {
      EXPECT_TRUE(three.found[b].item<bool>());
      EXPECT_TRUE(torch::equal(one.plans[b], three.plans[b])) << "plan " << b;
    }
    if (!three.found[b].item<bool>()) {
      EXPECT_THAT(three.failure[static_cast<size_t>(b)], ::testing::HasSubstr("found no path within 6 iterations"));
      continue;
    }
    EXPECT_EQ(three.failure[static_cast<size_t>(b)], "");
    EXPECT_GT(DiscCentreDistance(three.plans[b]), 0.2 + 0.05 - 0.0005) << "plan " << b;
  }
}

// A path found but too long to time within the speed limits fails the plan check; a further search finds another,
// and plans found at the first search are kept bit for bit. Unsimplified paths, so that some are long.
TEST(RrtConnectTest, APathTooLongToTimeWithinTheSpeedLimitsIsFollowedByAFurtherSearch) {
  constexpr int64_t B = 24;
  constexpr double kSpeed = 1.0;  // m/s in x and in y: 16 states (1 s) cover at most this far in each
  kinematics::TrajectoryInfo info = Disc(16);
  info.robot.velocity_limit = {kSpeed, kSpeed};
  RrtConnectConfig once;
  once.simplify = false;
  RrtConnectConfig thrice = once;
  thrice.attempts = 3;
  const planning::PlanRequest request = PastTheDisc(B, 8);
  const planning::PlanResult one = RrtConnectPlanner(info, once).Plan(request);
  const planning::PlanResult three = RrtConnectPlanner(info, thrice).Plan(request);
  int too_long = 0, recovered = 0;
  for (int64_t b = 0; b < B; ++b) {
    const std::string& why = one.failure[static_cast<size_t>(b)];
    if (one.found[b].item<bool>()) {
      EXPECT_TRUE(torch::equal(one.plans[b], three.plans[b])) << "plan " << b;
    } else if (why.find("the timed path fails the plan check") != std::string::npos) {
      EXPECT_THAT(why, ::testing::HasSubstr("x its speed limit"));
      ++too_long;
      recovered += three.found[b].item<bool>();
    }
    if (!three.found[b].item<bool>()) continue;
    // Found plans keep to the speed limit and clear the disc, by plain arithmetic on the states.
    const torch::Tensor p = three.plans[b].to(torch::kFloat64).slice(1, 0, 2);
    const double fastest = (p.slice(0, 1) - p.slice(0, 0, -1)).abs().max().item<double>() / kDt;
    EXPECT_LE(fastest, kSpeed * (1.0 + 1e-4)) << "plan " << b;
    EXPECT_GT(DiscCentreDistance(three.plans[b]), 0.2 + 0.05 - 0.0005) << "plan " << b;
  }
  ASSERT_GT(too_long, 0) << "every first path could be timed: the test shows nothing";
  EXPECT_GT(recovered, 0);
}

TEST(RrtConnectTest, AStartInsideAnObstacleOrPastALimitIsRefusedWithItsReason) {
  const RrtConnectPlanner planner(Disc(16), RrtConnectConfig{});
  planning::PlanRequest request;
  request.start = torch::tensor({{0.5f, 0.5f, 0.0f, 0.0f}, {1.2f, 0.5f, 0.0f, 0.0f}, {1.0f, 0.5f, 0.0f, 0.0f}});
  request.goal = torch::tensor({{0.9f, 0.5f, 0.0f, 0.0f}, {0.9f, 0.5f, 0.0f, 0.0f}, {0.9f, 0.9f, 0.0f, 0.0f}});
  request.scene = Disc05();
  const planning::PlanResult result = planner.Plan(request);
  EXPECT_FALSE(result.found[0].item<bool>());
  EXPECT_FALSE(result.found[1].item<bool>());
  EXPECT_EQ(result.refused, (std::vector<bool>{true, true, false}));
  EXPECT_THAT(result.failure[0], ::testing::HasSubstr("start: the robot is -0.25 from obstacle 0"));
  EXPECT_THAT(result.failure[1], ::testing::HasSubstr("start: joint 1 = 1.2 is 0.2 past its upper limit 1"));
  // A start exactly at a limit is planned from it.
  EXPECT_TRUE(result.found[2].item<bool>());
  EXPECT_EQ(result.failure[2], "");
  EXPECT_LT((result.plans[0].select(1, 1) - 0.5).abs().max().item<float>(), 1e-6);  // the line it falls back to
}

/// The particle's guide of T states along the straight line from (0.1, 0.5) to (0.9, 0.5), bent by `bend` × sin(πs)
/// in y: (1, T, 4), velocities zero (they are not read).
torch::Tensor Guide(int64_t T, double bend) {
  const torch::Tensor s = torch::linspace(0.0, 1.0, T, torch::kFloat64);
  const torch::Tensor x = 0.1 + 0.8 * s, y = 0.5 + bend * torch::sin(M_PI * s);
  return torch::stack({x, y, torch::zeros_like(s), torch::zeros_like(s)}, 1).unsqueeze(0).to(torch::kFloat32);
}

/// Distance of each point p (N, 2) from the polyline `line` (M, 2): (N,).
torch::Tensor DistanceToPolyline(const torch::Tensor& p, const torch::Tensor& line) {
  const torch::Tensor a = line.slice(0, 0, -1), ab = line.slice(0, 1) - a;             // (M−1, 2)
  const torch::Tensor ap = p.unsqueeze(1) - a.unsqueeze(0);                            // (N, M−1, 2)
  const torch::Tensor u = ((ap * ab).sum(-1) / (ab * ab).sum(-1)).clamp(0.0, 1.0);     // (N, M−1)
  return (ap - u.unsqueeze(-1) * ab).norm(2, -1).amin(1);
}

planning::PlanRequest AcrossTheDisc() {
  planning::PlanRequest request;
  request.start = torch::tensor({{0.1f, 0.5f, 0.0f, 0.0f}});
  request.goal = torch::tensor({{0.9f, 0.5f, 0.0f, 0.0f}});
  request.scene = Disc05();
  request.seed = 5;
  return request;
}

TEST(RrtConnectTest, AValidGuideIsFollowedWithoutSearch) {
  // A guide arching over the disc (0.35 above the centre at its middle) is valid as a whole: unsimplified, the
  // plan's positions lie on it.
  RrtConnectConfig config;
  config.simplify = false;
  const RrtConnectPlanner planner(Disc(32), config);
  const planning::PlanRequest request = AcrossTheDisc();
  const torch::Tensor guide = Guide(16, 0.35);
  const planning::PlanResult result = planner.PlanAlong(request, guide);
  ASSERT_TRUE(result.found[0].item<bool>());
  const torch::Tensor p = result.plans[0].slice(1, 0, 2).to(torch::kFloat64);
  const torch::Tensor line = guide[0].slice(1, 0, 2).to(torch::kFloat64);
  EXPECT_LT(DistanceToPolyline(p, line).max().item<double>(), 1e-5);
}

/// The largest angle (degrees) between consecutive non-zero displacements of positions p (T, 2).
double LargestTurn(const torch::Tensor& p) {
  const torch::Tensor d = p.slice(0, 1) - p.slice(0, 0, -1);
  const torch::Tensor moving = d.index({d.norm(2, 1) > 1e-9});
  const torch::Tensor u = moving / moving.norm(2, 1, true);
  const torch::Tensor cosine = (u.slice(0, 1) * u.slice(0, 0, -1)).sum(1).clamp(-1.0, 1.0);
  return torch::acos(cosine).max().item<double>() * 180.0 / M_PI;
}

TEST(RrtConnectTest, SimplifyingShortensAGuideAndRoundsItsCornerWithoutTouchingTheDisc) {
  // A tent over the disc: straight up to (0.5, 0.9) and down again, 9 states a leg, a right angle at the top.
  // Unsimplified, the plan keeps the corner; simplified, it is shorter, turns by less than 20° between states
  // and still clears the disc.
  std::vector<torch::Tensor> rows;
  for (int k = 0; k <= 16; ++k) {
    const double u = k / 16.0, x = 0.1 + 0.8 * u, y = 0.5 + 0.4 * (1.0 - std::abs(2.0 * u - 1.0));
    rows.push_back(torch::tensor({x, y, 0.0, 0.0}, torch::kFloat64));
  }
  const torch::Tensor tent = torch::stack(rows).unsqueeze(0).to(torch::kFloat32);
  const planning::PlanRequest request = AcrossTheDisc();
  RrtConnectConfig as_given;
  as_given.simplify = false;
  const torch::Tensor raw = RrtConnectPlanner(Disc(64), as_given).PlanAlong(request, tent).plans[0].slice(1, 0, 2).to(torch::kFloat64);
  const planning::PlanResult result = RrtConnectPlanner(Disc(64), RrtConnectConfig{}).PlanAlong(request, tent);
  ASSERT_TRUE(result.found[0].item<bool>());
  const torch::Tensor p = result.plans[0].slice(1, 0, 2).to(torch::kFloat64);
  auto length = [](const torch::Tensor& q) { return (q.slice(0, 1) - q.slice(0, 0, -1)).norm(2, 1).sum().item<double>(); };
  EXPECT_GT(LargestTurn(raw), 40.0);  // the right angle, split over the two displacements either side of it
  EXPECT_LT(LargestTurn(p), 20.0) << LargestTurn(p);
  EXPECT_LT(length(p), length(raw) - 0.01);
  const torch::Tensor s = torch::linspace(0, 1, 21, torch::kFloat64).view({1, -1, 1});
  const torch::Tensor dense = p.slice(0, 0, 63).unsqueeze(1) + s * (p.slice(0, 1) - p.slice(0, 0, 63)).unsqueeze(1);
  EXPECT_GT((dense - torch::tensor({0.5, 0.5}, torch::kFloat64)).norm(2, -1).min().item<double>(), 0.2 + 0.05);
  EXPECT_LT((p[0] - torch::tensor({0.1, 0.5}, torch::kFloat64)).abs().max().item<double>(), 1e-6);
  EXPECT_LT((p[63] - torch::tensor({0.9, 0.5}, torch::kFloat64)).abs().max().item<double>(), 1e-6);
}

TEST(RrtConnectTest, AGuideThroughTheDiscKeepsItsValidEndsAndJoinsThem) {
  // The straight guide crosses the disc: the plan starts along it (y = 0.5 exactly, which a search from the start
  // would not give), goes around the disc, and ends along it.
  RrtConnectConfig config;
  config.simplify = false;
  const RrtConnectPlanner planner(Disc(64), config);
  const planning::PlanRequest request = AcrossTheDisc();
  const planning::PlanResult result = planner.PlanAlong(request, Guide(33, 0.0));
  ASSERT_TRUE(result.found[0].item<bool>());
  EXPECT_EQ(result.route, std::vector<std::string>{"seeded"});
  const torch::Tensor p = result.plans[0].slice(1, 0, 2).to(torch::kFloat64);
  EXPECT_LT((p[1][1] - 0.5).abs().item<double>(), 1e-6);
  EXPECT_GT(p[1][0].item<double>(), 0.1);
  EXPECT_LT((p[62][1] - 0.5).abs().item<double>(), 1e-6);
  EXPECT_LT(p[62][0].item<double>(), 0.9);
  const torch::Tensor s = torch::linspace(0, 1, 21, torch::kFloat64).view({1, -1, 1});
  const torch::Tensor dense = p.slice(0, 0, 63).unsqueeze(1) + s * (p.slice(0, 1) - p.slice(0, 0, 63)).unsqueeze(1);
  EXPECT_GT((dense - torch::tensor({0.5, 0.5}, torch::kFloat64)).norm(2, -1).min().item<double>(), 0.2 + 0.05);
  // Without a guide, the same seed's plan leaves the line at once.
  const torch::Tensor unseeded = planner.Plan(request).plans[0].to(torch::kFloat64);
  EXPECT_GT((unseeded[1][1] - 0.5).abs().item<double>(), 1e-6);
}

TEST(RrtConnectTest, AGuideWithNothingToKeepOrNotFinitePlansAsUnseeded) {
  // A guide whose inner states all lie in the disc keeps nothing of itself, and one holding NaN is not used: both
  // plan exactly as Plan does with the same seed, and say so.
  const RrtConnectPlanner planner(Disc(32), RrtConnectConfig{});
  const planning::PlanRequest request = AcrossTheDisc();
  const planning::PlanResult unseeded = planner.Plan(request);
  EXPECT_TRUE(unseeded.route.empty());
  torch::Tensor inside = Guide(8, 0.0);
  inside.slice(1, 1, 7).select(2, 0).fill_(0.5);
  torch::Tensor not_finite = Guide(8, 0.35);
  not_finite[0][3][1] = NAN;
  for (const torch::Tensor& guide : {inside, not_finite}) {
    const planning::PlanResult result = planner.PlanAlong(request, guide);
    EXPECT_TRUE(result.found[0].item<bool>());
    EXPECT_EQ(result.route, std::vector<std::string>{"unseeded"});
    EXPECT_TRUE(torch::equal(result.plans, unseeded.plans));
  }
}

TEST(RrtConnectTest, GuidesOfTheWrongShapeAreRejected) {
  using ::testing::HasSubstr;
  using ::testing::ThrowsMessage;
  const RrtConnectPlanner planner(Disc(16), RrtConnectConfig{});
  EXPECT_THAT([&] { planner.PlanAlong(AcrossTheDisc(), torch::zeros({1, 16, 2})); },
              ThrowsMessage<Error>(HasSubstr("rrt_connect: guide paths of shape [1, 16, 2]; expected (1, T >= 2, 4)")));
}

TEST(RrtConnectTest, RobotsWithoutFiniteLimitsOrOddStatesAreRejected) {
  using ::testing::HasSubstr;
  using ::testing::ThrowsMessage;
  kinematics::TrajectoryInfo odd = Disc(16);
  odd.state_labels = {"x", "y", "vx"};
  EXPECT_THAT([&] { RrtConnectPlanner(odd, RrtConnectConfig{}); },
              ThrowsMessage<Error>(HasSubstr("rrt_connect: states of 3 dimensions")));
  kinematics::TrajectoryInfo unbounded = Disc(16);
  unbounded.robot = kinematics::PointRobot("disc", 2, 0.05, -INFINITY, INFINITY);
  EXPECT_THAT([&] { RrtConnectPlanner(unbounded, RrtConnectConfig{}); },
              ThrowsMessage<Error>(HasSubstr("has no finite range")));
}

/// Plans the Franka once between joint configurations in `scene`, and executes the plan in MuJoCo among the same
/// obstacles as collision geoms.
sim::ExecutionResult PlanAndExecute(const geometry::Scene& scene, const torch::Tensor& start_q,
                                    const torch::Tensor& goal_q, const Eigen::Vector3d& goal_tcp) {
  // Execution tracks the plan within millimetres: the plan keeps a centimetre.
  const RrtConnectPlanner planner(testing::FrankaTrajectory(64), RrtConnectConfig{}, Margin());
  planning::PlanRequest request;
  request.start = torch::cat({start_q.view({1, 7}), torch::zeros({1, 7}, torch::kFloat64)}, 1).to(torch::kFloat32);
  request.goal = torch::cat({goal_q.view({1, 7}), torch::zeros({1, 7}, torch::kFloat64)}, 1).to(torch::kFloat32);
  request.scene = geometry::Rows(scene, 3, "test scene");
  request.seed = 1;
  const planning::PlanResult result = planner.Plan(request);
  EXPECT_TRUE(result.found[0].item<bool>());
  sim::ExecutionConfig config;
  const sim::FrankaModel world = sim::MakeFrankaScene(scene, 1.0 / config.control_hz);
  sim::FrankaExecutor executor(world, static_cast<int>(scene.size()), config);
  const torch::Tensor plan = result.plans[0].to(torch::kFloat64).contiguous();
  const std::vector<double> states(plan.data_ptr<double>(), plan.data_ptr<double>() + plan.numel());
  return executor.Execute(states, 64, kDt, goal_tcp);
}

TEST(RrtConnectTest, FrankaAroundTheSphereExecutesInMujocoWithoutContact) {
  // The paper's scene: TCP from (0.5, −0.3, 0.2) to (0.5, 0.3, 0.2) around a 0.10 m sphere at (0.5, 0, 0.2).
  const kinematics::Robot robot(sim::LoadFrankaModel().description());
  const kinematics::IkSolution ik =
      robot.InverseTcp(torch::tensor({{0.5, -0.3, 0.2}, {0.5, 0.3, 0.2}}, torch::kFloat64));
  ASSERT_TRUE(ik.converged.all().item<bool>());
  geometry::Scene scene;
  scene.spheres = {{{0.5, 0.0, 0.2}, 0.1}};
  const sim::ExecutionResult executed = PlanAndExecute(scene, ik.q[0], ik.q[1], Eigen::Vector3d(0.5, 0.3, 0.2));
  EXPECT_TRUE(executed.contacts.empty()) << executed.contacts.size() << " contacts, first with "
                                         << executed.contacts.front().arm_geom;
  EXPECT_GT(executed.min_distance[0], 0.0);
  EXPECT_LT(executed.goal_distance, 0.03);
}

TEST(RrtConnectTest, FrankaOverABoxWallAndPastACylinderBetweenJointGoals) {
  // Start and goal are joint configurations on either side of a wall (a box,
  // turned 10° about z) with a post (a cylinder) beside it: the arm must lift
  // over the wall. Validity uses the same distances as guidance; MuJoCo's
  // contacts with the shapes as geoms are the independent check.
  const torch::Tensor start_q = torch::tensor({-0.55, 0.35, 0.0, -2.2, 0.0, 2.55, 0.23}, torch::kFloat64);
  const torch::Tensor goal_q = torch::tensor({0.55, 0.35, 0.0, -2.2, 0.0, 2.55, 1.33}, torch::kFloat64);
  const kinematics::Robot robot(sim::LoadFrankaModel().description());
  const torch::Tensor goal_tcp = robot.Tcp(goal_q.view({1, 7}))[0];
  geometry::Scene scene;
  const double turn = 5.0 * M_PI / 180.0;
  scene.boxes = {{{0.5, 0.0, 0.15}, {0.5, 0.04, 0.3}, {std::cos(turn), 0.0, 0.0, std::sin(turn)}, NAN}};
  scene.cylinders = {{{0.25, 0.1, 0.2}, 0.04, 0.4, {}, NAN}};
  const geometry::SceneRows rows = geometry::Rows(scene, 3, "test scene");
  ASSERT_GT(robot.Clearance(torch::stack({start_q, goal_q}), rows).min().item<double>(), 0.02);
  // The straight joint-space line goes through the wall.
  const torch::Tensor line = start_q + torch::linspace(0, 1, 50, torch::kFloat64).view({-1, 1}) * (goal_q - start_q);
  ASSERT_LT(robot.Clearance(line, rows).min().item<double>(), 0.0);
  const sim::ExecutionResult executed = PlanAndExecute(
      scene, start_q, goal_q, Eigen::Vector3d(goal_tcp[0].item<double>(), goal_tcp[1].item<double>(), goal_tcp[2].item<double>()));
  EXPECT_TRUE(executed.contacts.empty()) << executed.contacts.size() << " contacts, first with "
                                         << executed.contacts.front().arm_geom;
  EXPECT_GT(executed.min_distance[0], 0.0);
  EXPECT_GT(executed.min_distance[1], 0.0);
  EXPECT_LT(executed.goal_distance, 0.03);
}

/// Whether the plan (T, 14) is valid by a check that shares nothing with the planner's: the script kinematics'
/// clearance from every obstacle at 40 points of every segment, no sphere of a pair of links the robot checks
/// overlapping there, every joint within its limits and speed limit.
std::string IndependentCheck(const kinematics::Robot& robot, const torch::Tensor& plan, const geometry::SceneRows& scene,
                             double margin) {
  const auto& d = robot.description();
  const int64_t T = plan.size(0);
  const torch::Tensor q = plan.slice(1, 0, 7).to(torch::kFloat64);
  for (int64_t j = 0; j < 7; ++j) {
    if (q.select(1, j).min().item<double>() < d.joint_lower[j] - 1e-6 ||
        q.select(1, j).max().item<double>() > d.joint_upper[j] + 1e-6) {
      return "joint " + std::to_string(j + 1) + " outside its limits";
    }
    const double fastest = (q.slice(0, 1).select(1, j) - q.slice(0, 0, T - 1).select(1, j)).abs().max().item<double>();
    if (fastest / kDt > d.velocity_limit[j] * (1 + 1e-6)) return "joint " + std::to_string(j + 1) + " too fast";
  }
  const torch::Tensor u = torch::linspace(0, 1, 40, torch::kFloat64).view({1, -1, 1});
  const torch::Tensor dense = (q.slice(0, 0, T - 1).unsqueeze(1) + u * (q.slice(0, 1) - q.slice(0, 0, T - 1)).unsqueeze(1))
                                  .reshape({-1, 7});  // (40 (T - 1), 7)
  const double clearance = robot.Clearance(dense, scene).min().item<double>();
  if (clearance < margin - 0.0005) return "clearance " + std::to_string(clearance);
  // Self-collision: every pair of spheres on links the description does not ignore. The gaps of all pairs at 16
  // states at a time, small enough for the allocator to reuse (330 spheres: 16 x 330 x 330 float64 = 14 MB).
  std::set<std::pair<int, int>> ignored;
  for (const auto& pair : d.self_collision_ignore) {
    const int a = d.FindLink(pair[0]), b = d.FindLink(pair[1]);
    ignored.insert({std::min(a, b), std::max(a, b)});
  }
  const int64_t S = robot.num_spheres();
  const torch::Tensor radii = robot.SphereRadii();  // (S,)
  torch::Tensor reach = radii.view({S, 1}) + radii.view({1, S});  // (S, S); -inf for the pairs not checked: gap +inf
  auto r = reach.accessor<double, 2>();
  for (int64_t s = 0; s < S; ++s) {
    for (int64_t t = 0; t < S; ++t) {
      const int a = d.spheres[s].link, b = d.spheres[t].link;
      if (t <= s || a == b || ignored.count({std::min(a, b), std::max(a, b)})) r[s][t] = -INFINITY;
    }
  }
  torch::Tensor closest = torch::full({S, S}, INFINITY, torch::kFloat64);  // (S, S) least gap over the states
  for (const torch::Tensor& piece : dense.split(16)) {
    const torch::Tensor centres = robot.SphereCentres(piece);  // (m, S, 3)
    closest = torch::minimum(closest, std::get<0>(torch::cdist(centres, centres).min(0)) - reach);
  }
  const int64_t worst = closest.argmin().item<int64_t>();
  if (closest.view(-1)[worst].item<double>() < -0.0005) {
    return "spheres " + std::to_string(worst / S) + " and " + std::to_string(worst % S) + " overlap";
  }
  return "";
}

TEST(RrtConnectTest, EveryFrankaPlanItFindsAmongRandomObstaclesPassesAnIndependentCheck) {
  // Random scenes of boxes and spheres around the arm, random valid start and goal: a property of the planner,
  // on a budget that finds most plans; a plan it calls found must be valid.
  const kinematics::TrajectoryInfo info = testing::FrankaTrajectory(64);
  const RrtConnectPlanner planner(info, RrtConnectConfig{});
  const kinematics::Robot robot(info.robot);
  // The independent check finds what it looks for: the hand folded back onto the upper arm, held still.
  torch::Tensor folded = torch::zeros({4, 14});
  const std::vector<double> fold = {0.0, 0.0, 0.0, -3.0, 0.0, 0.2, 0.0};
  for (int j = 0; j < 7; ++j) folded.select(1, j).fill_(fold[static_cast<size_t>(j)]);
  geometry::Scene far;
  far.spheres.push_back({{5.0, 5.0, 5.0}, 0.1});
  EXPECT_NE(IndependentCheck(robot, folded, geometry::Rows(far, 3, "far"), 0.0).find("overlap"), std::string::npos);
  Rng rng(21);
  const auto& d = info.robot;
  int found = 0, planned = 0;
  for (int trial = 0; trial < 40 && planned < 12; ++trial) {
    geometry::Scene scene;
    for (int k = 0; k < 3; ++k) {
      scene.boxes.push_back({{rng.Uniform(0.2, 0.7), rng.Uniform(-0.5, 0.5), rng.Uniform(0.1, 0.8)},
                             {rng.Uniform(0.05, 0.3), rng.Uniform(0.05, 0.3), rng.Uniform(0.05, 0.3)},
                             {rng.Uniform(-1, 1), rng.Uniform(-1, 1), rng.Uniform(-1, 1), rng.Uniform(-1, 1)}, NAN});
      scene.spheres.push_back({{rng.Uniform(-0.6, 0.7), rng.Uniform(-0.6, 0.6), rng.Uniform(0.1, 0.9)}, rng.Uniform(0.03, 0.12)});
    }
    const geometry::SceneRows rows = geometry::Rows(scene, 3, "random scene");
    const collision::Checker check = planner.checker().ConfigurationChecker(rows);
    std::vector<double> ends[2];
    for (auto& end : ends) {
      for (int tries = 0; tries < 200 && end.empty(); ++tries) {
        std::vector<double> q(7);
        for (int j = 0; j < 7; ++j) q[j] = rng.Uniform(d.joint_lower[j], d.joint_upper[j]);
        if (check.Valid(q.data())) end = q;
      }
    }
    if (ends[0].empty() || ends[1].empty()) continue;
    ++planned;
    planning::PlanRequest request;
    request.start = torch::zeros({1, 14});
    request.goal = torch::zeros({1, 14});
    for (int j = 0; j < 7; ++j) {
      request.start[0][j] = ends[0][j];
      request.goal[0][j] = ends[1][j];
    }
    request.scene = rows;
    request.seed = static_cast<uint64_t>(trial);
    const planning::PlanResult result = planner.Plan(request);
    if (!result.found[0].item<bool>()) continue;
    ++found;
    EXPECT_EQ(IndependentCheck(robot, result.plans[0], rows, 0.0), "") << "trial " << trial;
    EXPECT_TRUE(planner.checker().Check(result.plans, request.start[0], request.goal[0], rows)[0].valid());
  }
  EXPECT_GE(planned, 12);
  EXPECT_GE(found, 10);
}

}  // namespace
}  // namespace flowplan::classical
