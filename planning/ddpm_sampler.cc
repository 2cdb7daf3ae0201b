#include <cmath>

#include "core/error.h"
#include "jit/library.h"
#include "models/conditioning.h"
#include "models/trajectory_net.h"
#include "objectives/ddpm_schedule.h"
#include "planning/samplers.h"

namespace flowplan::planning {

torch::jit::Module BuildDdpmSampler(const SamplerContext& context) {
  const PlannerParts& parts = context.parts;
  const auto net = std::dynamic_pointer_cast<models::TrajectoryNet>(parts.net);
  if (!net) throw Error("objective.name: ddpm plans with a trajectory network (model.name unet1d or transformer)");
  FLOWPLAN_DEMAND(net->cond_dim() == models::ConditionDim(parts.objective.conditioning, net->state_dim()));
  net->CheckHorizon(parts.trajectory.horizon);
  // The posterior q(x_{k-1} | x_k, x0) of the schedule: mean = mean_x0 x0 + mean_x x_k, std noise_std;
  // x0 = x0_from_x x_k - x0_from_eps eps.
  const objectives::DdpmSchedule schedule(parts.objective.ddpm);
  const int steps = schedule.steps;
  torch::Tensor x0_from_x = torch::empty({steps}, torch::kFloat64), x0_from_eps = torch::empty({steps}, torch::kFloat64);
  torch::Tensor mean_x0 = torch::empty({steps}, torch::kFloat64), mean_x = torch::empty({steps}, torch::kFloat64);
  torch::Tensor noise_std = torch::empty({steps}, torch::kFloat64);
  for (int k = 0; k < steps; ++k) {
    const double a = schedule.alpha_bar(k), a_before = schedule.alpha_bar_before(k), beta = schedule.beta(k);
    x0_from_x[k] = 1.0 / std::sqrt(a);
    x0_from_eps[k] = std::sqrt(1.0 / a - 1.0);
    mean_x0[k] = beta * std::sqrt(a_before) / (1.0 - a);
    mean_x[k] = (1.0 - a_before) * std::sqrt(schedule.alpha(k)) / (1.0 - a);
    noise_std[k] = std::sqrt(beta * (1.0 - a_before) / (1.0 - a));
  }
  return jit::ModuleBuilder("DdpmSampler")
      .Submodule("network", models::ScriptNetwork(*net, parts.sampler.network_kernels))
      .Submodule("normalizer", context.normalizer)
      .Submodule("guide", context.guide)
      .Buffer("x0_from_x", x0_from_x)
      .Buffer("x0_from_eps", x0_from_eps)
      .Buffer("mean_x0", mean_x0)
      .Buffer("mean_x", mean_x)
      .Buffer("noise_std", noise_std)
      .Attribute("conditioning", std::string(config::EnumName(parts.objective.conditioning)))
      .Attribute("diffusion_steps", static_cast<int64_t>(steps))
      .Attribute("guide_on", std::string(config::EnumName(parts.sampler.ddpm.guide_on)))
      .Methods("planning/ddpm_sampler.py")
      .Build();
}

}  // namespace flowplan::planning
