#include "core/error.h"
#include "jit/library.h"
#include "models/conditioning.h"
#include "models/trajectory_net.h"
#include "planning/samplers.h"

namespace flowplan::planning {

torch::jit::Module BuildFlowSampler(const SamplerContext& context) {
  const PlannerParts& parts = context.parts;
  const auto net = std::dynamic_pointer_cast<models::TrajectoryNet>(parts.net);
  if (!net) throw Error("objective.name: flow_matching plans with a trajectory network (model.name unet1d or transformer)");
  FLOWPLAN_DEMAND(net->cond_dim() == models::ConditionDim(parts.objective.conditioning, net->state_dim()));
  const int64_t T = parts.trajectory.horizon;
  net->CheckHorizon(T);
  if (parts.sampler.splitting != Splitting::kNone) models::CheckHalfHorizon(*net, T, "sampler.splitting plans");
  return jit::ModuleBuilder("FlowSampler")
      .Submodule("network", models::ScriptNetwork(*net, parts.sampler.network_kernels))
      .Submodule("normalizer", context.normalizer)
      .Submodule("guide", context.guide)
      .Attribute("conditioning", std::string(config::EnumName(parts.objective.conditioning)))
      .Attribute("splitting", std::string(config::EnumName(parts.sampler.splitting)))
      .Attribute("horizon", T)
      .Methods("planning/flow_sampler.py")
      .Build();
}

}  // namespace flowplan::planning
