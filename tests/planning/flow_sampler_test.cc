// The flow planner's sampler (planning/flow_sampler.py) on networks whose
// output is known: Euler's exactness, inpainting, splitting's boundaries, and
// guidance's pushes in closed form; per-call settings; thread-count invariance.

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "core/error.h"
#include "planning/assemble.h"
#include "tests/support/planners.h"

namespace flowplan::planning {
namespace {

using ::testing::HasSubstr;
using ::testing::ThrowsMessage;
using testing::DiscTrajectory;
using testing::Parts;
using testing::ScriptedNet;
using testing::Spheres;
using testing::UnitNormalizer;
using testing::ZeroVelocity;

std::unique_ptr<LearnedPlanner> Flow(models::NetworkPtr net, models::MinMaxNormalizer normalizer, int steps,
                                     Splitting splitting = Splitting::kNone,
                                     models::Conditioning conditioning = models::Conditioning::kInpaint,
                                     guidance::GuidanceConfig guidance = {}) {
  PlannerParts parts = Parts(std::move(net), DiscTrajectory(), std::move(normalizer));
  parts.objective.conditioning = conditioning;
  parts.sampler.steps = steps;
  parts.sampler.splitting = splitting;
  parts.guidance = guidance;
  return AssemblePlanner(parts);
}

std::unique_ptr<LearnedPlanner> TinyFlow(models::Conditioning conditioning) {
  return Flow(testing::TinyUNet(4, models::ConditionDim(conditioning, 4)),
              models::MinMaxNormalizer(torch::tensor({0.f, 0.f, -1.f, -1.f}), torch::tensor({1.f, 1.f, 1.f, 1.f})), 4,
              Splitting::kNone, conditioning);
}

TEST(FlowSamplerTest, ConstantVelocityIsIntegratedExactlyInAnyNumberOfSteps) {
  // Direct conditioning (no inpainting): x1 = x0 + c for velocity c, whatever the steps.
  const torch::Tensor c = 0.1 * torch::randn({16, 4});
  auto net = std::make_shared<ScriptedNet>(4, std::vector<std::string>{"out = self.p_c.expand_as(x)"},
                                           std::vector<std::pair<std::string, torch::Tensor>>{{"c", c}}, 8);
  for (int steps : {1, 7, 10}) {
    const auto planner = Flow(net, UnitNormalizer(4), steps, Splitting::kNone, models::Conditioning::kDirect);
    const torch::Tensor noise = 0.1 * torch::randn({3, 16, 4});
    const torch::Tensor plan = planner->PlanWithNoise(torch::zeros({3, 4}), torch::zeros({3, 4}), noise);
    EXPECT_TRUE(torch::allclose(plan, noise + c, 0.0, 1e-6)) << steps << " steps";
  }
}

TEST(FlowSamplerTest, VelocityLinearInTimeGivesTheLeftRiemannSum) {
  // dx/dt = t: Euler with h = 1/n gives sum_i h (i h) = (n - 1) / (2n).
  auto net = std::make_shared<ScriptedNet>(
      4, std::vector<std::string>{"out = t.view(-1, 1, 1).expand_as(x)"},
      std::vector<std::pair<std::string, torch::Tensor>>{}, 8);
  const auto planner = Flow(net, UnitNormalizer(4), 10, Splitting::kNone, models::Conditioning::kDirect);
  const torch::Tensor plan =
      planner->PlanWithNoise(torch::zeros({1, 4}), torch::zeros({1, 4}), torch::zeros({1, 16, 4}));
  EXPECT_NEAR(plan.max().item<float>(), 0.45f, 1e-6);
  EXPECT_NEAR(plan.min().item<float>(), 0.45f, 1e-6);
  // Per call, the step count is a setting.
  PlanSettings twenty;
  twenty.values["sampler.steps"] = 20;
  EXPECT_NEAR(planner->PlanWithNoise(torch::zeros({1, 4}), torch::zeros({1, 4}), torch::zeros({1, 16, 4}), {}, geometry::SceneRows(),
                                     twenty)
                  .max()
                  .item<float>(),
              0.475f, 1e-6);
}

TEST(FlowSamplerTest, InpaintedPlansStartAndEndExactlyAtTheRequest) {
  const auto planner = TinyFlow(models::Conditioning::kInpaint);
  const torch::Tensor start = torch::tensor({{0.1f, 0.2f, 0.0f, 0.0f}, {0.9f, 0.8f, 0.3f, -0.2f}});
  const torch::Tensor goal = torch::tensor({{0.7f, 0.6f, 0.1f, 0.1f}, {0.2f, 0.3f, 0.0f, 0.0f}});
  const torch::Tensor plan = planner->PlanWithNoise(start, goal, torch::randn({2, 16, 4}));
  ASSERT_EQ(plan.sizes(), (std::vector<int64_t>{2, 16, 4}));
  EXPECT_TRUE(torch::equal(plan.select(1, 0), start));
  EXPECT_TRUE(torch::equal(plan.select(1, 15), goal));
  // Interior states stay in the training range.
  EXPECT_TRUE((plan.slice(2, 0, 2) >= 0).all().item<bool>());
  EXPECT_TRUE((plan.slice(2, 0, 2) <= 1).all().item<bool>());
}

TEST(FlowSamplerTest, SameNoiseSamePlan) {
  const auto planner = TinyFlow(models::Conditioning::kDirect);
  const torch::Tensor start = torch::full({3, 4}, 0.5f), goal = torch::full({3, 4}, 0.25f);
  const torch::Tensor noise = torch::randn({3, 16, 4});
  EXPECT_TRUE(torch::equal(planner->PlanWithNoise(start, goal, noise),
                           planner->PlanWithNoise(start, goal, noise)));
  PlanRequest request;
  request.start = start;
  request.goal = goal;
  request.seed = 7;
  EXPECT_TRUE(torch::equal(planner->Plan(request).plans, planner->Plan(request).plans));
  PlanRequest other = request;
  other.seed = 8;
  EXPECT_FALSE(torch::equal(planner->Plan(request).plans, planner->Plan(other).plans));
}

TEST(FlowSamplerTest, BadShapesAndSettingsNameTheArgument) {
  const auto planner = TinyFlow(models::Conditioning::kInpaint);
  EXPECT_THAT([&] { planner->PlanWithNoise(torch::zeros({2, 3}), torch::zeros({2, 3}), torch::zeros({2, 16, 4})); },
              ThrowsMessage<Error>(HasSubstr("start: expected (B, 4), got (2, 3)")));
  EXPECT_THAT([&] { planner->PlanWithNoise(torch::zeros({2, 4}), torch::zeros({2, 4}), torch::zeros({2, 8, 4})); },
              ThrowsMessage<Error>(HasSubstr("plan: noise: expected [2, 16, 4], got [2, 8, 4]")));
  PlanSettings unknown;
  unknown.values["guidance.frobnicate"] = 1.0;
  EXPECT_THAT([&] { planner->PlanWithNoise(torch::zeros({1, 4}), torch::zeros({1, 4}), torch::zeros({1, 16, 4}), {}, geometry::SceneRows(), unknown); },
              ThrowsMessage<Error>(HasSubstr("plan: settings: unknown key guidance.frobnicate (this planner takes")));
  PlanSettings negative;
  negative.values["guidance.clip"] = -1.0;
  EXPECT_THAT([&] { planner->PlanWithNoise(torch::zeros({1, 4}), torch::zeros({1, 4}), torch::zeros({1, 16, 4}), {}, geometry::SceneRows(), negative); },
              ThrowsMessage<Error>(HasSubstr("guidance.clip: expected a non-negative value")));
  PlanSettings schedule;
  schedule.schedule = "sideways";
  EXPECT_THAT([&] { planner->PlanWithNoise(torch::zeros({1, 4}), torch::zeros({1, 4}), torch::zeros({1, 16, 4}), {}, geometry::SceneRows(), schedule); },
              ThrowsMessage<Error>(HasSubstr("plan: schedule: expected one of one_minus_t, ratio, rising, got sideways")));
}

TEST(FlowSamplerTest, MidpointSplittingUsesTheStatesBesideTheMiddleAsBoundaries) {
  const auto plain = Flow(ZeroVelocity(4), UnitNormalizer(4), 4, Splitting::kNone);
  const auto split = Flow(ZeroVelocity(4), UnitNormalizer(4), 4, Splitting::kMidpoint);
  const torch::Tensor start = torch::full({2, 4}, -0.5f), goal = torch::full({2, 4}, 0.5f);
  auto generator = at::make_generator<at::CPUGeneratorImpl>(3);
  // Small noise keeps every state inside the normalizer's range, where nothing is clamped.
  const torch::Tensor noise = 0.2 * torch::randn({2, 16, 4}, generator).clamp(-4, 4);
  const torch::Tensor renoise = 0.2 * torch::randn({2, 16, 4}, generator).clamp(-4, 4);
  const torch::Tensor first = plain->PlanWithNoise(start, goal, noise);
  const torch::Tensor joined = split->PlanWithNoise(start, goal, noise, renoise);
  ASSERT_EQ(joined.sizes(), first.sizes());
  // With zero velocity, each half keeps its re-noised states and takes its boundaries
  // from the first plan: states 7 and 8 are the first plan's, the ends the request's.
  EXPECT_TRUE(torch::allclose(joined.select(1, 7), first.select(1, 7)));
  EXPECT_TRUE(torch::allclose(joined.select(1, 8), first.select(1, 8)));
  EXPECT_TRUE(torch::equal(joined.select(1, 0), start));
  EXPECT_TRUE(torch::equal(joined.select(1, 15), goal));
  EXPECT_TRUE(torch::allclose(joined.slice(1, 1, 7), (0.5 * renoise + 0.5 * first).slice(1, 1, 7)));
  EXPECT_THAT([&] { split->PlanWithNoise(start, goal, noise); }, ThrowsMessage<Error>(HasSubstr("renoise")));
}

TEST(FlowSamplerTest, SplittingNeedsHalvesTheNetworkCanTake) {
  models::ModelConfig config;
  config.unet.down_dims = {8, 8, 8, 8};  // T must be a multiple of 8
  auto net = models::MakeTrajectoryNet(config, 4, 0);
  PlannerParts parts = Parts(net, DiscTrajectory(8), UnitNormalizer(4));
  parts.sampler.splitting = Splitting::kMidpoint;
  EXPECT_THAT([&] { AssemblePlanner(parts); }, ThrowsMessage<Error>(HasSubstr("sampler.splitting")));
}

TEST(FlowSamplerTest, PlanningDoesNotChangeTheNetwork) {
  auto net = testing::TinyUNet(4, 0);
  const auto planner = Flow(net, UnitNormalizer(4), 4);
  std::vector<torch::Tensor> before;
  for (const auto& p : net->parameters()) before.push_back(p.clone());
  planner->PlanWithNoise(torch::zeros({1, 4}), torch::ones({1, 4}) * 0.5, torch::randn({1, 16, 4}));
  const auto after = net->parameters();
  for (size_t i = 0; i < before.size(); ++i) EXPECT_TRUE(torch::equal(before[i], after[i]));
}

/// A disc planner on a zero velocity field: plans are the (inpainted) noise
/// plus whatever guidance adds, so guidance's effect is seen alone.
std::unique_ptr<LearnedPlanner> GuidedZero(Splitting splitting, double scale) {
  guidance::GuidanceConfig config;
  config.scale = scale;
  config.collision_weight = 1.0;
  config.smoothness_weight = 0.0;
  config.margin = 0.0;
  return Flow(ZeroVelocity(4), UnitNormalizer(4), 4, splitting, models::Conditioning::kInpaint, config);
}

TEST(FlowSamplerTest, GuidancePushesStatesOutOfAnObstacleAndOnlyWithObstacles) {
  torch::manual_seed(1);
  const torch::Tensor start = torch::tensor({{-0.8f, 0.0f, 0.0f, 0.0f}}), goal = torch::tensor({{0.8f, 0.0f, 0.0f, 0.0f}});
  const torch::Tensor noise = 0.01 * torch::randn({1, 16, 4});  // every state near the origin
  const auto planner = GuidedZero(Splitting::kNone, 0.1);
  const torch::Tensor free = planner->PlanWithNoise(start, goal, noise);
  EXPECT_TRUE(torch::equal(free, planner->PlanWithNoise(start, goal, noise, {}, Spheres(torch::zeros({0, 3})))));
  const geometry::SceneRows obstacle = Spheres(torch::tensor({{0.0f, 0.0f, 0.3f}}));
  const torch::Tensor guided = planner->PlanWithNoise(start, goal, noise, {}, obstacle);
  const torch::Tensor radius_free = free.slice(1, 1, 15).slice(2, 0, 2).norm(2, -1);
  const torch::Tensor radius_guided = guided.slice(1, 1, 15).slice(2, 0, 2).norm(2, -1);
  // With b_t = 1 - t after steps ending at t = 0.25, 0.5, 0.75, 1 the pushes add up to
  // scale * (0.75 + 0.5 + 0.25) = 0.15 along the outward unit direction (the hinge's gradient).
  EXPECT_NEAR((radius_guided - radius_free).min().item<float>(), 0.15f, 2e-3);
  EXPECT_NEAR((radius_guided - radius_free).max().item<float>(), 0.15f, 2e-3);
  // The ends stay where they were asked to be.
  EXPECT_TRUE(torch::equal(guided.select(1, 0), start));
  EXPECT_TRUE(torch::equal(guided.select(1, 15), goal));
  // A call's own settings win over the planner's: scale 0 is unguided; the
  // rising schedule (b = t) pushes 0.1 * (0.25 + 0.5 + 0.75 + 1) = 0.25.
  PlanSettings off;
  off.values["guidance.scale"] = 0.0;
  EXPECT_TRUE(torch::equal(free, planner->PlanWithNoise(start, goal, noise, {}, obstacle, off)));
  PlanSettings rising;
  rising.schedule = "rising";
  const torch::Tensor pushed = planner->PlanWithNoise(start, goal, noise, {}, obstacle, rising);
  EXPECT_NEAR((pushed.slice(1, 1, 15).slice(2, 0, 2).norm(2, -1) - radius_free).mean().item<float>(), 0.25f, 2e-3);
}

TEST(FlowSamplerTest, GuidanceAlsoRunsInBothHalvesOfSplitting) {
  torch::manual_seed(1);
  const torch::Tensor start = torch::tensor({{-0.8f, 0.0f, 0.0f, 0.0f}}), goal = torch::tensor({{0.8f, 0.0f, 0.0f, 0.0f}});
  const torch::Tensor noise = 0.01 * torch::randn({1, 16, 4}), renoise = 0.01 * torch::randn({1, 16, 4});
  const auto split = GuidedZero(Splitting::kMidpoint, 0.1);
  const torch::Tensor free = split->PlanWithNoise(start, goal, noise, renoise);
  const torch::Tensor guided = split->PlanWithNoise(start, goal, noise, renoise, Spheres(torch::tensor({{0.0f, 0.0f, 0.5f}})));
  // The halves' interiors (states 1..6 and 9..14) are re-noised halfway and then
  // guided by the two stage-2 steps (b = 0.25 at t = 0.75, 0 at t = 1) on top of half
  // the first stage's push: 0.5 * 0.15 + 0.1 * 0.25 = 0.1 outward.
  for (const auto& [begin, end] : {std::pair{1, 7}, std::pair{9, 15}}) {
    const torch::Tensor moved = guided.slice(1, begin, end).slice(2, 0, 2).norm(2, -1) -
                                free.slice(1, begin, end).slice(2, 0, 2).norm(2, -1);
    EXPECT_NEAR(moved.mean().item<float>(), 0.1f, 1e-2) << "states " << begin << ".." << end - 1;
  }
}

TEST(FlowSamplerTest, GuidanceWorksForEveryShape) {
  // Each shape centred at the origin, swallowing the near-origin plan: guidance
  // moves every interior state outwards; a box pushes along its nearest face normal.
  torch::manual_seed(1);
  const torch::Tensor start = torch::tensor({{-0.8f, 0.0f, 0.0f, 0.0f}}), goal = torch::tensor({{0.8f, 0.0f, 0.0f, 0.0f}});
  const torch::Tensor noise = 0.01 * torch::randn({1, 16, 4});
  const auto planner = GuidedZero(Splitting::kNone, 0.1);
  const torch::Tensor free = planner->PlanWithNoise(start, goal, noise);
  for (const auto& [kind, row] : std::vector<std::pair<std::string, torch::Tensor>>{
           {"boxes", torch::tensor({{0.0f, 0.0f, 0.6f, 0.6f, 0.3f}})},
           {"cylinders", torch::tensor({{0.0f, 0.0f, 0.3f, 0.6f, 0.0f}})},
           {"capsules", torch::tensor({{0.0f, -0.05f, 0.0f, 0.05f, 0.3f}})}}) {
    geometry::SceneRows scene;
    scene.insert(kind, row);
    const torch::Tensor guided = planner->PlanWithNoise(start, goal, noise, {}, scene);
    const torch::Tensor moved = guided.slice(1, 1, 15).slice(2, 0, 2).norm(2, -1) -
                                free.slice(1, 1, 15).slice(2, 0, 2).norm(2, -1);
    EXPECT_GT(moved.min().item<float>(), 0.1f) << kind;
  }
}

TEST(FlowSamplerTest, ObstaclesAreChecked) {
  const auto planner = GuidedZero(Splitting::kNone, 1.0);
  const torch::Tensor s = torch::zeros({1, 4}), noise = torch::zeros({1, 16, 4});
  EXPECT_THAT([&] { planner->PlanWithNoise(s, s, noise, {}, Spheres(torch::zeros({1, 4}))); },
              ThrowsMessage<Error>(HasSubstr("plan: spheres: expected (K, 3) rows of spheres")));
  EXPECT_THAT([&] { planner->PlanWithNoise(s, s, noise, {}, Spheres(torch::tensor({{0.f, 0.f, -1.f}}))); },
              ThrowsMessage<Error>(HasSubstr("non-negative radius")));
}

TEST(FlowSamplerTest, PlanningInChunksDoesNotDependOnTheThreadCount) {
  at::set_num_threads(1);
  const auto planner = GuidedZero(Splitting::kMidpoint, 0.5);
  torch::manual_seed(1);
  PlanRequest request;
  request.start = torch::rand({37, 4}) - 0.5;
  request.goal = torch::rand({37, 4}) - 0.5;
  request.scene = Spheres(torch::tensor({{0.0f, 0.0f, 0.2f}}));
  request.seed = 3;
  const PlanResult one = PlanInChunks(*planner, request, 1, 8);
  const PlanResult three = PlanInChunks(*planner, request, 3, 8);
  EXPECT_TRUE(torch::equal(one.plans, three.plans));
  EXPECT_EQ(one.call_seconds.size(), 37u);
  EXPECT_EQ(one.call_plans[0], 8);
  EXPECT_EQ(one.call_plans[36], 5);
  EXPECT_TRUE(one.found.all().item<bool>());
}

}  // namespace
}  // namespace flowplan::planning
