#include "planning/flow_planner.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "core/error.h"
#include "models/model_config.h"

namespace flowplan::planning {
namespace {

using ::testing::HasSubstr;
using ::testing::ThrowsMessage;

FlowPlanner MakePlanner(Conditioning conditioning, int steps = 4) {
  torch::manual_seed(0);
  models::ModelConfig config;
  config.unet.down_dims = {16, 32};
  auto net = models::MakeVelocityNet(config, 4, ConditionDim(conditioning, 4));
  models::MinMaxNormalizer normalizer(torch::tensor({0.f, 0.f, -1.f, -1.f}), torch::tensor({1.f, 1.f, 1.f, 1.f}));
  return FlowPlanner(net, normalizer, conditioning, 16, SamplerConfig{steps});
}

TEST(FlowPlannerTest, InpaintedPlansStartAndEndExactlyAtTheRequest) {
  const FlowPlanner planner = MakePlanner(Conditioning::kInpaint);
  const torch::Tensor start = torch::tensor({{0.1f, 0.2f, 0.0f, 0.0f}, {0.9f, 0.8f, 0.3f, -0.2f}});
  const torch::Tensor goal = torch::tensor({{0.7f, 0.6f, 0.1f, 0.1f}, {0.2f, 0.3f, 0.0f, 0.0f}});
  const torch::Tensor plan = planner.Plan(start, goal, torch::randn({2, 16, 4}));
  ASSERT_EQ(plan.sizes(), (std::vector<int64_t>{2, 16, 4}));
  EXPECT_TRUE(torch::equal(plan.select(1, 0), start));
  EXPECT_TRUE(torch::equal(plan.select(1, 15), goal));
  // Interior states stay in the training range.
  EXPECT_TRUE((plan.slice(2, 0, 2) >= 0).all().item<bool>());
  EXPECT_TRUE((plan.slice(2, 0, 2) <= 1).all().item<bool>());
}

TEST(FlowPlannerTest, SameNoiseSamePlan) {
  const FlowPlanner planner = MakePlanner(Conditioning::kDirect);
  const torch::Tensor start = torch::full({3, 4}, 0.5f), goal = torch::full({3, 4}, 0.25f);
  const torch::Tensor noise = torch::randn({3, 16, 4});
  EXPECT_TRUE(torch::equal(planner.Plan(start, goal, noise), planner.Plan(start, goal, noise)));
  auto g1 = at::make_generator<at::CPUGeneratorImpl>(7), g2 = at::make_generator<at::CPUGeneratorImpl>(7);
  EXPECT_TRUE(torch::equal(planner.Sample(start, goal, g1), planner.Sample(start, goal, g2)));
}

TEST(FlowPlannerTest, BadShapesNameTheArgument) {
  const FlowPlanner planner = MakePlanner(Conditioning::kInpaint);
  EXPECT_THAT([&] { planner.Plan(torch::zeros({2, 3}), torch::zeros({2, 3}), torch::zeros({2, 16, 4})); },
              ThrowsMessage<Error>(HasSubstr("start: expected (B, 4), got (2, 3)")));
  EXPECT_THAT([&] { planner.Plan(torch::zeros({2, 4}), torch::zeros({2, 4}), torch::zeros({2, 8, 4})); },
              ThrowsMessage<Error>(HasSubstr("noise: expected (2, 16, 4), got (2, 8, 4)")));
}

/// A network whose velocity is zero everywhere: plans stay where the noise puts them.
class ZeroVelocity : public models::VelocityNet {
 public:
  torch::Tensor Forward(const torch::Tensor& x, const torch::Tensor&, const torch::Tensor&) override {
    return torch::zeros_like(x);
  }
  void CheckHorizon(int64_t) const override {}
  std::string WriteScript(models::ScriptWriter&) const override { return ""; }
  int64_t state_dim() const override { return 4; }
  int64_t cond_dim() const override { return 0; }
};

TEST(FlowPlannerTest, MidpointSplittingUsesTheStatesBesideTheMiddleAsBoundaries) {
  auto net = std::make_shared<ZeroVelocity>();
  models::MinMaxNormalizer unit(-torch::ones({4}), torch::ones({4}));  // raw == normalized
  const FlowPlanner plain(net, unit, Conditioning::kInpaint, 16, SamplerConfig{4, Splitting::kNone});
  const FlowPlanner split(net, unit, Conditioning::kInpaint, 16, SamplerConfig{4, Splitting::kMidpoint});
  const torch::Tensor start = torch::full({2, 4}, -0.5f), goal = torch::full({2, 4}, 0.5f);
  auto generator = at::make_generator<at::CPUGeneratorImpl>(3);
  // Small noise keeps every state inside the normalizer's range, where nothing is clamped.
  const torch::Tensor noise = 0.2 * torch::randn({2, 16, 4}, generator).clamp(-4, 4);
  const torch::Tensor renoise = 0.2 * torch::randn({2, 16, 4}, generator).clamp(-4, 4);
  const torch::Tensor first = plain.Plan(start, goal, noise);
  const torch::Tensor joined = split.Plan(start, goal, noise, renoise);
  ASSERT_EQ(joined.sizes(), first.sizes());
  // With zero velocity, each half keeps its re-noised states and takes its boundaries
  // from the first plan: states 7 and 8 are the first plan's, the ends the request's.
  EXPECT_TRUE(torch::allclose(joined.select(1, 7), first.select(1, 7)));
  EXPECT_TRUE(torch::allclose(joined.select(1, 8), first.select(1, 8)));
  EXPECT_TRUE(torch::equal(joined.select(1, 0), start));
  EXPECT_TRUE(torch::equal(joined.select(1, 15), goal));
  EXPECT_TRUE(torch::allclose(joined.slice(1, 1, 7), (0.5 * renoise + 0.5 * first).slice(1, 1, 7)));
  EXPECT_THAT([&] { split.Plan(start, goal, noise); }, ThrowsMessage<Error>(HasSubstr("renoise")));
}

TEST(FlowPlannerTest, SplittingNeedsHalvesTheNetworkCanTake) {
  models::ModelConfig config;
  config.unet.down_dims = {8, 8, 8, 8};  // T must be a multiple of 8
  auto net = models::MakeVelocityNet(config, 4, 0);
  models::MinMaxNormalizer unit(-torch::ones({4}), torch::ones({4}));
  EXPECT_THAT([&] { FlowPlanner(net, unit, Conditioning::kInpaint, 8, SamplerConfig{4, Splitting::kMidpoint}); },
              ThrowsMessage<Error>(HasSubstr("sampler.splitting")));
}

TEST(FlowPlannerTest, PlanningDoesNotChangeTheNetwork) {
  const FlowPlanner planner = MakePlanner(Conditioning::kInpaint);
  std::vector<torch::Tensor> before;
  for (const auto& p : planner.net()->parameters()) before.push_back(p.clone());
  planner.Plan(torch::zeros({1, 4}), torch::ones({1, 4}), torch::randn({1, 16, 4}));
  const auto after = planner.net()->parameters();
  for (size_t i = 0; i < before.size(); ++i) EXPECT_TRUE(torch::equal(before[i], after[i]));
}

}  // namespace
}  // namespace flowplan::planning
