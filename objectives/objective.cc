#include "objectives/objective.h"

#include "core/error.h"
#include "objectives/ddpm.h"
#include "objectives/flow_matching.h"
#include "objectives/vae.h"

namespace flowplan::objectives {

ObjectiveBatch ObjectiveBatch::Slice(int64_t begin, int64_t end) const {
  return {x1.slice(0, begin, end), noise.defined() ? noise.slice(0, begin, end) : noise,
          time.defined() ? time.slice(0, begin, end) : time};
}

ObjectiveBatch ObjectiveBatch::To(const torch::Device& device) const {
  return {x1.to(device), noise.defined() ? noise.to(device) : noise, time.defined() ? time.to(device) : time};
}

std::unique_ptr<Objective> MakeObjective(const ObjectiveConfig& config, const models::ModelConfig& model) {
  // One line per objective.
  switch (config.name) {
    case ObjectiveKind::kFlowMatching: return std::make_unique<FlowMatchingObjective>();
    case ObjectiveKind::kDdpm: return std::make_unique<DdpmObjective>(config.ddpm);
    case ObjectiveKind::kVae: return std::make_unique<VaeObjective>(config.vae, model.vae.latent);
  }
  FLOWPLAN_DEMAND(false);
  return nullptr;
}

}  // namespace flowplan::objectives
