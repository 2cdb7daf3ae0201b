// The DDPM (MPD) sampler (planning/ddpm_sampler.py) with exact noise
// predictors: sampling reaches the data, the chain's Gaussian moments match
// closed form, and guidance acts where MPD's scheme says.

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>

#include "core/error.h"
#include "objectives/ddpm_schedule.h"
#include "planning/assemble.h"
#include "tests/support/planners.h"

namespace flowplan::planning {
namespace {

/// The ideal noise predictor for data that is always `target` (T, D):
/// ε(x_k, k) = (x_k − sqrt(ᾱ_k) target) / sqrt(1 − ᾱ_k).
std::shared_ptr<models::TrajectoryNet> OracleNoise(const torch::Tensor& target, const objectives::DdpmSchedule& schedule) {
  return std::make_shared<testing::ScriptedNet>(
      target.size(1),
      std::vector<std::string>{"a = self.p_alpha_bars.to(x.dtype).index_select(0, t.long()).view(-1, 1, 1)",
                               "out = (x - torch.sqrt(a) * self.p_target) / torch.sqrt(1.0 - a)"},
      std::vector<std::pair<std::string, torch::Tensor>>{{"alpha_bars", schedule.alpha_bars}, {"target", target}});
}

/// The ideal noise predictor for data whose every entry is N(mu, sigma²), independent:
/// E[ε | x_k] = sqrt(1 − ᾱ) (x_k − sqrt(ᾱ) mu) / (ᾱ sigma² + 1 − ᾱ).
std::shared_ptr<models::TrajectoryNet> GaussianNoise(double mu, double sigma, const objectives::DdpmSchedule& schedule,
                                                     int64_t D) {
  const std::string m = std::to_string(mu), v = std::to_string(sigma * sigma);
  return std::make_shared<testing::ScriptedNet>(
      D,
      std::vector<std::string>{"a = self.p_alpha_bars.to(x.dtype).index_select(0, t.long()).view(-1, 1, 1)",
                               "out = torch.sqrt(1.0 - a) * (x - torch.sqrt(a) * " + m + ") / (a * " + v + " + 1.0 - a)"},
      std::vector<std::pair<std::string, torch::Tensor>>{{"alpha_bars", schedule.alpha_bars}});
}

std::unique_ptr<LearnedPlanner> Ddpm(models::NetworkPtr net, int64_t horizon, DdpmSamplerConfig sampler = {},
                                     guidance::GuidanceConfig guidance = {}) {
  PlannerParts parts = testing::Parts(std::move(net), testing::DiscTrajectory(horizon), testing::UnitNormalizer(4));
  parts.objective.name = objectives::ObjectiveKind::kDdpm;
  parts.sampler.ddpm = sampler;
  parts.guidance = guidance;
  return AssemblePlanner(parts);
}

TEST(DdpmSamplerTest, AnIdealNoisePredictorSamplesTheDataFromPureNoise) {
  objectives::DdpmConfig config;  // MPD's 25 steps
  const objectives::DdpmSchedule schedule(config);
  const torch::Tensor target = 0.5 * torch::sin(torch::linspace(0, 3, 16)).view({16, 1}).expand({16, 4}).contiguous();
  const auto planner = Ddpm(OracleNoise(target, schedule), 16);
  torch::manual_seed(2);
  const torch::Tensor start = target[0].expand({3, 4}), goal = target[15].expand({3, 4});
  const torch::Tensor plans =
      planner->PlanWithNoise(start, goal, torch::randn({3, 16, 4}), torch::randn({3, 24, 16, 4}));
  EXPECT_LT((plans - target.unsqueeze(0)).abs().max().item<float>(), 1e-4);
  // The first step already starts from (nearly) pure noise: ᾱ_{N−1} < 1e-3.
  EXPECT_LT(schedule.alpha_bar(24), 1e-3);
  EXPECT_THAT([&] { planner->PlanWithNoise(start, goal, torch::randn({3, 16, 4}), torch::randn({3, 16, 4})); },
              ::testing::ThrowsMessage<Error>(::testing::HasSubstr("plan: renoise: expected [3, 24, 16, 4], got [3, 16, 4]")));
}

/// Data N(0.2, 0.3²) per entry and its exact noise predictor: every step of
/// the sampler is then linear-Gaussian, and the mean m and variance v of its
/// samples follow in closed form from the schedule (DDPM's posterior
/// q(x_{k−1} | x_k, x0) with variance β̃_k, its standard deviation times
/// `noise_scale`; derived here, not taken from the planner). Checks the
/// planner's samples (49,152 entries) against m and v; returns sqrt(v).
double CheckGaussianChain(double noise_scale) {
  const double mu = 0.2, sigma = 0.3;
  objectives::DdpmConfig config;
  const objectives::DdpmSchedule schedule(config);
  DdpmSamplerConfig sampler;
  sampler.noise_scale = noise_scale;
  const auto planner = Ddpm(GaussianNoise(mu, sigma, schedule, 4), 8, sampler);
  double m = 0.0, v = 1.0;  // x_{N−1}: pure noise
  auto step = [&](int k, bool noisy) {
    const double a = schedule.alpha_bar(k), a_before = schedule.alpha_bar_before(k), beta = schedule.beta(k);
    const double s = std::sqrt(1 - a) / (a * sigma * sigma + 1 - a);            // ε̂ = s (x − sqrt(a) mu)
    const double gain_x0 = 1 / std::sqrt(a) - std::sqrt(1 / a - 1) * s;          // x̂0 = gain_x0 x + shift_x0
    const double shift_x0 = std::sqrt(1 / a - 1) * s * std::sqrt(a) * mu;
    const double c1 = beta * std::sqrt(a_before) / (1 - a), c2 = (1 - a_before) * std::sqrt(1 - beta) / (1 - a);
    const double added = noisy ? noise_scale * noise_scale * beta * (1 - a_before) / (1 - a) : 0.0;
    m = (c1 * gain_x0 + c2) * m + c1 * shift_x0;
    v = (c1 * gain_x0 + c2) * (c1 * gain_x0 + c2) * v + added;
  };
  for (int k = 24; k >= 0; --k) step(k, k > 0);
  for (int e = 0; e < DdpmSamplerConfig{}.extra_steps; ++e) step(0, false);
  torch::manual_seed(8);
  const int64_t B = 2048;
  const torch::Tensor ends = torch::full({B, 4}, 0.2f);
  const torch::Tensor plans =
      planner->PlanWithNoise(ends, ends, torch::randn({B, 8, 4}), torch::randn({B, 24, 8, 4}));
  const torch::Tensor interior = plans.slice(1, 1, 7).to(torch::kFloat64);  // 49,152 samples
  EXPECT_NEAR(interior.mean().item<double>(), m, 0.004) << "noise_scale " << noise_scale;
  EXPECT_NEAR(interior.std().item<double>(), std::sqrt(v), 0.01 * std::sqrt(v)) << "noise_scale " << noise_scale;
  EXPECT_NEAR(m, mu, 0.01);
  return std::sqrt(v);
}

TEST(DdpmSamplerTest, AncestralSamplingOfAGaussianMatchesItsMeanAndVariance) {
  // 25 large steps with β̃ give a standard deviation below the data's (about
  // 0.27): the chain, not the data, is the reference.
  EXPECT_NEAR(CheckGaussianChain(1.0), 0.3, 0.15 * 0.3);
}

TEST(DdpmSamplerTest, HalvedNoiseShrinksTheChainsSpreadAsItsClosedFormSays) {
  // Published MPD's option (sampler.ddpm.noise_scale 0.5): each step adds a
  // quarter of the variance; the samples follow the chain with that noise, and
  // their spread is clearly below the full-noise chain's.
  const double halved = CheckGaussianChain(0.5);
  EXPECT_LT(halved, 0.8 * CheckGaussianChain(1.0));
}

TEST(DdpmSamplerTest, GuidanceInTheGuidedStepsAndTheExtraStepsPushesOutOfAnObstacle) {
  // With the guided window empty (fraction 0) and no extra steps the oracle's plan is untouched;
  // the last quarter of the steps alone, or the extra steps alone, push it out.
  objectives::DdpmConfig config;
  const objectives::DdpmSchedule schedule(config);
  const torch::Tensor target = torch::zeros({16, 4});
  guidance::GuidanceConfig guidance;
  guidance.collision_weight = 1.0;
  guidance.smoothness_weight = 0.0;
  const auto planner = Ddpm(OracleNoise(target, schedule), 16, DdpmSamplerConfig{}, guidance);
  const torch::Tensor start = torch::tensor({{-0.9f, 0.0f, 0.0f, 0.0f}}), goal = torch::tensor({{0.9f, 0.0f, 0.0f, 0.0f}});
  torch::manual_seed(4);
  const torch::Tensor noise = torch::randn({1, 16, 4}), renoise = torch::randn({1, 24, 16, 4});
  // Off centre: a defined push direction.
  const geometry::SceneRows obstacle = testing::Spheres(torch::tensor({{0.0f, -0.03f, 0.2f}}));
  // The window and the extra steps are per-call settings of one planner.
  auto plan = [&](double fraction, int extra) {
    PlanSettings settings;
    settings.values["sampler.ddpm.guide_fraction"] = fraction;
    settings.values["sampler.ddpm.extra_steps"] = extra;
    return planner->PlanWithNoise(start, goal, noise, renoise, obstacle, settings);
  };
  const torch::Tensor free = plan(0.0, 0);
  // The oracle puts every interior state at the origin, inside the obstacle;
  // guidance in the last steps pushes them out.
  EXPECT_LT(free.slice(1, 1, 15).slice(2, 0, 2).norm(2, -1).max().item<float>(), 1e-4);
  for (const auto& [fraction, extra] : {std::pair{0.25, 0}, std::pair{0.0, 5}, std::pair{0.25, 5}}) {
    const torch::Tensor guided = plan(fraction, extra);
    EXPECT_GT(guided.slice(1, 1, 15).slice(2, 0, 2).norm(2, -1).min().item<float>(), 0.01) << fraction << " " << extra;
  }
  PlanSettings fractional;
  fractional.values["sampler.ddpm.extra_steps"] = 1.5;
  EXPECT_THAT([&] { planner->PlanWithNoise(start, goal, noise, renoise, obstacle, fractional); },
              ::testing::ThrowsMessage<Error>(::testing::HasSubstr("sampler.ddpm.extra_steps: expected a whole number, got 1.5")));
}

TEST(DdpmSamplerTest, BestOfNReturnsEachRequestsCandidateOfLeastCost) {
  objectives::DdpmConfig config;
  const objectives::DdpmSchedule schedule(config);
  guidance::GuidanceConfig guidance;
  guidance.scale = 0.0;  // unguided: the candidates differ by their noise, the choice by the cost alone
  guidance.collision_weight = 1.0;
  guidance.smoothness_weight = 1e-3;
  const auto planner = Ddpm(GaussianNoise(0.0, 0.3, schedule, 4), 16, {}, guidance);
  torch::manual_seed(4);
  const int64_t B = 3, N = 4;
  const torch::Tensor start = torch::full({B, 4}, -0.5f), goal = torch::full({B, 4}, 0.5f);
  const torch::Tensor noise = torch::randn({B, N, 16, 4}), renoise = torch::randn({B, N, 24, 16, 4});
  const geometry::SceneRows obstacle = testing::Spheres(torch::tensor({{0.1f, 0.0f, 0.3f}}));
  PlanSettings settings;
  settings.values["guidance.candidates"] = N;
  const torch::Tensor best = planner->PlanWithNoise(start, goal, noise, renoise, obstacle, settings);
  // Each candidate planned alone, scored by the planner's own guide (its cost terms' weighted sum).
  torch::jit::Module guide = planner->module().attr("sampler").toModule().attr("guide").toModule();
  std::vector<torch::Tensor> plans, costs;
  for (int64_t j = 0; j < N; ++j) {
    plans.push_back(planner->PlanWithNoise(start, goal, noise.select(1, j), renoise.select(1, j), obstacle));
    costs.push_back(guide.run_method("value", plans.back(), obstacle, planner->module().attr("settings")).toTensor());
  }
  const torch::Tensor choice = torch::stack(costs, 1).argmin(1);
  EXPECT_GT(std::get<0>(at::_unique(choice)).numel(), 1) << "the test needs requests that choose differently";
  for (int64_t b = 0; b < B; ++b) {
    EXPECT_TRUE(torch::allclose(best[b], plans[choice[b].item<int64_t>()][b], 0.0, 1e-6)) << "request " << b;
  }
  EXPECT_THAT([&] { planner->PlanWithNoise(start, goal, noise, renoise.select(1, 0), obstacle, settings); },
              ::testing::ThrowsMessage<Error>(::testing::HasSubstr("plan: renoise: expected [3, 4, 24, 16, 4] (guidance.candidates = 4)")));
  // Where to guide is the flow planner's choice; the DDPM planner guides its posterior mean.
  PlanSettings at;
  at.guide_at = "prediction";
  EXPECT_THAT([&] { planner->PlanWithNoise(start, goal, noise.select(1, 0), renoise.select(1, 0), obstacle, at); },
              ::testing::ThrowsMessage<Error>(::testing::HasSubstr("plan: guide_at: only the flow planner takes it")));
}

TEST(DdpmSamplerTest, ThePapersBaselineGuidesTheNoisedSampleByThePosteriorVariance) {
  // A predictor of zero noise: x0 = x_k / sqrt(ᾱ_k) and the posterior mean is
  // c_k x_k, c_k = mean_x0 / sqrt(ᾱ_k) + mean_x. Without ancestral noise and
  // with states near the origin inside a sphere there, every state's distance
  // r from the origin follows r <- c_k r, then r <- r + s σ_k² (one step of
  // the unit outward gradient weighted by the step's posterior variance).
  objectives::DdpmConfig config;
  config.steps = 10;
  config.schedule = objectives::BetaSchedule::kLinear;
  config.beta_start = 1e-4;
  config.beta_end = 0.02;
  const objectives::DdpmSchedule schedule(config);
  DdpmSamplerConfig sampler;
  sampler.guide_on = DdpmGuideOn::kSampleByVariance;
  sampler.guide_fraction = 1.0;
  sampler.guide_iterations = 1;
  sampler.extra_steps = 0;
  sampler.noise_scale = 0.0;
  guidance::GuidanceConfig guidance;
  guidance.scale = 2.0;
  guidance.collision_weight = 1.0;
  guidance.smoothness_weight = 0.0;
  guidance.margin = 0.0;
  PlannerParts parts = testing::Parts(testing::ZeroVelocity(4), testing::DiscTrajectory(16), testing::UnitNormalizer(4));
  parts.objective.name = objectives::ObjectiveKind::kDdpm;
  parts.objective.ddpm = config;
  parts.sampler.ddpm = sampler;
  parts.guidance = guidance;
  const auto planner = AssemblePlanner(parts);
  auto generator = at::make_generator<at::CPUGeneratorImpl>(6);
  const torch::Tensor start = torch::tensor({{-0.8f, 0.0f, 0.0f, 0.0f}}), goal = torch::tensor({{0.8f, 0.0f, 0.0f, 0.0f}});
  const torch::Tensor noise = 0.01 * torch::randn({1, 16, 4}, generator), renoise = torch::randn({1, 9, 16, 4}, generator);
  const geometry::SceneRows obstacle = testing::Spheres(torch::tensor({{0.0f, 0.0f, 0.3f}}));
  const torch::Tensor free = planner->PlanWithNoise(start, goal, noise, renoise);
  const torch::Tensor guided = planner->PlanWithNoise(start, goal, noise, renoise, obstacle);
  double pushed = 0.0;  // how far the pushes move r by the end
  for (int k = 9; k >= 0; --k) {
    const double a = schedule.alpha_bar(k), before = schedule.alpha_bar_before(k), beta = schedule.beta(k);
    const double c = beta * std::sqrt(before) / (1.0 - a) / std::sqrt(a) + (1.0 - before) * std::sqrt(schedule.alpha(k)) / (1.0 - a);
    pushed = c * pushed + guidance.scale * beta * (1.0 - before) / (1.0 - a);
  }
  EXPECT_GT(pushed, 0.01);
  const torch::Tensor moved = guided.slice(1, 1, 15).slice(2, 0, 2).norm(2, -1) - free.slice(1, 1, 15).slice(2, 0, 2).norm(2, -1);
  EXPECT_NEAR(moved.min().item<float>(), pushed, 1e-4);
  EXPECT_NEAR(moved.max().item<float>(), pushed, 1e-4);
  // MPD's guidance of the posterior mean moves the same plans another way.
  parts.sampler.ddpm.guide_on = DdpmGuideOn::kPosteriorMean;
  const torch::Tensor mpd = AssemblePlanner(parts)->PlanWithNoise(start, goal, noise, renoise, obstacle);
  EXPECT_GT((mpd - guided).abs().max().item<float>(), 1e-3);
}

}  // namespace
}  // namespace flowplan::planning
