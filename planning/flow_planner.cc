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
}

void FlowPlanner::CheckRequest(const torch::Tensor& start, const torch::Tensor& goal, const torch::Tensor& noise) const {
  const int64_t D = state_dim();
  const std::string want = "(B, " + std::to_string(D) + ")";
  if (!start.defined() || start.dim() != 2 || start.size(1) != D) throw Error("plan: start: expected " + want + ", got " + ShapeString(start));
  if (!goal.defined() || goal.sizes() != start.sizes()) throw Error("plan: goal: expected " + ShapeString(start) + ", got " + ShapeString(goal));
  if (!noise.defined() || noise.dim() != 3 || noise.size(0) != start.size(0) || noise.size(1) != horizon_ || noise.size(2) != D) {
    throw Error("plan: noise: expected (" + std::to_string(start.size(0)) + ", " + std::to_string(horizon_) + ", " +
                std::to_string(D) + "), got " + ShapeString(noise));
  }
}

VelocityField FlowPlanner::Velocity(const torch::Tensor& start_n, const torch::Tensor& goal_n) const {
  const torch::Tensor cond = ConditionVector(conditioning_, start_n, goal_n);
  const bool inpaint = conditioning_ == Conditioning::kInpaint;
  return [this, cond, inpaint, start_n, goal_n](const torch::Tensor& x, const torch::Tensor& t) {
    return net_->Forward(inpaint ? Inpaint(x, start_n, goal_n) : x, t, cond);
  };
}

torch::Tensor FlowPlanner::PlanNormalized(const torch::Tensor& start_n, const torch::Tensor& goal_n,
                                          const torch::Tensor& noise) const {
  CheckRequest(start_n, goal_n, noise);
  StateHook hook;
  if (conditioning_ == Conditioning::kInpaint) {
    hook = [&](const torch::Tensor& x, double) { return Inpaint(x, start_n, goal_n); };
  }
  return IntegrateEuler(noise, Velocity(start_n, goal_n), TimeGrid{0.0, 1.0, sampler_.steps}, hook);
}

torch::Tensor FlowPlanner::Plan(const torch::Tensor& start, const torch::Tensor& goal, const torch::Tensor& noise) const {
  CheckRequest(start, goal, noise);
  torch::NoGradGuard no_grad;
  const torch::Tensor start_raw = start.to(torch::kFloat32), goal_raw = goal.to(torch::kFloat32);
  const torch::Tensor plan_n = PlanNormalized(normalizer_.Normalize(start_raw), normalizer_.Normalize(goal_raw),
                                              noise.to(torch::kFloat32));
  const torch::Tensor plan = normalizer_.Denormalize(plan_n);
  // The ends are the requested states exactly, not their normalize/clamp round trip.
  return conditioning_ == Conditioning::kInpaint ? Inpaint(plan, start_raw, goal_raw) : plan;
}

torch::Tensor FlowPlanner::Sample(const torch::Tensor& start, const torch::Tensor& goal, at::Generator& generator) const {
  if (!start.defined() || start.dim() != 2) throw Error("plan: start: expected (B, D), got " + ShapeString(start));
  const torch::Tensor noise = torch::randn({start.size(0), horizon_, state_dim()}, generator, torch::kFloat32);
  return Plan(start, goal, noise);
}

}  // namespace flowplan::planning
