// The guidance costs: their written-out gradients against finite differences
// and autograd in double precision, hand-computed values, and scenes.

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <fstream>

#include "core/error.h"
#include "guidance/collision_cost.h"
#include "guidance/guide.h"
#include "guidance/scene.h"
#include "guidance/smoothness_cost.h"
#include "kinematics/arm_kinematics.h"
#include "sim/franka_model.h"
#include "tests/support/scratch_dir.h"

namespace flowplan::guidance {
namespace {

using ::testing::HasSubstr;
using ::testing::ThrowsMessage;

std::shared_ptr<const kinematics::Robot> Franka() {
  static const auto robot = kinematics::MakeRobot(sim::LoadFrankaModel().description());
  return robot;
}

std::shared_ptr<const kinematics::Robot> Disc(double radius) {
  return kinematics::MakeRobot(kinematics::PointRobot("disc", 2, radius, 0.0, 1.0));
}

/// Central differences of Σ_b cost(x)_b in every entry of x, float64.
torch::Tensor NumericGradient(const Cost& cost, const torch::Tensor& x, const torch::Tensor& obstacles) {
  torch::Tensor numeric = torch::zeros_like(x);
  const double h = 1e-6;
  auto flat_x = x.view({-1});
  auto flat_g = numeric.view({-1});
  for (int64_t i = 0; i < flat_x.numel(); ++i) {
    torch::Tensor plus = x.clone(), minus = x.clone();
    plus.view({-1})[i] += h;
    minus.view({-1})[i] -= h;
    flat_g[i] = (cost.Value(plus, obstacles).sum().item<double>() - cost.Value(minus, obstacles).sum().item<double>()) /
                (2 * h);
  }
  return numeric;
}

torch::Tensor AutogradGradient(const Cost& cost, const torch::Tensor& x, const torch::Tensor& obstacles) {
  const torch::Tensor leaf = x.clone().requires_grad_(true);
  return torch::autograd::grad({cost.Value(leaf, obstacles).sum()}, {leaf})[0];
}

/// A Franka trajectory (B, T, 14) of random joint angles within the limits and velocities.
torch::Tensor FrankaTrajectory(int64_t B, int64_t T, uint64_t seed) {
  torch::manual_seed(seed);
  const auto& d = Franka()->description();
  const torch::Tensor lo = torch::tensor(d.joint_lower, torch::kFloat64), hi = torch::tensor(d.joint_upper, torch::kFloat64);
  const torch::Tensor q = lo + (hi - lo) * (0.2 + 0.6 * torch::rand({B, T, 7}, torch::kFloat64));
  return torch::cat({q, torch::randn({B, T, 7}, torch::kFloat64)}, 2);
}

TEST(CollisionCostTest, FrankaGradientMatchesFiniteDifferencesAndAutograd) {
  const torch::Tensor x = FrankaTrajectory(2, 4, 1);
  // Obstacles placed on sphere centres of the trajectory, so that many pairs are active.
  const torch::Tensor centres = Franka()->Spheres(x.slice(2, 0, 7).reshape({-1, 7})).centres;  // (8, S, 3)
  const torch::Tensor obstacles = torch::cat(
      {torch::stack({centres[1][30] + 0.03, centres[6][50] - 0.02}), torch::tensor({{0.12}, {0.2}}, torch::kFloat64)}, 1);
  const CollisionCost cost(Franka(), 0.05);
  const CostAndGradient written = cost.ValueAndGradient(x, obstacles);
  EXPECT_GT(written.value.min().item<double>(), 0.0) << "the test needs active pairs in every trajectory";
  EXPECT_TRUE(torch::allclose(written.value, cost.Value(x, obstacles), 0, 1e-12));
  const torch::Tensor numeric = NumericGradient(cost, x, obstacles);
  EXPECT_LT((written.gradient - numeric).abs().max().item<double>(), 1e-6 * std::max(1.0, numeric.abs().max().item<double>()));
  EXPECT_LT((written.gradient - AutogradGradient(cost, x, obstacles)).abs().max().item<double>(), 1e-10);
  // Velocities do not enter.
  EXPECT_EQ(written.gradient.slice(2, 7, 14).abs().max().item<double>(), 0.0);
}

TEST(CollisionCostTest, HandComputedHingeOfADiscAndTwoSpheres) {
  // Disc of radius 0.1 at (0.5, 0.5); obstacles: radius 0.2 at (0.5, 0.8), 0.3 away (reach 0.05 + 0.1 + 0.2 = 0.35:
  // penetration 0.05), and radius 0.1 at (0.1, 0.5), 0.4 away (reach 0.25: none).
  const CollisionCost cost(Disc(0.1), 0.05);
  const torch::Tensor x = torch::tensor({0.5, 0.5, 0.0, 0.0}, torch::kFloat64).view({1, 1, 4});
  const torch::Tensor obstacles = torch::tensor({{0.5, 0.8, 0.2}, {0.1, 0.5, 0.1}}, torch::kFloat64);
  const CostAndGradient r = cost.ValueAndGradient(x, obstacles);
  EXPECT_NEAR(r.value.item<double>(), 0.05, 1e-12);
  // The gradient points from the obstacle to the disc, negated: moving towards +y raises the cost.
  EXPECT_NEAR(r.gradient[0][0][0].item<double>(), 0.0, 1e-12);
  EXPECT_NEAR(r.gradient[0][0][1].item<double>(), 1.0, 1e-12);
  // Two states, the second one inside both: 0.05 + (0.35 − 0.3) ... summed over states.
  const torch::Tensor two = torch::tensor({{0.5, 0.5, 0.0, 0.0}, {0.2, 0.55, 0.0, 0.0}}, torch::kFloat64).view({1, 2, 4});
  const double d1 = std::hypot(0.3, 0.25), d2 = std::hypot(0.1, 0.05);
  EXPECT_NEAR(cost.Value(two, obstacles).item<double>(), 0.05 + std::max(0.0, 0.35 - d1) + (0.25 - d2), 1e-12);
}

TEST(CollisionCostTest, ZeroFarFromEveryObstacleAndWithoutObstacles) {
  const torch::Tensor x = FrankaTrajectory(3, 8, 2);
  const CollisionCost cost(Franka(), 0.05);
  const CostAndGradient far = cost.ValueAndGradient(x, torch::tensor({{5.0, 5.0, 5.0, 0.5}}, torch::kFloat64));
  EXPECT_EQ(far.value.abs().max().item<double>(), 0.0);
  EXPECT_EQ(far.gradient.abs().max().item<double>(), 0.0);
  const CostAndGradient none = cost.ValueAndGradient(x, torch::zeros({0, 4}, torch::kFloat64));
  EXPECT_EQ(none.value.abs().max().item<double>(), 0.0);
  EXPECT_EQ(none.gradient.sizes(), x.sizes());
}

TEST(SmoothnessCostTest, ZeroAtConstantVelocityAndPositiveOtherwise) {
  const double dt = 1.0 / 15.0;
  const SmoothnessCost cost(7, dt, 1.0);
  const torch::Tensor q0 = torch::randn({2, 1, 7}, torch::kFloat64), v = torch::randn({2, 1, 7}, torch::kFloat64);
  const torch::Tensor steps = torch::arange(64, torch::kFloat64).view({1, 64, 1});
  const torch::Tensor x = torch::cat({q0 + dt * steps * v, v.expand({2, 64, 7})}, 2);
  const torch::Tensor empty = torch::zeros({0, 4});
  EXPECT_LT(cost.Value(x, empty).abs().max().item<double>(), 1e-15);
  EXPECT_LT(cost.ValueAndGradient(x, empty).gradient.abs().max().item<double>(), 1e-9);
  torch::Tensor bent = x.clone();
  bent[0][30][2] += 0.01;
  const torch::Tensor value = cost.Value(bent, empty);
  EXPECT_GT(value[0].item<double>(), 0.0);
  EXPECT_LT(value[1].item<double>(), 1e-15);
  // Hand value of one position offset δ at state i: e_{i-1} = (δ, 0), e_i = (−δ, 0):
  // 2 · 12/dt³ δ² (σ = 1).
  EXPECT_NEAR(value[0].item<double>(), 2 * 12 / (dt * dt * dt) * 1e-4, 1e-6);
}

TEST(SmoothnessCostTest, GradientMatchesFiniteDifferencesAndAutograd) {
  const SmoothnessCost cost(2, 0.05, 0.7);
  torch::manual_seed(3);
  const torch::Tensor x = torch::randn({2, 6, 5}, torch::kFloat64);  // an extra dimension beyond [q, q̇]
  const torch::Tensor empty = torch::zeros({0, 3});
  const CostAndGradient written = cost.ValueAndGradient(x, empty);
  const torch::Tensor numeric = NumericGradient(cost, x, empty);
  EXPECT_LT((written.gradient - numeric).abs().max().item<double>(), 1e-5 * numeric.abs().max().item<double>());
  EXPECT_LT((written.gradient - AutogradGradient(cost, x, empty)).abs().max().item<double>(), 1e-8);
  EXPECT_EQ(written.gradient.select(2, 4).abs().max().item<double>(), 0.0);
}

TEST(GuideTest, WeightedSumGradientAndClipping) {
  GuidanceConfig config;
  config.collision_weight = 2.0;   // states inside the obstacle: norm 2, clipped
  config.smoothness_weight = 1e-6;  // states outside: small, kept
  config.clip = 0.5;
  const auto cost = MakeGuidanceCost(config, Disc(0.05), 0.05);
  const torch::Tensor x = torch::rand({2, 8, 4}, torch::kFloat64);
  const torch::Tensor obstacles = torch::tensor({{0.5, 0.5, 0.3}}, torch::kFloat64);
  const CostAndGradient written = cost->ValueAndGradient(x, obstacles);
  EXPECT_LT((written.gradient - AutogradGradient(*cost, x, obstacles)).abs().max().item<double>(), 1e-10);
  // raw = x_n + 1 (lo 0, hi 2): the chain rule's factor (hi − lo)/2 is 1.
  const Guide guide(cost, models::MinMaxNormalizer(torch::zeros({4}), torch::full({4}, 2.0)), config);
  const torch::Tensor x_n = x.to(torch::kFloat32) - 1.0;
  const torch::Tensor got = guide.Gradient(x_n, obstacles.to(torch::kFloat32));
  // Each term's gradient is capped at norm 0.5 per state before it is weighted.
  torch::Tensor expected = torch::zeros_like(x);
  int64_t clipped = 0;
  for (const auto& term : cost->terms()) {
    torch::Tensor part = term.cost->ValueAndGradient(x, obstacles).gradient;
    const torch::Tensor norm = part.norm(2, -1, true);
    clipped += (norm > 0.5).sum().item<int64_t>();
    part = torch::where(norm > 0.5, part * 0.5 / norm, part);
    expected = expected + term.weight * part;
  }
  EXPECT_GT(clipped, 0) << "the test needs states whose gradient is capped";
  EXPECT_TRUE(torch::allclose(got, expected.to(torch::kFloat32), 1e-5, 1e-6));
  EXPECT_LE(got.norm(2, -1).max().item<float>(), 2.0f * 0.5f + 1e-6f * 0.5f + 1e-5f);
  EXPECT_DOUBLE_EQ(GuidanceFactor(GuidanceSchedule::kOneMinusT, 0.25), 0.75);
  EXPECT_DOUBLE_EQ(GuidanceFactor(GuidanceSchedule::kRatio, 0.25), 3.0);
  EXPECT_DOUBLE_EQ(GuidanceFactor(GuidanceSchedule::kRatio, 0.0), 1.0 / kMinRatioTime);
}

TEST(RobotTest, SphereVectorJacobianProductMatchesAutograd) {
  torch::manual_seed(4);
  const torch::Tensor q = FrankaTrajectory(1, 5, 4).slice(2, 0, 7).squeeze(0);
  const torch::Tensor g = torch::randn({5, Franka()->num_spheres(), 3}, torch::kFloat64);
  const kinematics::SpherePoses poses = Franka()->Spheres(q);
  const torch::Tensor leaf = q.clone().requires_grad_(true);
  const torch::Tensor autograd =
      torch::autograd::grad({(Franka()->Spheres(leaf).centres * g).sum()}, {leaf})[0];
  EXPECT_LT((Franka()->SpheresVjp(poses, g) - autograd).abs().max().item<double>(), 1e-10);
}

std::string WriteScene(const std::string& name, const std::string& text) {
  const std::string path = (flowplan::testing::ScratchDir() / name).string();
  std::ofstream(path) << text;
  return path;
}

TEST(SceneTest, FileIsReadIntoObstacleRows) {
  const std::string path =
      WriteScene("two.yaml", "spheres:\n  - {centre: [0.5, 0.0, 0.2], radius: 0.1}\n  - centre: [0.1, 0.2, 0.3]\n    radius: 0\n");
  const torch::Tensor o = LoadScene(path).Obstacles(3, path);
  EXPECT_TRUE(torch::equal(o, torch::tensor({{0.5f, 0.0f, 0.2f, 0.1f}, {0.1f, 0.2f, 0.3f, 0.0f}})));
  EXPECT_EQ(LoadScene(WriteScene("empty.yaml", "spheres: []\n")).Obstacles(3, "x").size(0), 0);
}

TEST(SceneTest, BadScenesNameTheFileAndEntry) {
  const std::string negative = WriteScene("negative.yaml", "spheres:\n  - {centre: [0.5, 0.0, 0.2], radius: -0.1}\n");
  EXPECT_THAT([&] { LoadScene(negative); },
              ThrowsMessage<Error>(HasSubstr("negative.yaml:2: spheres[0].radius: expected a non-negative value, got \"-0.1\"")));
  const std::string nan = WriteScene("nan.yaml", "spheres:\n  - {centre: [0.5, 0.0, 0.2], radius: .nan}\n");
  EXPECT_THAT([&] { LoadScene(nan); }, ThrowsMessage<Error>(HasSubstr("spheres[0].radius: expected a number")));
  const std::string flat = WriteScene("flat.yaml", "spheres:\n  - {centre: [0.5, 0.0], radius: 0.1}\n");
  EXPECT_THAT([&] { LoadScene(flat).Obstacles(3, flat); },
              ThrowsMessage<Error>(HasSubstr("flat.yaml: spheres[0].centre: expected 3 values (the robot's workspace is 3-D), got 2")));
  const std::string missing = WriteScene("missing.yaml", "spheres:\n  - {centre: [0.5, 0.0, 0.2]}\n");
  EXPECT_THAT([&] { LoadScene(missing).Obstacles(3, missing); },
              ThrowsMessage<Error>(HasSubstr("missing.yaml: spheres[0].radius: missing")));
  const std::string typo = WriteScene("typo.yaml", "spheres:\n  - {center: [0.5, 0.0, 0.2], radius: 0.1}\n");
  EXPECT_THAT([&] { LoadScene(typo); }, ThrowsMessage<Error>(HasSubstr("spheres[0].center: unknown key")));
}

}  // namespace
}  // namespace flowplan::guidance
