#include "planning/zoo.h"

#include "core/error.h"
#include "planning/ddpm_planner.h"
#include "planning/latent_planner.h"

namespace flowplan::planning {
namespace {

std::shared_ptr<models::TrajectoryNet> TrajectoryNetOf(const LearnedPlannerParts& parts, const char* objective) {
  auto net = std::dynamic_pointer_cast<models::TrajectoryNet>(parts.net);
  if (!net) {
    throw Error(std::string("objective.name: ") + objective + " plans with a trajectory network (model.name "
                "unet1d or transformer)");
  }
  return net;
}

}  // namespace

std::unique_ptr<Planner> MakeLearnedPlanner(const LearnedPlannerParts& parts) {
  // One line per objective.
  switch (parts.objective.name) {
    case objectives::ObjectiveKind::kFlowMatching:
      return std::make_unique<FlowPlanner>(TrajectoryNetOf(parts, "flow_matching"), parts.normalizer,
                                           parts.objective.conditioning, parts.horizon, parts.sampler, parts.guidance);
    case objectives::ObjectiveKind::kDdpm:
      return std::make_unique<DdpmPlanner>(TrajectoryNetOf(parts, "ddpm"), parts.normalizer,
                                           parts.objective.conditioning, parts.horizon, parts.objective.ddpm,
                                           parts.sampler.ddpm, parts.guidance);
    case objectives::ObjectiveKind::kVae: {
      auto vae = std::dynamic_pointer_cast<models::StateVae>(parts.net);
      if (!vae) throw Error("objective.name: vae plans with a state VAE (model.name state_vae)");
      return std::make_unique<LatentPlanner>(vae, parts.normalizer, parts.horizon, parts.sampler.latent, parts.guidance);
    }
  }
  FLOWPLAN_DEMAND(false);
  return nullptr;
}

}  // namespace flowplan::planning
