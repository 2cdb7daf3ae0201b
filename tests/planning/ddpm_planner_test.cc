#include "planning/ddpm_planner.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>

#include "core/error.h"

namespace flowplan::planning {
namespace {

/// The ideal noise predictor for data that is always `target` (T, D):
/// ε(x_k, k) = (x_k − sqrt(ᾱ_k) target) / sqrt(1 − ᾱ_k).
class OracleNoise : public models::TrajectoryNet {
 public:
  OracleNoise(torch::Tensor target, objectives::DdpmSchedule schedule)
      : target_(std::move(target)), schedule_(std::move(schedule)) {}
  torch::Tensor Forward(const torch::Tensor& x, const torch::Tensor& t, const torch::Tensor&) override {
    const torch::Tensor a = schedule_.alpha_bars.to(x.options()).index_select(0, t.to(torch::kInt64)).view({-1, 1, 1});
    return (x - a.sqrt() * target_) / (1.0 - a).sqrt();
  }
  void CheckHorizon(int64_t) const override {}
  std::string WriteScript(jit::ScriptWriter&) const override { return ""; }
  int64_t state_dim() const override { return target_.size(1); }
  int64_t cond_dim() const override { return 0; }

 private:
  torch::Tensor target_;
  objectives::DdpmSchedule schedule_;
};

TEST(DdpmPlannerTest, AnIdealNoisePredictorSamplesTheDataFromPureNoise) {
  objectives::DdpmConfig config;  // MPD's 25 steps
  const objectives::DdpmSchedule schedule(config);
  const torch::Tensor target = 0.5 * torch::sin(torch::linspace(0, 3, 16)).view({16, 1}).expand({16, 2}).contiguous();
  auto net = std::make_shared<OracleNoise>(target, schedule);
  models::MinMaxNormalizer unit(-torch::ones({2}), torch::ones({2}));  // raw == normalized
  const DdpmPlanner planner(net, unit, models::Conditioning::kInpaint, 16, config, DdpmSamplerConfig{}, {});
  torch::manual_seed(2);
  const torch::Tensor start = target[0].expand({3, 2}), goal = target[15].expand({3, 2});
  const torch::Tensor plans =
      planner.PlanWithNoise(start, goal, torch::randn({3, 16, 2}), torch::randn({3, 24, 16, 2}));
  EXPECT_LT((plans - target.unsqueeze(0)).abs().max().item<float>(), 1e-4);
  // The first step already starts from (nearly) pure noise: ᾱ_{N−1} < 1e-3.
  EXPECT_LT(schedule.alpha_bar(24), 1e-3);
  EXPECT_THAT([&] { planner.PlanWithNoise(start, goal, torch::randn({3, 16, 2}), torch::randn({3, 16, 2})); },
              ::testing::ThrowsMessage<Error>(::testing::HasSubstr("renoise: expected the noise of the DDPM steps (3, 24, 16, 2)")));
}

/// The ideal noise predictor for data whose every entry is N(mu, sigma²), independent:
/// E[ε | x_k] = sqrt(1 − ᾱ) (x_k − sqrt(ᾱ) mu) / (ᾱ sigma² + 1 − ᾱ).
class GaussianNoise : public models::TrajectoryNet {
 public:
  GaussianNoise(double mu, double sigma, objectives::DdpmSchedule schedule, int64_t D)
      : mu_(mu), var_(sigma * sigma), schedule_(std::move(schedule)), D_(D) {}
  torch::Tensor Forward(const torch::Tensor& x, const torch::Tensor& t, const torch::Tensor&) override {
    const torch::Tensor a = schedule_.alpha_bars.to(x.options()).index_select(0, t.to(torch::kInt64)).view({-1, 1, 1});
    return (1.0 - a).sqrt() * (x - a.sqrt() * mu_) / (a * var_ + 1.0 - a);
  }
  void CheckHorizon(int64_t) const override {}
  std::string WriteScript(jit::ScriptWriter&) const override { return ""; }
  int64_t state_dim() const override { return D_; }
  int64_t cond_dim() const override { return 0; }

