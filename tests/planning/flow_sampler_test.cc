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
              ThrowsMessage<Error>(HasSubstr("plan: schedule: expected one of one_minus_t, ratio, rising, constant, got sideways")));
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

/// A near-origin request on the disc, and how far each interior state of a
/// plan lies from the origin (the outward direction the hinge pushes along).
struct NearOrigin {
  torch::Tensor start = torch::tensor({{-0.8f, 0.0f, 0.0f, 0.0f}});
  torch::Tensor goal = torch::tensor({{0.8f, 0.0f, 0.0f, 0.0f}});
  torch::Tensor noise, renoise;
  NearOrigin() {
    auto generator = at::make_generator<at::CPUGeneratorImpl>(1);
    noise = 0.01 * torch::randn({1, 16, 4}, generator);
    renoise = 0.01 * torch::randn({1, 16, 4}, generator);
  }
  static torch::Tensor Radii(const torch::Tensor& plan) { return plan.slice(1, 1, 15).slice(2, 0, 2).norm(2, -1); }
};

PlanSettings With(std::map<std::string, double> values, std::optional<std::string> guide_at = std::nullopt,
                  std::optional<std::string> schedule = std::nullopt) {
  PlanSettings settings;
  settings.values = std::move(values);
  settings.guide_at = std::move(guide_at);
  settings.schedule = std::move(schedule);
  return settings;
}

TEST(FlowSamplerTest, GuidanceAtThePredictionMovesThePlanByTheClosedFormAmount) {
  // Zero velocity: x̂1 = x_t. Four steps (h = 0.25), scale 0.1, b(t_i) at t_i = 0, 0.25, 0.5, 0.75 (1 - t unless named):
  //   velocity:   x moves h s sum b(t_i) = 0.25 * 0.1 * 2.5 = 0.0625;
  //   prediction: each step heads for x̂1 moved by G s b(t_i), so x moves h G s b / (1 - t_i) = 0.025 G per step:
  //               0.1 for G = 1 and 0.2 for G = 2, and the plan ends exactly on the last moved x̂1.
  const NearOrigin r;
  const auto planner = GuidedZero(Splitting::kNone, 0.1);
  const geometry::SceneRows obstacle = Spheres(torch::tensor({{0.0f, 0.0f, 0.3f}}));
  const torch::Tensor free = NearOrigin::Radii(planner->PlanWithNoise(r.start, r.goal, r.noise));
  const auto moved = [&](const PlanSettings& settings) {
    return NearOrigin::Radii(planner->PlanWithNoise(r.start, r.goal, r.noise, {}, obstacle, settings)) - free;
  };
  for (const auto& [settings, expected] : std::vector<std::pair<PlanSettings, float>>{
           {With({}, "velocity"), 0.0625f},
           {With({}, "prediction"), 0.1f},
           {With({{"sampler.prediction_iterations", 2}}, "prediction"), 0.2f},
           // The paper's weight at x̂1 with the velocity form: b = 1 - t is never zero where the gradient is taken.
           {With({}, "velocity", "rising"), 0.25f * 0.1f * 1.5f}}) {
    const torch::Tensor m = moved(settings);
    EXPECT_NEAR(m.min().item<float>(), expected, 2e-3) << *settings.guide_at;
    EXPECT_NEAR(m.max().item<float>(), expected, 2e-3) << *settings.guide_at;
  }
  EXPECT_THAT([&] { planner->PlanWithNoise(r.start, r.goal, r.noise, {}, obstacle, With({}, "sideways")); },
              ThrowsMessage<Error>(HasSubstr("plan: guide_at (sampler.guide_at): expected one of state, velocity, prediction, got sideways")));
}

