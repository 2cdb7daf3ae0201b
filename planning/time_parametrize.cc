#include "planning/time_parametrize.h"

#include <algorithm>

#include "core/error.h"
#include "core/format.h"

namespace flowplan::planning {

std::pair<torch::Tensor, torch::Tensor> TimeAlongPath(const torch::Tensor& points, int64_t T, double dt) {
  if (!points.defined() || points.dim() != 2 || points.size(0) < 1 || points.scalar_type() != torch::kFloat64) {
    throw Error("time_along_path: points: expected (M, J) float64 with M >= 1, got " +
                (points.defined() ? ShapeText(points.sizes().vec()) + " " + std::string(c10::toString(points.scalar_type()))
                                  : std::string("(undefined)")));
  }
  if (T < 2 || !(dt > 0)) throw Error("time_along_path: expected T >= 2 states and a positive dt");
  const int64_t M = points.size(0), J = points.size(1);
  const torch::Tensor lengths = M > 1 ? (points.slice(0, 1) - points.slice(0, 0, M - 1)).norm(2, 1)
                                      : torch::zeros({0}, torch::kFloat64);  // (M−1,)
  const torch::Tensor cumulative = torch::cat({torch::zeros({1}, torch::kFloat64), lengths.cumsum(0)});
  const double total = cumulative[-1].item<double>();
  torch::Tensor q = torch::empty({T, J}, torch::kFloat64), v = torch::zeros({T, J}, torch::kFloat64);
  const double duration = static_cast<double>(T - 1) * dt;
  const auto c = cumulative.accessor<double, 1>();
  const auto p = points.accessor<double, 2>();
  auto qa = q.accessor<double, 2>();
  auto va = v.accessor<double, 2>();
  int64_t k = 0;
  for (int64_t i = 0; i < T; ++i) {
    const double tau = static_cast<double>(i) / static_cast<double>(T - 1);
    const double s = total * (3.0 * tau * tau - 2.0 * tau * tau * tau);  // non-decreasing in i
    const double speed = total * 6.0 * tau * (1.0 - tau) / duration;    // path length per second
    if (M == 1) {
      for (int64_t j = 0; j < J; ++j) qa[i][j] = p[0][j];
      continue;
    }
    while (k + 2 < M && c[k + 1] < s) ++k;
    const double segment = c[k + 1] - c[k];
    const double u = segment > 0.0 ? std::clamp((s - c[k]) / segment, 0.0, 1.0) : 0.0;
    for (int64_t j = 0; j < J; ++j) {
      qa[i][j] = p[k][j] + u * (p[k + 1][j] - p[k][j]);
      if (segment > 0.0) va[i][j] = speed * (p[k + 1][j] - p[k][j]) / segment;
    }
  }
  for (int64_t j = 0; j < J; ++j) qa[T - 1][j] = p[M - 1][j];
  return {q, v};
}

torch::Tensor TimedStates(const torch::Tensor& points, int64_t T, double dt, int64_t D) {
  auto [q, v] = TimeAlongPath(points, T, dt);
  const int64_t J = q.size(1);
  if (D != J && D != 2 * J) {
    throw Error("timed_states: states of " + std::to_string(D) + " dimensions for a path of " + std::to_string(J) +
                " joints (expected " + std::to_string(J) + " or " + std::to_string(2 * J) + ")");
  }
  return D == J ? q : torch::cat({q, v}, 1);
}

}  // namespace flowplan::planning