 private:
  double mu_, var_;
  objectives::DdpmSchedule schedule_;
  int64_t D_;
};

TEST(DdpmPlannerTest, AncestralSamplingOfAGaussianMatchesItsMeanAndVariance) {
  // Data N(0.2, 0.3²) per entry and its exact noise predictor: every step of
  // the sampler is then linear-Gaussian, and the mean m and variance v of its
  // samples follow in closed form from the schedule (DDPM's posterior
  // q(x_{k−1} | x_k, x0) with variance β̃_k; derived here, not taken from the
  // planner). 25 large steps with β̃ give a standard deviation below the
  // data's (about 0.27): the chain, not the data, is the reference.
  const double mu = 0.2, sigma = 0.3;
  objectives::DdpmConfig config;
  const objectives::DdpmSchedule schedule(config);
  auto net = std::make_shared<GaussianNoise>(mu, sigma, schedule, 2);
  models::MinMaxNormalizer unit(-torch::ones({2}), torch::ones({2}));
  const DdpmPlanner planner(net, unit, models::Conditioning::kInpaint, 8, config, DdpmSamplerConfig{}, {});
  double m = 0.0, v = 1.0;  // x_{N−1}: pure noise
  auto step = [&](int k, bool noisy) {
    const double a = schedule.alpha_bar(k), a_before = schedule.alpha_bar_before(k), beta = schedule.beta(k);
    const double s = std::sqrt(1 - a) / (a * sigma * sigma + 1 - a);            // ε̂ = s (x − sqrt(a) mu)
    const double gain_x0 = 1 / std::sqrt(a) - std::sqrt(1 / a - 1) * s;          // x̂0 = gain_x0 x + shift_x0
    const double shift_x0 = std::sqrt(1 / a - 1) * s * std::sqrt(a) * mu;
    const double c1 = beta * std::sqrt(a_before) / (1 - a), c2 = (1 - a_before) * std::sqrt(1 - beta) / (1 - a);
    m = (c1 * gain_x0 + c2) * m + c1 * shift_x0;
    v = (c1 * gain_x0 + c2) * (c1 * gain_x0 + c2) * v + (noisy ? beta * (1 - a_before) / (1 - a) : 0.0);
  };
  for (int k = 24; k >= 0; --k) step(k, k > 0);
  for (int e = 0; e < DdpmSamplerConfig{}.extra_steps; ++e) step(0, false);
  torch::manual_seed(8);
  const int64_t B = 4096;
  const torch::Tensor ends = torch::full({B, 2}, 0.2f);
  const torch::Tensor plans =
      planner.PlanWithNoise(ends, ends, torch::randn({B, 8, 2}), torch::randn({B, 24, 8, 2}));
  const torch::Tensor interior = plans.slice(1, 1, 7).to(torch::kFloat64);  // 49,152 samples
  EXPECT_NEAR(interior.mean().item<double>(), m, 0.004);
  EXPECT_NEAR(interior.std().item<double>(), std::sqrt(v), 0.01 * std::sqrt(v));
  EXPECT_NEAR(m, mu, 0.01);
  EXPECT_NEAR(std::sqrt(v), sigma, 0.15 * sigma);
}

TEST(DdpmPlannerTest, GuidanceInTheGuidedStepsAndTheExtraStepsPushesOutOfAnObstacle) {
  // With the guided window empty (fraction 0) and no extra steps the oracle's plan is untouched;
  // the last quarter of the steps alone, or the extra steps alone, push it out.
  objectives::DdpmConfig config;
  const objectives::DdpmSchedule schedule(config);
  const torch::Tensor target = torch::zeros({16, 2});
  auto net = std::make_shared<OracleNoise>(target, schedule);
  models::MinMaxNormalizer unit(-torch::ones({2}), torch::ones({2}));
  guidance::GuidanceConfig guidance;
  guidance.collision_weight = 1.0;
  guidance.smoothness_weight = 0.0;
  auto disc = kinematics::MakeRobot(kinematics::PointRobot("disc", 2, 0.05, -1.0, 1.0));
  const torch::Tensor start = torch::tensor({{-0.9f, 0.0f}}), goal = torch::tensor({{0.9f, 0.0f}});
  torch::manual_seed(4);
  const torch::Tensor noise = torch::randn({1, 16, 2}), renoise = torch::randn({1, 24, 16, 2});
  const torch::Tensor obstacle = torch::tensor({{0.0f, -0.03f, 0.2f}});  // off centre: a defined push direction
  auto plan = [&](double fraction, int extra) {
    DdpmSamplerConfig sampler;
    sampler.guide_fraction = fraction;
    sampler.extra_steps = extra;
    const DdpmPlanner planner(net, unit, models::Conditioning::kInpaint, 16, config, sampler,
                              GuidanceSetup{disc, 0.1, guidance});
    return planner.PlanWithNoise(start, goal, noise, renoise, obstacle);
  };
  const torch::Tensor free = plan(0.0, 0);
  // The oracle puts every interior state at the origin, inside the obstacle;
  // guidance in the last steps pushes them out.
  EXPECT_LT(free.slice(1, 1, 15).norm(2, -1).max().item<float>(), 1e-4);
  for (const auto& [fraction, extra] : {std::pair{0.25, 0}, std::pair{0.0, 5}, std::pair{0.25, 5}}) {
    const torch::Tensor guided = plan(fraction, extra);
    EXPECT_GT(guided.slice(1, 1, 15).norm(2, -1).min().item<float>(), 0.01) << fraction << " " << extra;
  }
}

}  // namespace
}  // namespace flowplan::planning
