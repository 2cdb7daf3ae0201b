#include "eval/stitching.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "core/error.h"
#include "models/model_config.h"
#include "planning/assemble.h"
#include "tests/support/planners.h"

namespace flowplan::eval {
namespace {

TEST(StitchingTest, ErrorIsTheMeanPositionGapBesideTheEnds) {
  // D = 4: positions are dims 0-1; velocities must not count.
  torch::Tensor plans = torch::zeros({1, 5, 4});
  plans[0][1] = torch::tensor({3.0f, 4.0f, 100.0f, 100.0f});  // 5 away from the start (0, 0)
  plans[0][3] = torch::tensor({1.0f, 1.0f, -7.0f, 9.0f});     // 1 away from the goal (1, 0)
  const torch::Tensor start = torch::zeros({1, 4});
  const torch::Tensor goal = torch::tensor({{1.0f, 0.0f, 5.0f, 5.0f}});
  EXPECT_FLOAT_EQ(StitchingErrors(plans, start, goal, {0, 1})[0].item<float>(), 0.5f * (5.0f + 1.0f));
}

TEST(StitchingTest, PositionsComeFromTheLabelsNotFromHalfTheState) {
  EXPECT_EQ(PositionDims({"x", "y", "vx", "vy"}), (std::vector<int64_t>{0, 1}));
  EXPECT_EQ(PositionDims({"q1", "q2", "dq1", "dq2"}), (std::vector<int64_t>{0, 1}));
  // Positions only, or positions after velocities, or a label that only starts with d.
  EXPECT_EQ(PositionDims({"x", "y", "z"}), (std::vector<int64_t>{0, 1, 2}));
  EXPECT_EQ(PositionDims({"vx", "x", "depth"}), (std::vector<int64_t>{1, 2}));
  EXPECT_THAT([] { PositionDims({}); }, ::testing::ThrowsMessage<Error>(::testing::HasSubstr("no position")));
  torch::Tensor plans = torch::zeros({1, 4, 3});
  plans[0][1][0] = 2.0f;  // x of state 1: 2 away from the start
  plans[0][1][1] = 7.0f;  // its velocity does not count
  plans[0][2][2] = 1.5f;  // depth is a position: state T − 2 is 1.5 from the goal
  EXPECT_FLOAT_EQ(StitchingErrors(plans, torch::zeros({1, 3}), torch::zeros({1, 3}), PositionDims({"x", "vx", "depth"}))[0]
                      .item<float>(),
                  0.5f * (2.0f + 1.5f));
}

std::unique_ptr<planning::LearnedPlanner> SmallPlanner() {
  torch::manual_seed(0);
  models::ModelConfig config;
  config.unet.down_dims = {8, 16};
  planning::PlannerParts parts = testing::Parts(models::MakeTrajectoryNet(config, 4, 0), testing::DiscTrajectory(16),
                                                testing::UnitNormalizer(4));
  parts.sampler.steps = 3;
  parts.sampler.splitting = planning::Splitting::kMidpoint;
  return planning::AssemblePlanner(parts);
}

std::vector<std::string> Labels() { return {"x", "y", "vx", "vy"}; }

datasets::EvalPairTensors Pairs() {
  return {torch::tensor({{0.f, 0.f, 0.f, 0.f}, {0.f, 1.f, 0.f, 0.f}}),
          torch::tensor({{1.f, 0.f, 0.f, 0.f}, {1.f, 1.f, 0.f, 0.f}}), {"a->b", "c->d"}};
}

TEST(StitchingTest, ResultDoesNotDependOnTheThreadCount) {
  at::set_num_threads(1);
  const auto planner = SmallPlanner();
  EvalConfig config;
  config.num_plans = 40;  // three chunks of 16, the last one short
  const StitchingResult one = EvaluateStitching(*planner, Pairs(), Labels(), "test", config, 1);
  const StitchingResult three = EvaluateStitching(*planner, Pairs(), Labels(), "test", config, 3);
  EXPECT_TRUE(torch::equal(one.plans, three.plans));
  EXPECT_EQ(one.mean, three.mean);
  ASSERT_EQ(one.plans.size(0), 40);
  // Plan i targets pair i mod 2.
  EXPECT_TRUE(torch::equal(one.plans[3][15], Pairs().goal[1]));
  EXPECT_EQ(one.pair_names, (std::vector<std::string>{"a->b", "c->d"}));
  EXPECT_GT(one.mean, 0.0);
}

TEST(StitchingTest, JsonReportEscapesNamesAndWritesNaNAsNull) {
  StitchingResult result;
  result.pairs = "test";
  result.mean = 0.25;
  result.stddev = NAN;
  result.pair_names = {"a \"quoted\" pair"};
  result.pair_means = {NAN};
  EXPECT_EQ(ToJson(result),
            "{\"pairs\": \"test\", \"mean\": 0.25, \"stddev\": null, \"num_plans\": 0, "
            "\"per_pair\": {\"a \\\"quoted\\\" pair\": null}}");
}

TEST(StitchingTest, WrongShapesAreNamed) {
  EXPECT_THAT([] { StitchingErrors(torch::zeros({4, 8}), torch::zeros({4, 4}), torch::zeros({4, 4}), {0, 1}); },
              ::testing::ThrowsMessage<Error>(::testing::HasSubstr("plans: expected (N, T, D) with T >= 3, got (4, 8)")));
  EXPECT_THAT([] { StitchingErrors(torch::zeros({4, 8, 4}), torch::zeros({4, 4}), torch::zeros({3, 4}), {0, 1}); },
              ::testing::ThrowsMessage<Error>(::testing::HasSubstr("goal: expected (4, 4), got (3, 4)")));
}

TEST(StitchingTest, NoPairsIsAClearError) {
  const auto planner = SmallPlanner();
  datasets::EvalPairTensors none{torch::zeros({0, 4}), torch::zeros({0, 4}), {}};
  EXPECT_THAT([&] { EvaluateStitching(*planner, none, Labels(), "test", EvalConfig{}); },
              ::testing::ThrowsMessage<Error>(::testing::HasSubstr("defines no test pairs")));
}

}  // namespace
}  // namespace flowplan::eval
