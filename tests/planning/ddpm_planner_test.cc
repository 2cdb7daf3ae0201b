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