TEST(FlowSamplerTest, GuidanceStartsAtGuideFrom) {
  // b = 1 - t on x_t after the steps reaching 0.75 and 1 only: 0.1 * 0.25; b = 1 (constant) on both: 0.2.
  // On the prediction, taken at t_i: only t_i = 0.75 is at or after 0.6, one step of 0.025 / 0.25 * 0.1 = 0.1
  // with b = 1 (constant), 0.025 with b = 1 - t.
  const NearOrigin r;
  const auto planner = GuidedZero(Splitting::kNone, 0.1);
  const geometry::SceneRows obstacle = Spheres(torch::tensor({{0.0f, 0.0f, 0.3f}}));
  const torch::Tensor free = NearOrigin::Radii(planner->PlanWithNoise(r.start, r.goal, r.noise));
  for (const auto& [schedule, expected] : {std::pair{"one_minus_t", 0.025f}, std::pair{"constant", 0.2f}}) {
    const torch::Tensor m =
        NearOrigin::Radii(planner->PlanWithNoise(r.start, r.goal, r.noise, {}, obstacle,
                                                 With({{"sampler.guide_from", 0.6}}, std::nullopt, schedule))) -
        free;
    EXPECT_NEAR(m.mean().item<float>(), expected, 2e-3) << schedule;
  }
  for (const auto& [schedule, expected] : {std::pair{"one_minus_t", 0.025f}, std::pair{"constant", 0.1f}}) {
    const torch::Tensor m =
        NearOrigin::Radii(planner->PlanWithNoise(r.start, r.goal, r.noise, {}, obstacle,
                                                 With({{"sampler.guide_from", 0.6}}, "prediction", schedule))) -
        free;
    EXPECT_NEAR(m.mean().item<float>(), expected, 2e-3) << "prediction, " << schedule;
  }
  EXPECT_THAT([&] { planner->PlanWithNoise(r.start, r.goal, r.noise, {}, geometry::SceneRows(), With({{"sampler.final_denoise_time", 1.0}})); },
              ThrowsMessage<Error>(HasSubstr("plan: settings: sampler.final_denoise_time: expected a flow time below 1, got 1")));
}

TEST(FlowSamplerTest, TheEndGameStepsOnTheFinishedPlanAndDenoisesBetween) {
  // A velocity of 0.1 in the q̇ dimensions only (which the collision cost does
  // not see): the Euler loop adds 0.1 to q̇, each final re-denoising step from
  // t_r adds (1 - t_r) 0.1 more; each final gradient step moves q out by the scale.
  auto net = std::make_shared<ScriptedNet>(
      4, std::vector<std::string>{"out = torch.cat([torch.zeros_like(x[:, :, 0:2]), torch.full_like(x[:, :, 2:4], 0.1)], 2)"},
      std::vector<std::pair<std::string, torch::Tensor>>{}, 0);
  guidance::GuidanceConfig config;
  config.scale = 0.05;
  config.collision_weight = 1.0;
  config.smoothness_weight = 0.0;
  config.margin = 0.0;
  const auto planner = Flow(net, UnitNormalizer(4), 4, Splitting::kNone, models::Conditioning::kInpaint, config);
  const NearOrigin r;
  const geometry::SceneRows obstacle = Spheres(torch::tensor({{0.0f, 0.0f, 0.3f}}));
  const torch::Tensor free = planner->PlanWithNoise(r.start, r.goal, r.noise);
  const torch::Tensor plain = planner->PlanWithNoise(r.start, r.goal, r.noise, {}, obstacle);
  const torch::Tensor ended = planner->PlanWithNoise(
      r.start, r.goal, r.noise, {}, obstacle,
      With({{"sampler.final_iterations", 2}, {"sampler.final_denoise_time", 0.9}}));
  // Guided by 1 - t: 0.05 * 1.5 = 0.075 out; two final steps: 0.1 more.
  EXPECT_NEAR((NearOrigin::Radii(plain) - NearOrigin::Radii(free)).mean().item<float>(), 0.075f, 2e-3);
  EXPECT_NEAR((NearOrigin::Radii(ended) - NearOrigin::Radii(plain)).mean().item<float>(), 0.1f, 2e-3);
  const torch::Tensor qd_change = (ended - plain).slice(1, 1, 15).slice(2, 2, 4);
  EXPECT_NEAR(qd_change.min().item<float>(), 2 * 0.1f * 0.1f, 1e-5);
  EXPECT_NEAR(qd_change.max().item<float>(), 2 * 0.1f * 0.1f, 1e-5);
  EXPECT_TRUE(torch::equal(ended.select(1, 0), r.start));
  EXPECT_TRUE(torch::equal(ended.select(1, 15), r.goal));
  // Without obstacles nothing guides, so nothing of the end-game runs.
  EXPECT_TRUE(torch::equal(free, planner->PlanWithNoise(r.start, r.goal, r.noise, {}, geometry::SceneRows(),
                                                        With({{"sampler.final_iterations", 2},
                                                              {"sampler.final_denoise_time", 0.9}}))));
}

