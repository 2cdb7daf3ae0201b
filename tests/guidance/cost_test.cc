// The guidance cost terms (guidance/*.py): their written-out gradients against
// central differences and autograd in float64, hand-computed values, a user's
// cost with its autograd gradient, and the guide's weighting and clipping.

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <fstream>

#include "core/error.h"
#include "guidance/guide.h"
#include "jit/library.h"
#include "kinematics/robot.h"
#include "models/normalizer.h"
#include "sim/franka_model.h"
#include "tests/support/scratch_dir.h"

namespace flowplan::guidance {
namespace {

using ::testing::HasSubstr;
using ::testing::ThrowsMessage;

const kinematics::Robot& Franka() {
  static const kinematics::Robot robot(sim::LoadFrankaModel().description());
  return robot;
}

kinematics::Robot Disc(double radius) { return kinematics::Robot(kinematics::PointRobot("disc", 2, radius, 0.0, 1.0)); }

/// The settings a call passes to the costs.
c10::Dict<std::string, double> Opts(const GuidanceConfig& config) {
  c10::Dict<std::string, double> opts;
  for (const auto& [key, value] : config::ListNumbers(config, "guidance")) opts.insert(key, value);
  return opts;
}

/// The guide of `config` for `robot` (raw == normalized states when `unit`).
torch::jit::Module Guide(const GuidanceConfig& config, const kinematics::Robot& robot, double dt = 0.05) {
  const int64_t D = 2 * robot.num_joints();
  const models::MinMaxNormalizer unit(-torch::ones({D}), torch::ones({D}));
  return BuildGuide(config, robot, unit.module(), dt);
}

/// Term k of the guide's chain (0 collision, 1 smoothness, 2 joint limit, 3 the user's).
torch::jit::Module Term(const torch::jit::Module& guide, int k) {
  torch::jit::Module chain = guide.attr("costs").toModule();
  for (int i = 0; i < k; ++i) chain = chain.attr("rest").toModule();
  return chain.attr("term").toModule();
}

struct Evaluated {
  torch::Tensor value, grad_q, grad_qd;  // (B,), (B, T, J), (B, T, J)
};

Evaluated Evaluate(const torch::jit::Module& term, const torch::Tensor& q, const torch::Tensor& qd,
                   const geometry::SceneRows& scene, const c10::Dict<std::string, double>& opts) {
  const auto out = jit::Call(term, "value_and_gradient", {q, qd, scene, opts}).toTuple()->elements();
  return {out[0].toTensor(), out[1].toTensor(), out[2].toTensor()};
}

/// Central differences of Σ_b value in every entry of q and qd, float64.
std::pair<torch::Tensor, torch::Tensor> Numeric(const torch::jit::Module& term, const torch::Tensor& q,
                                                const torch::Tensor& qd, const geometry::SceneRows& scene,
                                                const c10::Dict<std::string, double>& opts) {
  const double h = 1e-6;
  std::vector<torch::Tensor> out;
  for (int which = 0; which < 2; ++which) {
    const torch::Tensor x = which == 0 ? q : qd;
    torch::Tensor g = torch::zeros_like(x);
    for (int64_t i = 0; i < x.numel(); ++i) {
      torch::Tensor plus = x.clone(), minus = x.clone();
      plus.view({-1})[i] += h;
      minus.view({-1})[i] -= h;
      const double up = Evaluate(term, which ? q : plus, which ? plus : qd, scene, opts).value.sum().item<double>();
      const double down = Evaluate(term, which ? q : minus, which ? minus : qd, scene, opts).value.sum().item<double>();
      g.view({-1})[i] = (up - down) / (2 * h);
    }
    out.push_back(g);
  }
  return {out[0], out[1]};
}

std::pair<torch::Tensor, torch::Tensor> Autograd(const torch::jit::Module& term, const torch::Tensor& q,
                                                 const torch::Tensor& qd, const geometry::SceneRows& scene,
                                                 const c10::Dict<std::string, double>& opts) {
  const torch::Tensor a = q.clone().requires_grad_(true), b = qd.clone().requires_grad_(true);
  const auto grads = torch::autograd::grad({Evaluate(term, a, b, scene, opts).value.sum()}, {a, b}, {}, false, false, true);
  return {grads[0].defined() ? grads[0] : torch::zeros_like(q), grads[1].defined() ? grads[1] : torch::zeros_like(qd)};
}

double Largest(const torch::Tensor& t) { return t.abs().max().item<double>(); }

/// Random Franka joint angles inside the limits, (B, T, 7), and velocities.
std::pair<torch::Tensor, torch::Tensor> FrankaStates(int64_t B, int64_t T, uint64_t seed) {
  torch::manual_seed(seed);
  const auto& d = Franka().description();
  const torch::Tensor lo = torch::tensor(d.joint_lower, torch::kFloat64), hi = torch::tensor(d.joint_upper, torch::kFloat64);
  return {lo + (hi - lo) * (0.2 + 0.6 * torch::rand({B, T, 7}, torch::kFloat64)), torch::randn({B, T, 7}, torch::kFloat64)};
}

TEST(CollisionCostTest, FrankaGradientMatchesFiniteDifferencesAndAutogradForEveryShape) {
  const auto [q, qd] = FrankaStates(2, 3, 1);
  const torch::Tensor centres = Franka().SphereCentres(q.reshape({-1, 7}));  // (6, S, 3)
  // One obstacle of each shape near a sphere centre of the trajectory, so that pairs are active (off it by a few
  // cm: a sphere centre exactly on a cylinder's or capsule's axis has no defined gradient).
  auto at = [&](int n, int s) { return centres[n][s] + torch::tensor({0.013, -0.021, 0.017}, torch::kFloat64); };
  geometry::SceneRows scene;
  scene.insert("spheres", torch::cat({at(1, 30) + 0.03, torch::tensor({0.12}, torch::kFloat64)}).view({1, 4}));
  scene.insert("boxes", torch::cat({at(4, 50) - 0.02, torch::tensor({0.2, 0.1, 0.15, 0.9, 0.1, 0.3, -0.2},
                                                                   torch::kFloat64)}).view({1, 10}));
  scene.insert("cylinders", torch::cat({at(2, 10), torch::tensor({0.08, 0.3, 0.7, 0.7, 0.0, 0.1}, torch::kFloat64)})
                                .view({1, 9}));
  scene.insert("capsules", torch::cat({at(5, 20) - 0.05, at(5, 20) + 0.08, torch::tensor({0.05}, torch::kFloat64)})
                               .view({1, 7}));
  GuidanceConfig config;
  const torch::jit::Module collision = Term(Guide(config, Franka()), 0);
  const auto opts = Opts(config);
  const Evaluated written = Evaluate(collision, q, qd, scene, opts);
  EXPECT_GT(written.value.min().item<double>(), 0.0) << "the test needs active pairs in every trajectory";
  const auto [numeric_q, numeric_qd] = Numeric(collision, q, qd, scene, opts);
  EXPECT_LT(Largest(written.grad_q - numeric_q), 1e-6 * std::max(1.0, Largest(numeric_q)));
  EXPECT_LT(Largest(written.grad_q - Autograd(collision, q, qd, scene, opts).first), 1e-10);
  // Velocities do not enter.
  EXPECT_EQ(Largest(written.grad_qd), 0.0);
  EXPECT_EQ(Largest(numeric_qd), 0.0);
}

TEST(CollisionCostTest, HandComputedHingeOfADiscAndTwoSpheresAndABox) {
  // Disc of radius 0.1 at (0.5, 0.5); obstacles: radius 0.2 at (0.5, 0.8), 0.3 away (reach 0.05 + 0.1 + 0.2 = 0.35:
  // penetration 0.05), and radius 0.1 at (0.1, 0.5), 0.4 away (reach 0.25: none).
  GuidanceConfig config;
  const kinematics::Robot disc = Disc(0.1);
  const torch::jit::Module collision = Term(Guide(config, disc), 0);
  const auto opts = Opts(config);
  geometry::SceneRows scene = geometry::SphereRows(torch::tensor({{0.5, 0.8, 0.2}, {0.1, 0.5, 0.1}}, torch::kFloat64));
  const torch::Tensor q = torch::tensor({0.5, 0.5}, torch::kFloat64).view({1, 1, 2}), qd = torch::zeros({1, 1, 2}, torch::kFloat64);
  const Evaluated r = Evaluate(collision, q, qd, scene, opts);
  EXPECT_NEAR(r.value.item<double>(), 0.05, 1e-12);
  // Moving towards +y (into the obstacle) raises the cost.
  EXPECT_NEAR(r.grad_q[0][0][0].item<double>(), 0.0, 1e-12);
  EXPECT_NEAR(r.grad_q[0][0][1].item<double>(), 1.0, 1e-12);
  // A square of side 0.2 below the disc, its top face 0.12 below the disc's centre: penetration 0.15 − 0.12.
  scene.insert("boxes", torch::tensor({{0.5, 0.28, 0.2, 0.2, 0.0}}, torch::kFloat64));
  EXPECT_NEAR(Evaluate(collision, q, qd, scene, opts).value.item<double>(), 0.05 + 0.03, 1e-12);
}

TEST(CollisionCostTest, ZeroFarFromEveryObstacleAndWithoutObstacles) {
  const auto [q, qd] = FrankaStates(3, 8, 2);
  GuidanceConfig config;
  const torch::jit::Module collision = Term(Guide(config, Franka()), 0);
  geometry::SceneRows far = geometry::SphereRows(torch::tensor({{5.0, 5.0, 5.0, 0.5}}, torch::kFloat64));
  far.insert("boxes", torch::tensor({{-5.0, 5.0, 5.0, 1.0, 1.0, 1.0, 1.0, 0.0, 0.0, 0.0}}, torch::kFloat64));
  const Evaluated away = Evaluate(collision, q, qd, far, Opts(config));
  EXPECT_EQ(Largest(away.value), 0.0);
  EXPECT_EQ(Largest(away.grad_q), 0.0);
  const Evaluated none = Evaluate(collision, q, qd, geometry::SceneRows(), Opts(config));
  EXPECT_EQ(Largest(none.value), 0.0);
  EXPECT_EQ(none.grad_q.sizes(), q.sizes());
}

TEST(SmoothnessCostTest, ZeroAtConstantVelocityHandValueAndGradients) {
  const double dt = 1.0 / 15.0;
  GuidanceConfig config;
  const torch::jit::Module smoothness = Term(Guide(config, Franka(), dt), 1);
  const auto opts = Opts(config);
  const torch::Tensor q0 = torch::randn({2, 1, 7}, torch::kFloat64), v = torch::randn({2, 1, 7}, torch::kFloat64);
  const torch::Tensor steps = torch::arange(64, torch::kFloat64).view({1, 64, 1});
  const torch::Tensor q = q0 + dt * steps * v, qd = v.expand({2, 64, 7}).contiguous();
  const Evaluated straight = Evaluate(smoothness, q, qd, geometry::SceneRows(), opts);
  EXPECT_LT(Largest(straight.value), 1e-15);
  EXPECT_LT(Largest(straight.grad_q), 1e-9);
  torch::Tensor bent = q.clone();
  bent[0][30][2] += 0.01;
  const torch::Tensor value = Evaluate(smoothness, bent, qd, geometry::SceneRows(), opts).value;
  EXPECT_LT(value[1].item<double>(), 1e-15);
  // One position offset δ at state i: e_{i-1} = (δ, 0), e_i = (−δ, 0): 2 · 12/dt³ δ² (σ = 1).
  EXPECT_NEAR(value[0].item<double>(), 2 * 12 / (dt * dt * dt) * 1e-4, 1e-6);
  // Gradients against differences and autograd, σ = 0.7 per call.
  GuidanceConfig other = config;
  other.smoothness_sigma = 0.7;
  torch::manual_seed(3);
  const torch::Tensor a = torch::randn({2, 6, 7}, torch::kFloat64), b = torch::randn({2, 6, 7}, torch::kFloat64);
  const Evaluated written = Evaluate(smoothness, a, b, geometry::SceneRows(), Opts(other));
  const auto [numeric_q, numeric_qd] = Numeric(smoothness, a, b, geometry::SceneRows(), Opts(other));
  EXPECT_LT(Largest(written.grad_q - numeric_q), 1e-5 * Largest(numeric_q));
  EXPECT_LT(Largest(written.grad_qd - numeric_qd), 1e-5 * Largest(numeric_qd));
  const auto [auto_q, auto_qd] = Autograd(smoothness, a, b, geometry::SceneRows(), Opts(other));
  EXPECT_LT(Largest(written.grad_q - auto_q), 1e-8 * Largest(auto_q));
  EXPECT_LT(Largest(written.grad_qd - auto_qd), 1e-8 * Largest(auto_qd));
}

TEST(JointLimitCostTest, HingeOnTheDistanceToTheLimits) {
  GuidanceConfig config;
  config.joint_limit_margin = 0.1;
  const torch::jit::Module limits = Term(Guide(config, Disc(0.05)), 2);  // the disc's limits: [0, 1] per axis
  // x 0.05 below 0 + 0.1 → 0.05; y 0.97 above 1 − 0.1 → 0.07; then a state well inside.
  const torch::Tensor q = torch::tensor({{{0.05, 0.97}, {0.5, 0.5}}}, torch::kFloat64);
  const torch::Tensor qd = torch::zeros_like(q);
  const Evaluated r = Evaluate(limits, q, qd, geometry::SceneRows(), Opts(config));
  EXPECT_NEAR(r.value.item<double>(), 0.05 + 0.07, 1e-12);
  EXPECT_TRUE(torch::equal(r.grad_q, torch::tensor({{{-1.0, 1.0}, {0.0, 0.0}}}, torch::kFloat64)));
  const auto [numeric_q, numeric_qd] = Numeric(limits, q, qd, geometry::SceneRows(), Opts(config));
  EXPECT_LT(Largest(r.grad_q - numeric_q), 1e-6);
  // Off by default: the guide does not run for it alone.
  EXPECT_FALSE(jit::Call(Guide(GuidanceConfig{}, Disc(0.05)), "active", {geometry::SceneRows(), Opts(GuidanceConfig{})}).toBool());
  EXPECT_TRUE(jit::Call(Guide(config, Disc(0.05)), "active",
                        {geometry::SceneRows(), Opts([&] {
                           GuidanceConfig on = config;
                           on.joint_limit_weight = 1.0;
                           return on;
                         }())}).toBool());
}

TEST(JointSpeedCostTest, SquaredHingeOnTheSpeedsBetweenStatesMatchesHandValuesAndFiniteDifferences) {
  GuidanceConfig config;
  config.joint_speed_ratio = 0.5;
  const double dt = 0.1;
  const torch::jit::Module speed = Term(Guide(config, Franka(), dt), 3);
  const auto& limits = Franka().description().velocity_limit;  // rad/s
  // Joint 0 moves at 0.8 of its limit, then 0.3: only the first step is over 0.5, by 0.3; joint 3 at 1.5 of its
  // limit backwards, by 1.0; every other joint stands still.
  torch::Tensor q = torch::zeros({1, 3, 7}, torch::kFloat64);
  q[0][1][0] = 0.8 * limits[0] * dt;
  q[0][2][0] = (0.8 + 0.3) * limits[0] * dt;
  q[0][1][3] = -1.5 * limits[3] * dt;
  q[0][2][3] = -1.5 * limits[3] * dt;
  const torch::Tensor qd = torch::zeros_like(q);
  const Evaluated r = Evaluate(speed, q, qd, geometry::SceneRows(), Opts(config));
  EXPECT_NEAR(r.value.item<double>(), 0.3 * 0.3 + 1.0 * 1.0, 1e-9);
  // dC/dq_1 of joint 0: +2 (0.3) / (v dt) from the first step; of joint 3: -2 (1.0) / (v dt), and back on q_0.
  EXPECT_NEAR(r.grad_q[0][1][0].item<double>(), 2 * 0.3 / (limits[0] * dt), 1e-9);
  EXPECT_NEAR(r.grad_q[0][0][0].item<double>(), -2 * 0.3 / (limits[0] * dt), 1e-9);
  EXPECT_NEAR(r.grad_q[0][1][3].item<double>(), -2 * 1.0 / (limits[3] * dt), 1e-9);
  EXPECT_NEAR(r.grad_q[0][0][3].item<double>(), 2 * 1.0 / (limits[3] * dt), 1e-9);
  EXPECT_EQ(Largest(r.grad_qd), 0.0);
  // Random fast plans: the written gradient is the finite differences' and autograd's.
  torch::manual_seed(11);
  const torch::Tensor fast = torch::randn({2, 6, 7}, torch::kFloat64) * 0.5;
  const Evaluated f = Evaluate(speed, fast, torch::zeros_like(fast), geometry::SceneRows(), Opts(config));
  EXPECT_GT(f.value.min().item<double>(), 0.0) << "the test needs speeds over the hinge";
  const auto [numeric_q, numeric_qd] =
      Numeric(speed, fast, torch::zeros_like(fast), geometry::SceneRows(), Opts(config));
  EXPECT_LT(Largest(f.grad_q - numeric_q), 1e-5 * Largest(numeric_q));
  const auto [auto_q, auto_qd] = Autograd(speed, fast, torch::zeros_like(fast), geometry::SceneRows(), Opts(config));
  EXPECT_LT(Largest(f.grad_q - auto_q), 1e-9 * Largest(auto_q));
  // A robot without velocity limits has no cost, and the term never makes the guide run alone.
  const Evaluated none = Evaluate(Term(Guide(config, Disc(0.05)), 3), torch::rand({1, 4, 2}, torch::kFloat64) * 5,
                                  torch::zeros({1, 4, 2}, torch::kFloat64), geometry::SceneRows(), Opts(config));
  EXPECT_EQ(none.value.item<double>(), 0.0);
  EXPECT_EQ(Largest(none.grad_q), 0.0);
  GuidanceConfig on = config;
  on.joint_speed_weight = 1.0;
  on.collision_weight = 0.0;
  EXPECT_FALSE(jit::Call(Guide(on, Franka()), "active", {geometry::SceneRows(), Opts(on)}).toBool());
}

std::string WriteFile(const std::string& name, const std::string& text) {
  const std::string path = (flowplan::testing::ScratchDir() / name).string();
  std::ofstream(path) << text;
  return path;
}

TEST(UserCostTest, GradientByAutogradAlsoUnderNoGradAndAClearErrorUnderInferenceMode) {
  // Keep the disc above y = 0.6: sum over states of relu(0.6 − y)², with the robot's TCP.
  GuidanceConfig config;
  config.user_cost = WriteFile("above.py", R"PY(
def cost(self, q: Tensor, qd: Tensor, scene: Dict[str, Tensor]) -> Tensor:
    height = self.robot.tcp(q)[:, :, 1]
    return (torch.relu(0.6 - height) ** 2).sum(1) + 0.0 * qd.sum([1, 2])
)PY");
  const torch::jit::Module user = Term(Guide(config, Disc(0.05)), 4);
  const torch::Tensor q = torch::tensor({{{0.2, 0.5}, {0.3, 0.7}}}, torch::kFloat64), qd = torch::zeros_like(q);
  torch::NoGradGuard no_grad;  // as a planner calls it
  const Evaluated r = Evaluate(user, q, qd, geometry::SceneRows(), Opts(config));
  EXPECT_NEAR(r.value.item<double>(), 0.01, 1e-12);
  EXPECT_TRUE(torch::allclose(r.grad_q, torch::tensor({{{0.0, -0.2}, {0.0, 0.0}}}, torch::kFloat64), 0, 1e-12));
  EXPECT_FALSE(at::GradMode::is_enabled()) << "the cost restores the caller's grad mode";
  {
    c10::InferenceMode inference;
    const torch::Tensor qi = torch::tensor({{{0.2, 0.5}}}, torch::kFloat64);
    EXPECT_THAT([&] { Evaluate(user, qi, torch::zeros_like(qi), geometry::SceneRows(), Opts(config)); },
                ThrowsMessage<Error>(HasSubstr("above.py: a user cost takes its gradient by autograd, which cannot run "
                                               "under torch.inference_mode(); plan under torch.no_grad() instead")));
  }
}

TEST(UserCostTest, TheShippedExampleKeepsTheFrankaTcpAbove25Centimetres) {
  // configs/costs/tcp_above.py (docs/planning.md): Σ_t relu(0.25 − z_t)² of the TCP height z.
  GuidanceConfig config;
  config.user_cost = std::string(FLOWPLAN_SOURCE_DIR) + "/configs/costs/tcp_above.py";
  const torch::jit::Module user = Term(Guide(config, Franka()), 4);
  const auto [q, qd] = FrankaStates(2, 4, 7);
  const torch::Tensor z = Franka().Tcp(q.reshape({-1, 7})).select(1, 2).reshape({2, 4});
  ASSERT_TRUE((z < 0.25).any().item<bool>() && (z > 0.25).any().item<bool>()) << "states on both sides of 0.25 m";
  torch::NoGradGuard no_grad;
  const Evaluated r = Evaluate(user, q, qd, geometry::SceneRows(), Opts(config));
  EXPECT_TRUE(torch::allclose(r.value, torch::relu(0.25 - z).pow(2).sum(1), 0, 1e-12));
  const auto [numeric_q, numeric_qd] = Numeric(user, q, qd, geometry::SceneRows(), Opts(config));
  EXPECT_TRUE(torch::allclose(r.grad_q, numeric_q, 1e-6, 1e-7)) << (r.grad_q - numeric_q).abs().max();
  EXPECT_TRUE(torch::allclose(r.grad_qd, torch::zeros_like(qd)));
}

TEST(UserCostTest, SeesTheObstacleRowsAsTheCallGaveThem) {
  // A planning call prepares its scene (boxes carry their rotation matrices after their 10 columns); a user
  // cost still gets the rows as given: here its value is the boxes' column count and their sum.
  GuidanceConfig config;
  config.user_cost = WriteFile("columns.py", R"PY(
def cost(self, q: Tensor, qd: Tensor, scene: Dict[str, Tensor]) -> Tensor:
    boxes = scene["boxes"]
    return torch.full([q.size(0)], float(boxes.size(1)), dtype=q.dtype) + boxes.sum().to(q.dtype) + 0.0 * q.sum([1, 2])
)PY");
  const torch::jit::Module user = Term(Guide(config, Franka()), 4);
  const auto [q, qd] = FrankaStates(2, 3, 5);
  geometry::SceneRows scene;
  const torch::Tensor box = torch::tensor({{0.5, 0.1, 0.3, 0.2, 0.1, 0.05, 0.9, 0.1, 0.3, -0.2}}, torch::kFloat64);
  scene.insert("boxes", box);
  const auto prepared = jit::CallFunction("prepared_scene", {scene, static_cast<int64_t>(3)}).toGenericDict();
  ASSERT_EQ(prepared.at("boxes").toTensor().size(1), 19);
  geometry::SceneRows as_prepared;
  as_prepared.insert("boxes", prepared.at("boxes").toTensor());
  torch::NoGradGuard no_grad;
  const Evaluated r = Evaluate(user, q, qd, as_prepared, Opts(config));
  EXPECT_TRUE(torch::allclose(r.value, torch::full({2}, 10.0 + box.sum().item<double>(), torch::kFloat64), 0, 1e-12))
      << r.value;
}

TEST(UserCostTest, BadFilesAreOneClearError) {
  GuidanceConfig config;
  config.user_cost = WriteFile("typo.py", "def cost(self, q: Tensor, qd: Tensor, scene: Dict[str, Tensor]) -> Tensor:\n"
                                          "    return q.sum([1, 2) \n");
  EXPECT_THAT([&] { Guide(config, Disc(0.05)); },
              ThrowsMessage<Error>(HasSubstr("guidance.user_cost: " + config.user_cost + ": does not compile as TorchScript")));
  config.user_cost = WriteFile("free.py", "def cost(q: Tensor, qd: Tensor, scene: Dict[str, Tensor]) -> Tensor:\n"
                                          "    return q.sum([1, 2])\n");
  EXPECT_THAT([&] { Guide(config, Disc(0.05)); },
              ThrowsMessage<Error>(HasSubstr("expected a method `def cost(self, q: Tensor")));
  config.user_cost = "/nonexistent/cost.py";
  EXPECT_THAT([&] { Guide(config, Disc(0.05)); },
              ThrowsMessage<Error>(HasSubstr("guidance.user_cost: /nonexistent/cost.py: no such file")));
  config.user_cost = WriteFile("shape.py", "def cost(self, q: Tensor, qd: Tensor, scene: Dict[str, Tensor]) -> Tensor:\n"
                                           "    return q.sum()\n");
  const torch::jit::Module user = Term(Guide(config, Disc(0.05)), 4);
  EXPECT_THAT([&] { Evaluate(user, torch::zeros({2, 3, 2}), torch::zeros({2, 3, 2}), geometry::SceneRows(), Opts(config)); },
              ThrowsMessage<Error>(HasSubstr("shape.py: cost: expected a value per trajectory (2,), got []")));
}

TEST(GuideTest, WeightedSumOfClippedTermsAndTheSchedules) {
  GuidanceConfig config;
  config.collision_weight = 2.0;    // states inside the obstacle: norm 1, clipped to 0.5
  config.smoothness_weight = 1e-6;  // small, kept
  config.clip = 0.5;
  const kinematics::Robot disc = Disc(0.05);
  const torch::jit::Module guide = Guide(config, disc);
  const auto opts = Opts(config);
  torch::manual_seed(5);
  const torch::Tensor x = torch::rand({2, 8, 4}, torch::kFloat64);  // raw == normalized here
  const geometry::SceneRows scene = geometry::SphereRows(torch::tensor({{0.5, 0.5, 0.3}}, torch::kFloat64));
  const torch::Tensor got = jit::Call(guide, "gradient", {x, scene, opts}).toTensor();
  torch::Tensor expected = torch::zeros_like(x);
  int64_t clipped = 0;
  for (const auto& [k, weight] : {std::pair{0, 2.0}, std::pair{1, 1e-6}}) {
    const Evaluated r = Evaluate(Term(guide, k), x.slice(2, 0, 2), x.slice(2, 2, 4), scene, opts);
    torch::Tensor part = torch::cat({r.grad_q, r.grad_qd}, 2);
    const torch::Tensor norm = part.norm(2, -1, true);
    clipped += (norm > 0.5).sum().item<int64_t>();
    part = torch::where(norm > 0.5, part * 0.5 / norm, part);
    expected = expected + weight * part;
  }
  EXPECT_GT(clipped, 0) << "the test needs states whose gradient is capped";
  EXPECT_TRUE(torch::allclose(got, expected, 1e-12, 1e-12));
  // b_t of each schedule.
  auto factor = [](const std::string& schedule, double t) {
    return jit::CallFunction("schedule_factor", {schedule, t}).toDouble();
  };
  EXPECT_DOUBLE_EQ(factor("one_minus_t", 0.25), 0.75);
  EXPECT_DOUBLE_EQ(factor("ratio", 0.25), 3.0);
  EXPECT_DOUBLE_EQ(factor("ratio", 0.0), 1e3);
  EXPECT_DOUBLE_EQ(factor("rising", 0.25), 0.25);
  // A step moves x against scale · b_t times the gradient.
  const torch::Tensor stepped = jit::Call(guide, "step", {x, 0.25, scene, opts, std::string("rising")}).toTensor();
  EXPECT_TRUE(torch::allclose(stepped, x - 0.25 * config.scale * got, 1e-12, 1e-12));
}

}  // namespace
}  // namespace flowplan::guidance
