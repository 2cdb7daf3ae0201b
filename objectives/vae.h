#pragma once

#include "objectives/objective.h"

namespace flowplan::objectives {

/// The VAE objective over single states: every state of every trajectory of
/// the batch is encoded, a latent drawn by reparametrization, decoded; the
/// loss is the squared reconstruction error summed over D plus beta times the
/// KL divergence to N(0, I) summed over L, both averaged over the states.
/// Batch: noise (B, T, L) for the reparametrization; no time.
class VaeObjective : public Objective {
 public:
  VaeObjective(const VaeObjectiveConfig& config, int64_t latent_dim) : config_(config), latent_dim_(latent_dim) {}

  ObjectiveBatch Draw(const torch::Tensor& x1, at::Generator& generator) const override;
  /// @throws flowplan::Error if `net` is not a StateVae.
  torch::Tensor Loss(models::Network& net, const ObjectiveBatch& batch, models::Conditioning) const override;

 private:
  VaeObjectiveConfig config_;
  int64_t latent_dim_;
};

}  // namespace flowplan::objectives