/// (T, T) (I + l² KᵀK)⁻¹ on the interior states (KᵀK = tridiag(-1, 2, -1), the
/// ends held) scaled to a largest diagonal entry of 1, zero on the ends: the
/// spread the end-game applies, by matrix inversion instead of its closed form.
torch::Tensor SpreadByInversion(int64_t T, double length) {
  const int64_t n = T - 2;
  const torch::Tensor eye = torch::eye(n, torch::kFloat64);
  const torch::Tensor laplacian = 2.0 * eye - eye.roll(1, 1).triu(1) - eye.roll(1, 0).tril(-1);
  const torch::Tensor inverse = torch::linalg_inv(eye + length * length * laplacian);
  torch::Tensor M = torch::zeros({T, T}, torch::kFloat64);
  M.slice(0, 1, T - 1).slice(1, 1, T - 1).copy_(inverse / inverse.diagonal().max());
  return M;
}

TEST(FlowSamplerTest, EndGameSpreadMovesEveryStateByTheSpreadOfThePushes) {
  // One end-game step with sampler.final_spread = l moves the plan by M times
  // the plain step's move, M as SpreadByInversion computes it; the ends stay.
  const NearOrigin r;
  const auto planner = GuidedZero(Splitting::kNone, 0.1);
  const geometry::SceneRows obstacle = Spheres(torch::tensor({{0.0f, 0.0f, 0.3f}}));
  const torch::Tensor base = planner->PlanWithNoise(r.start, r.goal, r.noise, {}, obstacle);
  const torch::Tensor plain_move =
      (planner->PlanWithNoise(r.start, r.goal, r.noise, {}, obstacle, With({{"sampler.final_iterations", 1}})) - base)
          .to(torch::kFloat64);
  ASSERT_GT(plain_move.abs().max().item<double>(), 0.05) << "the test needs a push";
  for (double length : {0.5, 3.0, 1e4}) {
    const torch::Tensor spread =
        planner->PlanWithNoise(r.start, r.goal, r.noise, {}, obstacle,
                               With({{"sampler.final_iterations", 1}, {"sampler.final_spread", length}}));
    const torch::Tensor expected = torch::matmul(SpreadByInversion(16, length), plain_move[0]);
    EXPECT_LT(((spread - base)[0].to(torch::kFloat64) - expected).abs().max().item<double>(), 2e-6)
        << "final_spread " << length;
    EXPECT_TRUE(torch::equal(spread.select(1, 0), r.start));
    EXPECT_TRUE(torch::equal(spread.select(1, 15), r.goal));
  }
  EXPECT_THAT([&] { planner->PlanWithNoise(r.start, r.goal, r.noise, {}, obstacle,
                                           With({{"sampler.final_iterations", 1}, {"sampler.final_spread", 1e-5}})); },
              ThrowsMessage<Error>(HasSubstr("sampler.final_spread: expected 0 or a length in states from 0.001 to 1e6, got 1.0000000000000001e-05")));
  // A long spread moves the middle state as a plain step would and every other state less, tent-like.
  const torch::Tensor tent = SpreadByInversion(16, 1e4);
  EXPECT_NEAR(tent[7][7].item<double>(), 1.0, 1e-12);
  EXPECT_NEAR(tent[1][7].item<double>(), 1.0 / 7.0, 1e-6);  // min(i, j)(n + 1 - max(i, j)) / (7 * 8 / 15) at i = 1
}

