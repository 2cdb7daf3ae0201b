#include "core/error.h"
#include "jit/library.h"
#include "models/state_vae.h"
#include "planning/samplers.h"

namespace flowplan::planning {

torch::jit::Module BuildLatentSampler(const SamplerContext& context) {
  const PlannerParts& parts = context.parts;
  const auto vae = std::dynamic_pointer_cast<models::StateVae>(parts.net);
  if (!vae) throw Error("objective.name: vae plans with a state VAE (model.name state_vae)");
  if (parts.trajectory.horizon < 2) throw Error("latent planner: expected a horizon of at least 2 states");
  return jit::ModuleBuilder("LatentSampler")
      .Submodule("vae", vae->ToScript())
      .Submodule("normalizer", context.normalizer)
      .Submodule("robot", context.robot)
      .Submodule("guide", context.guide)
      .Attribute("horizon", parts.trajectory.horizon)
      .Attribute("adam_beta1", 0.9)
      .Attribute("adam_beta2", 0.999)
      .Attribute("adam_epsilon", 1e-8)
      .Methods("planning/latent_sampler.py")
      .Build();
}

}  // namespace flowplan::planning
