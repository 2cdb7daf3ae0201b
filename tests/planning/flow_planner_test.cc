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
  auto net = models::MakeTrajectoryNet(config, 4, ConditionDim(conditioning, 4));
  models::MinMaxNormalizer normalizer(torch::tensor({0.f, 0.f, -1.f, -1.f}), torch::tensor({1.f, 1.f, 1.f, 1.f}));
  return FlowPlanner(net, normalizer, conditioning, 16, SamplerConfig{steps});
}

TEST(FlowPlannerTest, InpaintedPlansStartAndEndExactlyAtTheRequest) {
  const FlowPlanner planner = MakePlanner(Conditioning::kInpaint);
  const torch::Tensor start = torch::tensor({{0.1f, 0.2f, 0.0f, 0.0f}, {0.9f, 0.8f, 0.3f, -0.2f}});
  const torch::Tensor goal = torch::tensor({{0.7f, 0.6f, 0.1f, 0.1f}, {0.2f, 0.3f, 0.0f, 0.0f}});
  const torch::Tensor plan = planner.PlanWithNoise(start, goal, torch::randn({2, 16, 4}));
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
  EXPECT_TRUE(torch::equal(planner.PlanWithNoise(start, goal, noise), planner.PlanWithNoise(start, goal, noise)));
  PlanRequest request{start, goal, torch::Tensor(), 7, std::nullopt};
  EXPECT_TRUE(torch::equal(planner.Plan(request).plans, planner.Plan(request).plans));
  PlanRequest other = request;
  other.seed = 8;
  EXPECT_FALSE(torch::equal(planner.Plan(request).plans, planner.Plan(other).plans));
}

TEST(FlowPlannerTest, BadShapesNameTheArgument) {
  const FlowPlanner planner = MakePlanner(Conditioning::kInpaint);
  EXPECT_THAT([&] { planner.PlanWithNoise(torch::zeros({2, 3}), torch::zeros({2, 3}), torch::zeros({2, 16, 4})); },
              ThrowsMessage<Error>(HasSubstr("start: expected (B, 4), got (2, 3)")));
  EXPECT_THAT([&] { planner.PlanWithNoise(torch::zeros({2, 4}), torch::zeros({2, 4}), torch::zeros({2, 8, 4})); },
              ThrowsMessage<Error>(HasSubstr("noise: expected (2, 16, 4), got (2, 8, 4)")));
}

/// A network whose velocity is zero everywhere: plans stay where the noise puts them.
class ZeroVelocity : public models::TrajectoryNet {
 public:
  torch::Tensor Forward(const torch::Tensor& x, const torch::Tensor&, const torch::Tensor&) override {
    return torch::zeros_like(x);
  }
  void CheckHorizon(int64_t) const override {}
  std::string WriteScript(jit::ScriptWriter&) const override { return ""; }
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
  const torch::Tensor first = plain.PlanWithNoise(start, goal, noise);
  const torch::Tensor joined = split.PlanWithNoise(start, goal, noise, renoise);
  ASSERT_EQ(joined.sizes(), first.sizes());
  // With zero velocity, each half keeps its re-noised states and takes its boundaries
  // from the first plan: states 7 and 8 are the first plan's, the ends the request's.
  EXPECT_TRUE(torch::allclose(joined.select(1, 7), first.select(1, 7)));
  EXPECT_TRUE(torch::allclose(joined.select(1, 8), first.select(1, 8)));
  EXPECT_TRUE(torch::equal(joined.select(1, 0), start));
  EXPECT_TRUE(torch::equal(joined.select(1, 15), goal));
  EXPECT_TRUE(torch::allclose(joined.slice(1, 1, 7), (0.5 * renoise + 0.5 * first).slice(1, 1, 7)));
  EXPECT_THAT([&] { split.PlanWithNoise(start, goal, noise); }, ThrowsMessage<Error>(HasSubstr("renoise")));
}