TEST(FlowSamplerTest, EndGameJointSpeedWeightActsInTheFinalStepsOnly) {
  // A disc with speed limits of 1 per second (0.1 per state at dt = 0.1), fast
  // noise, an obstacle far away: nothing guides while sampling; the end-game
  // step, weighted by sampler.final_joint_speed_weight, follows the squared
  // hinge's gradient written out here.
  kinematics::TrajectoryInfo trajectory = DiscTrajectory();
  trajectory.robot.velocity_limit = {1.0, 1.0};
  PlannerParts parts = Parts(ZeroVelocity(4), trajectory, UnitNormalizer(4));
  parts.sampler.steps = 4;
  parts.guidance.scale = 0.05;
  parts.guidance.collision_weight = 1.0;
  parts.guidance.smoothness_weight = 0.0;
  parts.guidance.margin = 0.0;
  parts.guidance.clip = 1.0;
  const auto planner = AssemblePlanner(parts);
  auto generator = at::make_generator<at::CPUGeneratorImpl>(3);
  const torch::Tensor noise = 0.2 * torch::randn({1, 16, 4}, generator);
  const torch::Tensor start = torch::zeros({1, 4}), goal = torch::tensor({{0.5f, 0.0f, 0.0f, 0.0f}});
  const geometry::SceneRows far = Spheres(torch::tensor({{5.0f, 5.0f, 0.1f}}));
  const torch::Tensor sampled = planner->PlanWithNoise(start, goal, noise, {}, far);
  EXPECT_TRUE(torch::equal(sampled, planner->PlanWithNoise(start, goal, noise, {}, far,
                                                           With({{"sampler.final_joint_speed_weight", 2.0}}))))
      << "without final steps the weight does nothing";
  EXPECT_TRUE(torch::equal(sampled, planner->PlanWithNoise(start, goal, noise, {}, far,
                                                           With({{"sampler.final_iterations", 1}}))))
      << "far from the obstacle a final step without the speed term does not move the plan";
  const torch::Tensor ended = planner->PlanWithNoise(
      start, goal, noise, {}, far, With({{"sampler.final_iterations", 1}, {"sampler.final_joint_speed_weight", 2.0}}));
  // C = sum relu(|q_{i+1} - q_i| / 0.1 - 1)², dC/dq_i = g_{i-1} - g_i with g_i = 2 excess_i sign(step_i) / 0.1,
  // each state's gradient capped at norm 1 (guidance.clip), then x <- x - 0.05 * 2 * gradient.
  const torch::Tensor q = sampled[0].slice(1, 0, 2).to(torch::kFloat64);
  const torch::Tensor step = q.slice(0, 1, 16) - q.slice(0, 0, 15);
  const torch::Tensor g = 2.0 * torch::relu(step.abs() / 0.1 - 1.0) * torch::sign(step) / 0.1;
  const torch::Tensor zero = torch::zeros({1, 2}, torch::kFloat64);
  torch::Tensor gradient = torch::cat({zero, g}, 0) - torch::cat({g, zero}, 0);
  gradient = gradient / gradient.norm(2, -1, true).clamp_min(1.0);
  torch::Tensor expected = q - 0.05 * 2.0 * gradient;
  expected[0] = q[0];
  expected[15] = q[15];
  ASSERT_GT(gradient.abs().max().item<double>(), 0.5) << "the test needs speeds over the limit";
  EXPECT_LT((ended[0].slice(1, 0, 2).to(torch::kFloat64) - expected).abs().max().item<double>(), 1e-6);
  EXPECT_TRUE(torch::equal(ended.slice(2, 2, 4), sampled.slice(2, 2, 4))) << "the hinge reads positions only";
}

TEST(FlowSamplerTest, SplittingRenoisesToSplitTimeAndStepsTheMidpointFirst) {
  // dx/dt = t, direct conditioning, 10 steps: the first stage gives noise + 0.45;
  // re-noised to t_s = 0.6 the halves take int(10 * 0.4) = 4 steps of 0.1: + 0.3.
  auto net = std::make_shared<ScriptedNet>(4, std::vector<std::string>{"out = t.view(-1, 1, 1).expand_as(x)"},
                                           std::vector<std::pair<std::string, torch::Tensor>>{}, 8);
  const auto split = Flow(net, UnitNormalizer(4), 10, Splitting::kMidpoint, models::Conditioning::kDirect);
  const NearOrigin r;
  const torch::Tensor zero = torch::zeros({1, 4});
  const torch::Tensor joined = split->PlanWithNoise(zero, zero, r.noise, r.renoise, geometry::SceneRows(), With({{"sampler.split_time", 0.6}}));
  EXPECT_TRUE(torch::allclose(joined, 0.4 * r.renoise + 0.6 * (r.noise + 0.45) + 0.3, 0.0, 1e-5));
  EXPECT_THAT([&] { split->PlanWithNoise(zero, zero, r.noise, r.renoise, geometry::SceneRows(), With({{"sampler.split_time", 1.0}})); },
              ThrowsMessage<Error>(HasSubstr("sampler.split_time: expected a flow time in (0, 1), got 1")));
  // Guided midpoint steps: the states beside the middle (the halves' fixed ends)
  // carry the first stage's push (0.15, as above) plus G steps of the scale.
  const auto guided = GuidedZero(Splitting::kMidpoint, 0.1);
  const geometry::SceneRows obstacle = Spheres(torch::tensor({{0.0f, 0.0f, 0.5f}}));
  const torch::Tensor free = guided->PlanWithNoise(r.start, r.goal, r.noise, r.renoise);
  const torch::Tensor stepped =
      guided->PlanWithNoise(r.start, r.goal, r.noise, r.renoise, obstacle, With({{"sampler.midpoint_iterations", 2}}));
  for (int state : {7, 8}) {
    const float moved = (stepped.select(1, state).slice(1, 0, 2).norm() - free.select(1, state).slice(1, 0, 2).norm())
                            .item<float>();
    EXPECT_NEAR(moved, 0.35f, 2e-3) << "state " << state;
  }
}

