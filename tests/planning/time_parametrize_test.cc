// Timing a joint-space path (planning/time_parametrize.h) against the
// closed form of the rest-to-rest profile s(τ) = 3τ² − 2τ³ on a straight line.

#include "planning/time_parametrize.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "core/error.h"

namespace flowplan::planning {
namespace {

using ::testing::HasSubstr;
using ::testing::ThrowsMessage;

TEST(TimeAlongPathTest, AStraightLineWithRepeatedPointsIsTimedByTheClosedForm) {
  // The line from a to b, given as a polyline that dwells at a (repeated points) and jumps in three pieces.
  const torch::Tensor a = torch::tensor({0.1, -0.2, 0.3}, torch::kFloat64), b = torch::tensor({0.9, 0.4, -0.3}, torch::kFloat64);
  std::vector<torch::Tensor> rows(5, a);
  for (double u : {0.2, 0.7, 1.0}) rows.push_back(a + u * (b - a));
  const torch::Tensor points = torch::stack(rows);  // (8, 3)
  const int64_t T = 21;
  const double dt = 0.05, duration = (T - 1) * dt, length = (b - a).norm().item<double>();
  const auto [q, v] = TimeAlongPath(points, T, dt);
  ASSERT_EQ(q.sizes(), (std::vector<int64_t>{T, 3}));
  ASSERT_EQ(v.sizes(), (std::vector<int64_t>{T, 3}));
  for (int64_t i = 0; i < T; ++i) {
    const double tau = static_cast<double>(i) / (T - 1), s = 3 * tau * tau - 2 * tau * tau * tau;
    const double speed = 6 * tau * (1 - tau) / duration;  // ds/dt as a fraction of the line per second
    EXPECT_LT((q[i] - (a + s * (b - a))).abs().max().item<double>(), 1e-12) << "state " << i;
    EXPECT_LT((v[i] - speed * (b - a)).abs().max().item<double>(), 1e-12) << "state " << i;
  }
  EXPECT_TRUE(torch::equal(q[0], a));
  EXPECT_TRUE(torch::equal(q[T - 1], points[-1]));  // the polyline's last point, exactly
  // The largest speed is 1.5 L / duration, at mid-course.
  EXPECT_NEAR(v.norm(2, 1).max().item<double>(), 1.5 * length / duration, 1e-12);
}

TEST(TimeAlongPathTest, EveryStateOfABentPathLiesOnIt) {
  // An L: along x, then along y. Each state has x = 1 or y = 0, and they come in order of arc length.
  const torch::Tensor points = torch::tensor({{0.0, 0.0}, {1.0, 0.0}, {1.0, 2.0}}, torch::kFloat64);
  const auto [q, v] = TimeAlongPath(points, 40, 0.1);
  double previous = -1.0;
  for (int64_t i = 0; i < 40; ++i) {
    const double x = q[i][0].item<double>(), y = q[i][1].item<double>();
    EXPECT_TRUE(std::abs(y) < 1e-12 || std::abs(x - 1.0) < 1e-12) << "state " << i << " at " << x << ", " << y;
    const double arc = x + y;
    EXPECT_GE(arc, previous);
    previous = arc;
  }
  EXPECT_DOUBLE_EQ(previous, 3.0);
}

TEST(TimeAlongPathTest, OnePointIsRestAndBadInputIsRefused) {
  const auto [q, v] = TimeAlongPath(torch::tensor({{0.5, -0.5}}, torch::kFloat64), 4, 0.1);
  EXPECT_TRUE(torch::equal(q, torch::tensor({0.5, -0.5}, torch::kFloat64).expand({4, 2})));
  EXPECT_TRUE(torch::equal(v, torch::zeros({4, 2}, torch::kFloat64)));
  EXPECT_THAT([] { TimeAlongPath(torch::zeros({3, 2}), 4, 0.1); },
              ThrowsMessage<Error>(HasSubstr("expected (M, J) float64")));
  EXPECT_THAT([] { TimeAlongPath(torch::zeros({3, 2}, torch::kFloat64), 1, 0.1); },
              ThrowsMessage<Error>(HasSubstr("T >= 2")));
}

}  // namespace
}  // namespace flowplan::planning