TEST(FlowPlannerTest, SplittingNeedsHalvesTheNetworkCanTake) {
  models::ModelConfig config;
  config.unet.down_dims = {8, 8, 8, 8};  // T must be a multiple of 8
  auto net = models::MakeTrajectoryNet(config, 4, 0);
  models::MinMaxNormalizer unit(-torch::ones({4}), torch::ones({4}));
  EXPECT_THAT([&] { FlowPlanner(net, unit, Conditioning::kInpaint, 8, SamplerConfig{4, Splitting::kMidpoint}); },
              ThrowsMessage<Error>(HasSubstr("sampler.splitting")));
}

TEST(FlowPlannerTest, PlanningDoesNotChangeTheNetwork) {
  const FlowPlanner planner = MakePlanner(Conditioning::kInpaint);
  std::vector<torch::Tensor> before;
  for (const auto& p : planner.net()->parameters()) before.push_back(p.clone());
  planner.PlanWithNoise(torch::zeros({1, 4}), torch::ones({1, 4}), torch::randn({1, 16, 4}));
  const auto after = planner.net()->parameters();
  for (size_t i = 0; i < before.size(); ++i) EXPECT_TRUE(torch::equal(before[i], after[i]));
}

/// A disc planner on a zero velocity field: plans are the (inpainted) noise
/// plus whatever guidance adds, so guidance's effect is seen alone.
FlowPlanner GuidedZeroPlanner(Splitting splitting, double scale) {
  models::MinMaxNormalizer unit(-torch::ones({4}), torch::ones({4}));  // raw == normalized
  guidance::GuidanceConfig config;
  config.scale = scale;
  config.collision_weight = 1.0;
  config.smoothness_weight = 0.0;
  config.margin = 0.0;
  auto disc = kinematics::MakeRobot(kinematics::PointRobot("disc", 2, 0.05, -1.0, 1.0));
  return FlowPlanner(std::make_shared<ZeroVelocity>(), unit, Conditioning::kInpaint, 16, SamplerConfig{4, splitting},
                     GuidanceSetup{disc, 0.1, config});
}

TEST(FlowPlannerTest, GuidancePushesStatesOutOfAnObstacleAndOnlyWithObstacles) {
  torch::manual_seed(1);
  const torch::Tensor start = torch::tensor({{-0.8f, 0.0f, 0.0f, 0.0f}}), goal = torch::tensor({{0.8f, 0.0f, 0.0f, 0.0f}});
  const torch::Tensor noise = 0.01 * torch::randn({1, 16, 4});  // every state near the origin
  const torch::Tensor obstacle = torch::tensor({{0.0f, 0.0f, 0.3f}});
  const FlowPlanner planner = GuidedZeroPlanner(Splitting::kNone, 0.1);
  const torch::Tensor free = planner.PlanWithNoise(start, goal, noise);
  EXPECT_TRUE(torch::equal(free, planner.PlanWithNoise(start, goal, noise, torch::Tensor(), torch::zeros({0, 3}))));
  const torch::Tensor guided = planner.PlanWithNoise(start, goal, noise, torch::Tensor(), obstacle);
  const torch::Tensor radius_free = free.slice(1, 1, 15).slice(2, 0, 2).norm(2, -1);
  const torch::Tensor radius_guided = guided.slice(1, 1, 15).slice(2, 0, 2).norm(2, -1);
  // With b_t = 1 - t after steps ending at t = 0.25, 0.5, 0.75, 1 the pushes add up to
  // scale * (0.75 + 0.5 + 0.25) = 0.15 along the outward unit direction (the hinge's gradient).
  EXPECT_NEAR((radius_guided - radius_free).min().item<float>(), 0.15f, 2e-3);
  EXPECT_NEAR((radius_guided - radius_free).max().item<float>(), 0.15f, 2e-3);
  // The ends stay where they were asked to be.
  EXPECT_TRUE(torch::equal(guided.select(1, 0), start));
  EXPECT_TRUE(torch::equal(guided.select(1, 15), goal));
  // A call's own scale wins over the planner's.
  guidance::GuidanceConfig off = planner.guidance().config;
  off.scale = 0.0;
  EXPECT_TRUE(torch::equal(free, planner.PlanWithNoise(start, goal, noise, torch::Tensor(), obstacle, &off)));
}