TEST(FlowSamplerTest, AtScaleZeroEveryVariantSettingLeavesTheUnguidedPlan) {
  const NearOrigin r;
  const geometry::SceneRows obstacle = Spheres(torch::tensor({{0.0f, 0.0f, 0.3f}}));
  for (Splitting splitting : {Splitting::kNone, Splitting::kMidpoint}) {
    const auto planner = Flow(testing::TinyUNet(4, 0), UnitNormalizer(4), 4, splitting);
    const torch::Tensor renoise = splitting == Splitting::kNone ? torch::Tensor() : r.renoise;
    const torch::Tensor free = planner->PlanWithNoise(r.start, r.goal, r.noise, renoise);
    for (const PlanSettings& variant :
         {With({{"guidance.scale", 0}}, "velocity"), With({{"guidance.scale", 0}}, "prediction"),
          With({{"guidance.scale", 0}, {"sampler.prediction_iterations", 3}}, "prediction", "constant"),
          With({{"guidance.scale", 0}, {"sampler.final_iterations", 3}, {"sampler.final_denoise_time", 0.97}}),
          With({{"guidance.scale", 0}, {"sampler.final_iterations", 3}, {"sampler.final_spread", 4},
                {"sampler.final_joint_speed_weight", 1}}),
          With({{"guidance.scale", 0}, {"sampler.midpoint_iterations", 3}, {"sampler.guide_from", 0.5}})}) {
      EXPECT_TRUE(torch::equal(free, planner->PlanWithNoise(r.start, r.goal, r.noise, renoise, obstacle, variant)))
          << "guide_at " << variant.guide_at.value_or("state") << ", splitting " << config::EnumName(splitting);
    }
  }
}

TEST(FlowSamplerTest, BestOfNReturnsTheCandidateOfLeastCost) {
  // Three candidates per request: noise near the origin (inside the sphere),
  // noise shifted out of it (no collision cost), and near the origin again.
  const auto planner = GuidedZero(Splitting::kNone, 0.0);  // unguided: candidates differ by their noise only
  const NearOrigin r;
  const geometry::SceneRows obstacle = Spheres(torch::tensor({{0.0f, 0.0f, 0.3f}}));
  torch::Tensor outside = r.noise.clone();
  outside.slice(2, 1, 2) += 0.5;
  const torch::Tensor candidates = torch::stack({r.noise, outside, 0.5 * r.noise}, 1);  // (1, 3, 16, 4)
  const PlanSettings three = With({{"guidance.candidates", 3}});
  const torch::Tensor best = planner->PlanWithNoise(r.start, r.goal, candidates, {}, obstacle, three);
  EXPECT_TRUE(torch::equal(best, planner->PlanWithNoise(r.start, r.goal, outside, {}, obstacle)));
  // Equal costs (no obstacle, no smoothness weight): the first candidate.
  EXPECT_TRUE(torch::equal(planner->PlanWithNoise(r.start, r.goal, candidates, {}, geometry::SceneRows(), three),
                           planner->PlanWithNoise(r.start, r.goal, r.noise)));
  // Two requests with different ends choose independently: the second's
  // candidates are rolled, so its clear candidate is the third.
  const torch::Tensor starts = torch::cat({r.start, r.start + torch::tensor({{0.0f, 0.05f, 0.0f, 0.0f}})}, 0);
  const torch::Tensor two = planner->PlanWithNoise(starts, r.goal.repeat({2, 1}),
                                                   torch::cat({candidates, candidates.roll(1, 1)}, 0), {}, obstacle, three);
  EXPECT_TRUE(torch::equal(two.select(0, 0), best.select(0, 0)));
  EXPECT_TRUE(torch::equal(two.select(0, 1),
                           planner->PlanWithNoise(starts.slice(0, 1, 2), r.goal, outside, {}, obstacle).select(0, 0)));
  EXPECT_THAT([&] { planner->PlanWithNoise(r.start, r.goal, r.noise, {}, obstacle, three); },
              ThrowsMessage<Error>(HasSubstr("plan: noise: expected [1, 3, 16, 4] (guidance.candidates = 3), got [1, 16, 4]")));
  EXPECT_THAT([&] { planner->PlanWithNoise(r.start, r.goal, candidates, {}, obstacle); },
              ThrowsMessage<Error>(HasSubstr("(for N candidates per plan, set guidance.candidates = N)")));
  // Plan() draws the candidates itself.
  PlanRequest request;
  request.start = r.start.repeat({5, 1});
  request.goal = r.goal.repeat({5, 1});
  request.scene = obstacle;
  request.settings = three;
  EXPECT_EQ(planner->Plan(request).plans.sizes(), (std::vector<int64_t>{5, 16, 4}));
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
