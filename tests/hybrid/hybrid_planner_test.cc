// The hybrid planner (hybrid/hybrid_planner.h) on the particle, with a
// proposer whose plan is known exactly: a network that returns a fixed
// trajectory in one Euler step. Plans are checked by plain geometry and
// finite differences, not by the plan checker the hybrid uses.

#include "hybrid/hybrid_planner.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>

#include "kinematics/robot.h"
#include "tests/support/planners.h"

namespace flowplan::hybrid {
namespace {


constexpr int64_t kT = 32;
constexpr double kDt = 1.0 / 15.0;

/// The particle in the unit square, at most 1 unit/s along each axis.
kinematics::TrajectoryInfo Particle() {
  kinematics::TrajectoryInfo info = testing::DiscTrajectory(kT);
  info.dt = kDt;
  info.robot = kinematics::PointRobot("disc", 2, 0.05, 0.0, 1.0);
  info.robot.velocity_limit = {1.0, 1.0};
  return info;
}

const torch::Tensor kStart = torch::tensor({0.1, 0.1}, torch::kFloat64);
const torch::Tensor kGoal = torch::tensor({0.9, 0.1}, torch::kFloat64);

/// (T, 4) from (0.1, 0.1) to (0.9, 0.1) along y = 0.1: resting at the start for T − 4 states, then across in three
/// steps of 0.27 (4 units/s, four times the limit).
torch::Tensor Dash() {
  std::vector<torch::Tensor> rows(kT - 3, kStart);
  for (double u : {1.0 / 3.0, 2.0 / 3.0, 1.0}) rows.push_back(kStart + u * (kGoal - kStart));
  const torch::Tensor q = torch::stack(rows);
  return torch::cat({q, torch::zeros_like(q)}, 1).to(torch::kFloat32);
}

/// A flow planner whose plan is `target` (T, 4): the network's velocity target − x, integrated in one Euler
/// step; guidance as given, with five end-game steps.
std::unique_ptr<planning::LearnedPlanner> Proposer(const torch::Tensor& target, guidance::GuidanceConfig guidance) {
  auto net = std::make_shared<testing::ScriptedNet>(
      4, std::vector<std::string>{"out = self.p_target.expand_as(x) - x"},
      std::vector<std::pair<std::string, torch::Tensor>>{{"target", target}});
  planning::PlannerParts parts = testing::Parts(net, Particle(), testing::UnitNormalizer(4));
  parts.sampler.steps = 1;
  parts.sampler.final_iterations = 5;
  parts.guidance = guidance;
  return planning::AssemblePlanner(parts);
}

HybridPlanner Hybrid(const torch::Tensor& target, HybridConfig config, guidance::GuidanceConfig guidance = {}) {
  const kinematics::TrajectoryInfo info = Particle();
  return HybridPlanner(Proposer(target, guidance), std::make_unique<classical::RrtConnectPlanner>(info, classical::RrtConnectConfig{}),
                       validity::PlanChecker(kinematics::MakeRobot(info.robot), kDt, validity::CheckConfig{}),
                       config);
}

/// One proposal, made with guidance only (not unguided first).
HybridConfig OneGuidedProposal(bool seeded) {
  HybridConfig config;
  config.proposals = 1;
  config.seeded_fallback = seeded;
  config.unguided_first = false;
  return config;
}

guidance::GuidanceConfig Unguided() {
  guidance::GuidanceConfig guidance;
  guidance.scale = 0.0;
  return guidance;
}

planning::PlanRequest Request(const torch::Tensor& disc) {
  planning::PlanRequest request;
  request.start = torch::cat({kStart, torch::zeros({2}, torch::kFloat64)}).view({1, 4}).to(torch::kFloat32);
  request.goal = torch::cat({kGoal, torch::zeros({2}, torch::kFloat64)}).view({1, 4}).to(torch::kFloat32);
  request.scene = geometry::SphereRows(disc);
  request.seed = 7;
  return request;
}

/// The largest speed along either axis between consecutive positions of a plan (T, 4), units/s.
double LargestSpeed(const torch::Tensor& plan) {
  const torch::Tensor p = plan.slice(1, 0, 2).to(torch::kFloat64);
  return ((p.slice(0, 1) - p.slice(0, 0, kT - 1)).abs() / kDt).max().item<double>();
}

TEST(HybridPlannerTest, AProposalThatIsOnlyTooFastIsRetimedAlongItsOwnPath) {
  // A disc far from the line: the dash (proposed as it is, unguided) is clear of it but four times too fast.
  const planning::PlanRequest request = Request(torch::tensor({{0.5f, 0.8f, 0.1f}}));
  const kinematics::TrajectoryInfo info = Particle();
  const validity::PlanChecker checker(kinematics::MakeRobot(info.robot), kDt, validity::CheckConfig{});
  ASSERT_EQ(checker.Check(Dash().unsqueeze(0), request.start[0], request.goal[0], request.scene, {})[0].failure,
            validity::Failure::kSpeedLimit);
  const planning::PlanResult result = Hybrid(Dash(), OneGuidedProposal(/*seeded=*/true), Unguided()).Plan(request);
  ASSERT_TRUE(result.found[0].item<bool>());
  EXPECT_EQ(result.route[0], "proposal 1 of 1 retimed");
  // The same straight line, timed rest to rest: position start + s(τ)(goal − start), s = 3τ² − 2τ³, velocity
  // s'(τ)/duration (goal − start).
  const torch::Tensor p = result.plans[0].slice(1, 0, 2).to(torch::kFloat64), v = result.plans[0].slice(1, 2, 4).to(torch::kFloat64);
  const double duration = (kT - 1) * kDt;
  for (int64_t i = 0; i < kT; ++i) {
    const double tau = static_cast<double>(i) / (kT - 1), s = 3 * tau * tau - 2 * tau * tau * tau;
    const double rate = 6 * tau * (1 - tau) / duration;
    EXPECT_LT((p[i] - (kStart + s * (kGoal - kStart))).abs().max().item<double>(), 1e-5) << "state " << i;
    EXPECT_LT((v[i] - rate * (kGoal - kStart)).abs().max().item<double>(), 1e-5) << "state " << i;
  }
  EXPECT_LT(LargestSpeed(result.plans[0]), 1.0);
}

TEST(HybridPlannerTest, AProposalThroughTheDiscIsRetimedInVainAndReplannedAroundIt) {
  // The disc sits on the line: the re-timed dash is refused too, so RRT-Connect plans around it.
  const planning::PlanRequest request = Request(torch::tensor({{0.5f, 0.1f, 0.05f}}));
  const planning::PlanResult result = Hybrid(Dash(), OneGuidedProposal(/*seeded=*/false), Unguided()).Plan(request);
  ASSERT_TRUE(result.found[0].item<bool>());
  EXPECT_EQ(result.route[0], "rrt_connect");
  const torch::Tensor p = result.plans[0].slice(1, 0, 2).to(torch::kFloat64);
  const torch::Tensor u = torch::linspace(0, 1, 21, torch::kFloat64).view({1, -1, 1});
  const torch::Tensor dense = p.slice(0, 0, kT - 1).unsqueeze(1) + u * (p.slice(0, 1) - p.slice(0, 0, kT - 1)).unsqueeze(1);
  EXPECT_GT((dense - torch::tensor({0.5, 0.1}, torch::kFloat64)).norm(2, -1).min().item<double>(), 0.05 + 0.05);
  EXPECT_LE(LargestSpeed(result.plans[0]), 1.0 + 1e-6);
}

TEST(HybridPlannerTest, UnguidedFirstKeepsTheUnguidedProposalWhenItIsValid) {
  // A disc 0.03 clear of the particle's path, inside the guidance margin of 0.1: guidance pushes the plan away,
  // while the unguided plan is valid as it is (the checker's margin is 0).
  const planning::PlanRequest request = Request(torch::tensor({{0.5f, 0.23f, 0.05f}}));
  guidance::GuidanceConfig guidance;
  guidance.scale = 0.05;
  guidance.collision_weight = 1.0;
  guidance.margin = 0.1;
  HybridConfig config;
  config.proposals = 1;
  config.unguided_first = true;
  const planning::PlanResult first = Hybrid(Dash(), config, guidance).Plan(request);
  ASSERT_TRUE(first.found[0].item<bool>());
  EXPECT_EQ(first.route[0], "proposal 1 of 1 unguided retimed");
  config.unguided_first = false;
  const planning::PlanResult guided = Hybrid(Dash(), config, guidance).Plan(request);
  ASSERT_TRUE(guided.found[0].item<bool>());
  EXPECT_EQ(guided.route[0], "proposal 1 of 1 retimed");
  // The unguided plan is the dash's line; the guided one was pushed off it (away from the disc, to lower y).
  const torch::Tensor y_first = first.plans[0].slice(1, 1, 2), y_guided = guided.plans[0].slice(1, 1, 2);
  EXPECT_LT((y_first - 0.1).abs().max().item<float>(), 1e-6);
  EXPECT_LT(y_guided.min().item<float>(), 0.1f - 1e-3f);
}

}  // namespace
}  // namespace flowplan::hybrid
