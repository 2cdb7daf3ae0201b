#include "validity/plan_quality.h"

#include "core/error.h"
#include "core/format.h"

namespace flowplan::validity {

std::vector<PlanQuality> MeasurePlans(const torch::Tensor& plans, const kinematics::Robot& robot, double dt,
                                      double at_rest) {
  const int64_t J = robot.num_joints();
  if (!plans.defined() || plans.dim() != 3 || plans.size(2) < J || plans.size(1) < 1) {
    throw Error("quality: plans: expected (N, T, D) with D >= " + std::to_string(J) + ", got " +
                (plans.defined() ? ShapeText(plans.sizes().vec()) : "(undefined)"));
  }
  const int64_t N = plans.size(0), T = plans.size(1);
  const torch::Tensor q = plans.to(torch::kFloat64).slice(2, 0, J).contiguous();  // (N, T, J)
  const torch::Tensor step = q.slice(1, 1, T) - q.slice(1, 0, T - 1);             // (N, T - 1, J)
  const torch::Tensor joint_length = step.norm(2, -1).sum(1);                       // (N,)
  const torch::Tensor tcp = robot.Tcp(q.view({N * T, J})).view({N, T, -1});
  const torch::Tensor tcp_length = (tcp.slice(1, 1, T) - tcp.slice(1, 0, T - 1)).norm(2, -1).sum(1);
  torch::Tensor speed = torch::zeros({N}, torch::kFloat64);
  const auto& limits = robot.description().velocity_limit;
  if (!limits.empty() && T > 1) {
    const torch::Tensor limit = torch::tensor(limits, torch::kFloat64).view({1, 1, J});
    speed = (step.abs() / dt / limit).flatten(1).amax(1);
  }
  torch::Tensor jerk = torch::zeros({N}, torch::kFloat64);
  if (T >= 4) {
    const torch::Tensor third =
        (q.slice(1, 3, T) - 3.0 * q.slice(1, 2, T - 1) + 3.0 * q.slice(1, 1, T - 2) - q.slice(1, 0, T - 3)) /
        (dt * dt * dt);
    jerk = third.square().flatten(1).mean(1);
  }
  // Index of the last state still away from the final one (-1: it never leaves it).
  const torch::Tensor away = (q - q.slice(1, T - 1, T)).abs().amax(-1) > at_rest;  // (N, T)
  const torch::Tensor index = torch::arange(T, torch::kInt64).view({1, T}).expand({N, T});
  const torch::Tensor last_away = torch::where(away, index, torch::full_like(index, -1)).amax(1);  // (N,)
  std::vector<PlanQuality> out(static_cast<size_t>(N));
  for (int64_t n = 0; n < N; ++n) {
    PlanQuality& p = out[static_cast<size_t>(n)];
    p.joint_path_length = joint_length[n].item<double>();
    p.tcp_path_length = tcp_length[n].item<double>();
    p.max_speed_ratio = speed[n].item<double>();
    p.mean_squared_jerk = jerk[n].item<double>();
    // The arm arrives one state after the last one away from the goal.
    p.duration = static_cast<double>(last_away[n].item<int64_t>() + 1) * dt;
  }
  return out;
}

}  // namespace flowplan::validity
