#include "planning/flow_planner.h"

#include "core/error.h"

namespace flowplan::planning {

using models::ShapeString;

FlowPlanner::FlowPlanner(models::VelocityNetPtr net, models::MinMaxNormalizer normalizer,
                         Conditioning conditioning, int64_t horizon, SamplerConfig sampler)
    : net_(std::move(net)),
      normalizer_(std::move(normalizer)),
      conditioning_(conditioning),
      horizon_(horizon),
      sampler_(sampler) {
  FLOWPLAN_DEMAND(net_ != nullptr);
  FLOWPLAN_DEMAND(normalizer_.dim() == net_->state_dim());
  FLOWPLAN_DEMAND(net_->cond_dim() == ConditionDim(conditioning_, net_->state_dim()));
  net_->CheckHorizon(horizon_);
  if (sampler_.steps < 1) throw Error("sampler.steps: expected a positive value, got " + std::to_string(sampler_.steps));
  if (sampler_.splitting != Splitting::kNone) models::CheckHalfHorizon(*net_, horizon_, "sampler.splitting plans");
}

void FlowPlanner::CheckRequest(const torch::Tensor& start, const torch::Tensor& goal, const torch::Tensor& noise,
                               const torch::Tensor& renoise) const {
  const int64_t D = state_dim();
  const std::string want = "(B, " + std::to_string(D) + ")";
  if (!start.defined() || start.dim() != 2 || start.size(1) != D) throw Error("plan: start: expected " + want + ", got " + ShapeString(start));
  if (!goal.defined() || goal.sizes() != start.sizes()) throw Error("plan: goal: expected " + ShapeString(start) + ", got " + ShapeString(goal));
  const std::string want_noise =
      "(" + std::to_string(start.size(0)) + ", " + std::to_string(horizon_) + ", " + std::to_string(D) + ")";
  auto noise_ok = [&](const torch::Tensor& n) {
    return n.defined() && n.dim() == 3 && n.size(0) == start.size(0) && n.size(1) == horizon_ && n.size(2) == D;
  };
  if (!noise_ok(noise)) throw Error("plan: noise: expected " + want_noise + ", got " + ShapeString(noise));
  if (sampler_.splitting != Splitting::kNone && !noise_ok(renoise)) {
    throw Error("plan: renoise: sampler.splitting needs re-noising noise " + want_noise + ", got " + ShapeString(renoise));
  }
}

VelocityField FlowPlanner::Velocity(const torch::Tensor& start_n, const torch::Tensor& goal_n) const {
  const torch::Tensor cond = ConditionVector(conditioning_, start_n, goal_n);
  const bool inpaint = conditioning_ == Conditioning::kInpaint;
  return [this, cond, inpaint, start_n, goal_n](const torch::Tensor& x, const torch::Tensor& t) {
    return net_->Forward(inpaint ? Inpaint(x, start_n, goal_n) : x, t, cond);
  };
}

torch::Tensor FlowPlanner::Integrate(const torch::Tensor& x, const torch::Tensor& start_n, const torch::Tensor& goal_n,
                                     const TimeGrid& grid) const {
  StateHook hook;
  if (conditioning_ == Conditioning::kInpaint) {
    hook = [&](const torch::Tensor& state, double) { return Inpaint(state, start_n, goal_n); };
  }
  return IntegrateEuler(x, Velocity(start_n, goal_n), grid, hook);
}

torch::Tensor FlowPlanner::PlanNormalized(const torch::Tensor& start_n, const torch::Tensor& goal_n,
                                          const torch::Tensor& noise, const torch::Tensor& renoise) const {
  CheckRequest(start_n, goal_n, noise, renoise);
  torch::Tensor x = Integrate(noise, start_n, goal_n, TimeGrid{0.0, 1.0, sampler_.steps});
  if (sampler_.splitting == Splitting::kNone) return x;

  // Midpoint splitting: the states on either side of the middle become the
  // boundaries of the two halves, so the joined plan has no duplicate state.
  const int64_t B = x.size(0), half = horizon_ / 2;
  const torch::Tensor before_mid = x.select(1, half - 1), after_mid = x.select(1, half);
  x = 0.5 * renoise + 0.5 * x;  // back to t = 0.5 on the OT path
  const torch::Tensor halves = torch::cat({x.slice(1, 0, half), x.slice(1, half, horizon_)}, 0);  // (2B, T/2, D)
  const torch::Tensor starts = torch::cat({start_n, after_mid}, 0);
  const torch::Tensor goals = torch::cat({before_mid, goal_n}, 0);
  const torch::Tensor refined = Integrate(halves, starts, goals, TimeGrid{0.5, 1.0, SplitSteps(sampler_)});
  return torch::cat({refined.slice(0, 0, B), refined.slice(0, B, 2 * B)}, 1);
}

torch::Tensor FlowPlanner::Plan(const torch::Tensor& start, const torch::Tensor& goal, const torch::Tensor& noise,
                                const torch::Tensor& renoise) const {
  CheckRequest(start, goal, noise, renoise);
  torch::NoGradGuard no_grad;
  const torch::Tensor start_raw = start.to(torch::kFloat32), goal_raw = goal.to(torch::kFloat32);
  const torch::Tensor plan_n =
      PlanNormalized(normalizer_.Normalize(start_raw), normalizer_.Normalize(goal_raw), noise.to(torch::kFloat32),
                     renoise.defined() ? renoise.to(torch::kFloat32) : renoise);
  const torch::Tensor plan = normalizer_.Denormalize(plan_n);
  // The ends are the requested states exactly, not their normalize/clamp round trip.
  return conditioning_ == Conditioning::kInpaint ? Inpaint(plan, start_raw, goal_raw) : plan;
}

torch::Tensor FlowPlanner::Sample(const torch::Tensor& start, const torch::Tensor& goal, at::Generator& generator) const {
  if (!start.defined() || start.dim() != 2) throw Error("plan: start: expected (B, D), got " + ShapeString(start));
  const std::vector<int64_t> shape = {start.size(0), horizon_, state_dim()};
  const torch::Tensor noise = torch::randn(shape, generator, torch::kFloat32);
  const torch::Tensor renoise =
      sampler_.splitting == Splitting::kNone ? torch::Tensor() : torch::randn(shape, generator, torch::kFloat32);
  return Plan(start, goal, noise, renoise);
}

}  // namespace flowplan::planning
