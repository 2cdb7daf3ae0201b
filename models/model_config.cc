#include "models/model_config.h"

#include "core/error.h"

namespace flowplan::models {

NetworkPtr MakeNetwork(const ModelConfig& config, int64_t state_dim, int64_t cond_dim) {
  // One line per network.
  switch (config.architecture) {
    case Architecture::kUNet1D: return std::make_shared<UNet1D>(config.unet, state_dim, cond_dim);
    case Architecture::kTransformer: return std::make_shared<Transformer>(config.transformer, state_dim, cond_dim);
    case Architecture::kStateVae: return std::make_shared<StateVae>(config.vae, state_dim);
  }
  FLOWPLAN_DEMAND(false);
  return nullptr;
}

TrajectoryNetPtr MakeTrajectoryNet(const ModelConfig& config, int64_t state_dim, int64_t cond_dim) {
  auto net = std::dynamic_pointer_cast<TrajectoryNet>(MakeNetwork(config, state_dim, cond_dim));
  if (!net) {
    throw Error(std::string("model.name: ") + config::EnumName(config.architecture) +
                " is not a trajectory network (unet1d or transformer)");
  }
  return net;
}

void CopyWeights(const torch::nn::Module& from, torch::nn::Module& to) {
  torch::NoGradGuard no_grad;
  const auto source_params = from.named_parameters(true);
  auto target_params = to.named_parameters(true);
  FLOWPLAN_DEMAND(source_params.size() == target_params.size());
  for (const auto& item : source_params) target_params[item.key()].copy_(item.value());
  const auto source_buffers = from.named_buffers(true);
  auto target_buffers = to.named_buffers(true);
  FLOWPLAN_DEMAND(source_buffers.size() == target_buffers.size());
  for (const auto& item : source_buffers) target_buffers[item.key()].copy_(item.value());
}

int64_t CountParameters(const torch::nn::Module& module) {
  int64_t count = 0;
  for (const auto& p : module.parameters(true)) count += p.numel();
  return count;
}

}  // namespace flowplan::models
