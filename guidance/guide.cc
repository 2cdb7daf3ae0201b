#include "guidance/guide.h"

#include <algorithm>

#include "core/error.h"
#include "guidance/collision_cost.h"
#include "guidance/smoothness_cost.h"

namespace flowplan::guidance {

double GuidanceFactor(GuidanceSchedule schedule, double t) {
  switch (schedule) {
    case GuidanceSchedule::kOneMinusT:
      return 1.0 - t;
    case GuidanceSchedule::kRatio:
      return (1.0 - t) / std::max(t, kMinRatioTime);
    case GuidanceSchedule::kRising:
      return t;
  }
  return 1.0 - t;
}

std::shared_ptr<const WeightedSumCost> MakeGuidanceCost(const GuidanceConfig& config,
                                                        std::shared_ptr<const kinematics::Robot> robot, double dt) {
  FLOWPLAN_DEMAND(robot != nullptr);
  const int64_t J = robot->num_joints();
  std::vector<WeightedSumCost::Term> terms;
  terms.push_back({"collision", config.collision_weight, std::make_shared<CollisionCost>(robot, config.margin)});
  terms.push_back(
      {"smoothness", config.smoothness_weight, std::make_shared<SmoothnessCost>(J, dt, config.smoothness_sigma)});
  return std::make_shared<WeightedSumCost>(std::move(terms));
}

Guide::Guide(std::shared_ptr<const WeightedSumCost> cost, models::MinMaxNormalizer normalizer, GuidanceConfig config)
    : cost_(std::move(cost)), normalizer_(std::move(normalizer)), config_(config) {
  FLOWPLAN_DEMAND(cost_ != nullptr && normalizer_.fitted());
}

torch::Tensor Guide::Gradient(const torch::Tensor& x_n, const torch::Tensor& obstacles) const {
  // Costs see raw states; x = (x_n + 1)/2 (hi − lo) + lo, so ∂/∂x_n = ∂/∂x · (hi − lo)/2.
  const torch::Tensor x = normalizer_.DenormalizeUnclamped(x_n);
  torch::Tensor gradient = torch::zeros_like(x);
  for (const WeightedSumCost::Term& term : cost_->terms()) {
    if (term.weight == 0.0) continue;
    torch::Tensor part = term.cost->ValueAndGradient(x, obstacles).gradient;
    if (config_.clip > 0.0) {
      // Written as the script writes it (tensor / float, then tensor / tensor), so that both round alike.
      part = part / (part.norm(2, -1, /*keepdim=*/true).clamp_min(config_.clip) / config_.clip);
    }
    gradient = gradient + term.weight * part;
  }
  return gradient * (0.5 * (normalizer_.hi() - normalizer_.lo()));
}

torch::Tensor Guide::Step(const torch::Tensor& x_n, double t, const torch::Tensor& obstacles, double scale) const {
  if (scale == 0.0 || !obstacles.defined()) return x_n;
  return x_n - (scale * GuidanceFactor(config_.schedule, t)) * Gradient(x_n, obstacles);
}

void Guide::WriteScript(jit::ScriptModule& module) const {
  cost_->WriteScript(module, "guidance_cost");  // also writes guidance_cost_<term> for every weighted term
  std::string s = R"PY(
def guide_gradient(self, x: Tensor, obstacles: Tensor) -> Tensor:
    raw = self.denormalize_unclamped(x)
    gradient = torch.zeros_like(x)
)PY";
  for (const WeightedSumCost::Term& term : cost_->terms()) {
    if (term.weight == 0.0) continue;
    s += "    value, part = self.guidance_cost_" + term.name + "(raw, obstacles)\n";
    if (config_.clip > 0.0) {
      const std::string clip = jit::ScriptFloat(config_.clip);
      s += "    part = part / (torch.norm(part, 2, -1, True).clamp_min(" + clip + ") / " + clip + ")\n";
    }
    s += "    gradient = gradient + " + jit::ScriptFloat(term.weight) + " * part\n";
  }
  s += "    return gradient * (0.5 * (self.hi - self.lo))\n";
  s += "\ndef guide(self, x: Tensor, t: float, obstacles: Tensor, scale: float) -> Tensor:\n";
  switch (config_.schedule) {
    case GuidanceSchedule::kOneMinusT:
      s += "    b = 1.0 - t\n";
      break;
    case GuidanceSchedule::kRatio:
      s += "    b = (1.0 - t) / max(t, " + jit::ScriptFloat(kMinRatioTime) + ")\n";
      break;
    case GuidanceSchedule::kRising:
      s += "    b = t\n";
      break;
  }
  s += "    return x - (scale * b) * self.guide_gradient(x, obstacles)\n";
  module.Define(s);
}

}  // namespace flowplan::guidance