TEST(FlowPlannerTest, GuidanceAlsoRunsInBothHalvesOfSplitting) {
  torch::manual_seed(1);
  const torch::Tensor start = torch::tensor({{-0.8f, 0.0f, 0.0f, 0.0f}}), goal = torch::tensor({{0.8f, 0.0f, 0.0f, 0.0f}});
  const torch::Tensor noise = 0.01 * torch::randn({1, 16, 4}), renoise = 0.01 * torch::randn({1, 16, 4});
  const torch::Tensor obstacle = torch::tensor({{0.0f, 0.0f, 0.5f}});
  const FlowPlanner split = GuidedZeroPlanner(Splitting::kMidpoint, 0.1);
  const torch::Tensor free = split.PlanWithNoise(start, goal, noise, renoise);
  const torch::Tensor guided = split.PlanWithNoise(start, goal, noise, renoise, obstacle);
  // The halves' interiors (states 1..6 and 9..14) are re-noised halfway and then
  // guided by the two stage-2 steps (b = 0.25 at t = 0.75, 0 at t = 1) on top of half
  // the first stage's push: 0.5 * 0.15 + 0.1 * 0.25 = 0.1 outward.
  for (const auto& [begin, end] : {std::pair{1, 7}, std::pair{9, 15}}) {
    const torch::Tensor moved = guided.slice(1, begin, end).slice(2, 0, 2).norm(2, -1) -
                                free.slice(1, begin, end).slice(2, 0, 2).norm(2, -1);
    EXPECT_NEAR(moved.mean().item<float>(), 0.1f, 1e-2) << "states " << begin << ".." << end - 1;
  }
}

TEST(FlowPlannerTest, ObstaclesAreChecked) {
  const FlowPlanner planner = GuidedZeroPlanner(Splitting::kNone, 1.0);
  const torch::Tensor s = torch::zeros({1, 4}), noise = torch::zeros({1, 16, 4});
  EXPECT_THAT([&] { planner.PlanWithNoise(s, s, noise, torch::Tensor(), torch::zeros({1, 4})); },
              ThrowsMessage<Error>(HasSubstr("plan: obstacles: expected (K, 3)")));
  EXPECT_THAT([&] { planner.PlanWithNoise(s, s, noise, torch::Tensor(), torch::tensor({{0.f, 0.f, -1.f}})); },
              ThrowsMessage<Error>(HasSubstr("non-negative radius")));
  const FlowPlanner blind = MakePlanner(Conditioning::kInpaint);
  EXPECT_THAT([&] { blind.PlanWithNoise(s, s, noise, torch::Tensor(), torch::tensor({{0.f, 0.f, 1.f}})); },
              ThrowsMessage<Error>(HasSubstr("no robot description")));
}

TEST(FlowPlannerTest, PlanningInChunksDoesNotDependOnTheThreadCount) {
  at::set_num_threads(1);
  const FlowPlanner planner = GuidedZeroPlanner(Splitting::kMidpoint, 0.5);
  torch::manual_seed(1);
  PlanRequest request;
  request.start = torch::rand({37, 4}) - 0.5;
  request.goal = torch::rand({37, 4}) - 0.5;
  request.obstacles = torch::tensor({{0.0f, 0.0f, 0.2f}});
  request.seed = 3;
  const PlanResult one = PlanInChunks(planner, request, 1, 8);
  const PlanResult three = PlanInChunks(planner, request, 3, 8);
  EXPECT_TRUE(torch::equal(one.plans, three.plans));
  EXPECT_EQ(one.seconds.size(), 37u);
  EXPECT_TRUE(one.found.all().item<bool>());
}

}  // namespace
}  // namespace flowplan::planning
