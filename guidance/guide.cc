#include "guidance/guide.h"

#include <algorithm>

#include "core/error.h"
#include "guidance/collision_cost.h"
#include "guidance/smoothness_cost.h"

namespace flowplan::guidance {

double GuidanceFactor(GuidanceSchedule schedule, double t) {
  return schedule == GuidanceSchedule::kRatio ? (1.0 - t) / std::max(t, kMinRatioTime) : 1.0 - t;
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

Guide::Guide(std::shared_ptr<const Cost> cost, models::MinMaxNormalizer normalizer, GuidanceConfig config)
    : cost_(std::move(cost)), normalizer_(std::move(normalizer)), config_(config) {
  FLOWPLAN_DEMAND(cost_ != nullptr && normalizer_.fitted());
}

torch::Tensor Guide::Gradient(const torch::Tensor& x_n, const torch::Tensor& obstacles) const {
  // Costs see raw states; x = (x_n + 1)/2 (hi − lo) + lo, so ∂/∂x_n = ∂/∂x · (hi − lo)/2.
  const torch::Tensor x = normalizer_.DenormalizeUnclamped(x_n);
  torch::Tensor gradient = cost_->ValueAndGradient(x, obstacles).gradient * (0.5 * (normalizer_.hi() - normalizer_.lo()));
  if (config_.clip > 0.0) {
    const torch::Tensor norm = gradient.norm(2, -1, /*keepdim=*/true);
    // Written as the script writes it (tensor / float, then tensor / tensor), so
    // that both round alike.
    gradient = gradient / (norm.clamp_min(config_.clip) / config_.clip);
  }
  return gradient;
}

torch::Tensor Guide::Step(const torch::Tensor& x_n, double t, const torch::Tensor& obstacles, double scale) const {
  if (scale == 0.0 || !obstacles.defined()) return x_n;
  return x_n - (scale * GuidanceFactor(config_.schedule, t)) * Gradient(x_n, obstacles);
}

void Guide::WriteScript(jit::ScriptModule& module) const {
  cost_->WriteScript(module, "guidance_cost");
  std::string s = R"PY(
def guide(self, x: Tensor, t: float, obstacles: Tensor, scale: float) -> Tensor:
    value, gradient = self.guidance_cost(self.denormalize_unclamped(x), obstacles)
    gradient = gradient * (0.5 * (self.hi - self.lo))
)PY";
  if (config_.clip > 0.0) {
    const std::string clip = jit::ScriptFloat(config_.clip);
    s += "    gradient = gradient / (torch.norm(gradient, 2, -1, True).clamp_min(" + clip + ") / " + clip + ")\n";
  }
  s += config_.schedule == GuidanceSchedule::kRatio
           ? "    b = (1.0 - t) / max(t, " + jit::ScriptFloat(kMinRatioTime) + ")\n"
           : "    b = 1.0 - t\n";
  s += "    return x - (scale * b) * gradient\n";
  module.Define(s);
}

}  // namespace flowplan::guidance
