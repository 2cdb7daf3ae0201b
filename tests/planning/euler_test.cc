#include "planning/euler.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "core/error.h"

namespace flowplan::planning {
namespace {

TEST(EulerTest, ConstantVelocityIsIntegratedExactly) {
  const torch::Tensor x0 = torch::randn({3, 8, 2}, torch::kFloat64);
  const torch::Tensor c = torch::randn({3, 8, 2}, torch::kFloat64);
  for (int steps : {1, 7, 10}) {
    const torch::Tensor x1 = IntegrateEuler(x0, [&](const torch::Tensor&, const torch::Tensor&) { return c; },
                                            TimeGrid{0.0, 1.0, steps});
    EXPECT_TRUE(torch::allclose(x1, x0 + c, 0.0, 1e-12)) << steps << " steps";
  }
}

TEST(EulerTest, LinearInTimeVelocityMatchesTheLeftRiemannSum) {
  // dx/dt = t: Euler with h = 1/n gives sum_i h * (i h) = (n - 1) / (2 n).
  const torch::Tensor x0 = torch::zeros({1, 1, 1}, torch::kFloat64);
  const int n = 10;
  const torch::Tensor x1 = IntegrateEuler(
      x0, [](const torch::Tensor& x, const torch::Tensor& t) { return t.view({-1, 1, 1}).expand_as(x); },
      TimeGrid{0.0, 1.0, n});
  EXPECT_NEAR(x1.item<double>(), (n - 1) / (2.0 * n), 1e-7);
}

TEST(EulerTest, ProjectionRunsFirstAndAfterEveryStepAndCorrectionAfterEveryStepAtItsEndTime) {
  std::vector<std::string> calls;
  IntegrateEuler(
      torch::zeros({1, 2, 1}), [](const torch::Tensor& x, const torch::Tensor&) { return x; }, TimeGrid{0.5, 1.0, 5},
      [&](const torch::Tensor& x) {
        calls.push_back("project");
        return x;
      },
      [&](const torch::Tensor& x, double t) {
        calls.push_back("correct " + std::to_string(t).substr(0, 3));
        return x;
      });
  ASSERT_EQ(calls.size(), 11u);
  EXPECT_EQ(calls[0], "project");
  EXPECT_EQ(calls[1], "correct 0.6");
  EXPECT_EQ(calls[2], "project");
  EXPECT_EQ(calls[9], "correct 1.0");
  EXPECT_EQ(calls[10], "project");
}

TEST(EulerTest, CorrectionChangesTheStateThatTheNextStepStartsFrom) {
  // dx/dt = 0, and each correction adds t: the result is the sum of the step end times.
  const torch::Tensor x = IntegrateEuler(
      torch::zeros({1, 1, 1}, torch::kFloat64),
      [](const torch::Tensor& state, const torch::Tensor&) { return torch::zeros_like(state); },
      TimeGrid{0.0, 1.0, 4}, nullptr, [](const torch::Tensor& state, double t) { return state + t; });
  EXPECT_NEAR(x.item<double>(), 0.25 + 0.5 + 0.75 + 1.0, 1e-12);
}

TEST(EulerTest, VelocitySeesTheGridTimes) {
  std::vector<float> seen;
  IntegrateEuler(torch::zeros({2, 2, 1}),
                 [&](const torch::Tensor& x, const torch::Tensor& t) {
                   seen.push_back(t[1].item<float>());
                   return x;
                 },
                 TimeGrid{0.0, 1.0, 4});
  EXPECT_THAT(seen, ::testing::ElementsAre(0.0f, 0.25f, 0.5f, 0.75f));
}

TEST(EulerTest, ZeroStepsIsAnError) {
  EXPECT_THROW(IntegrateEuler(torch::zeros({1, 2, 1}), nullptr, TimeGrid{0.0, 1.0, 0}), Error);
}

}  // namespace
}  // namespace flowplan::planning
