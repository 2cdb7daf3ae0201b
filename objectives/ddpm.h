#pragma once

#include "objectives/ddpm_schedule.h"
#include "objectives/objective.h"

namespace flowplan::objectives {

/// DDPM with ε-prediction as Motion Planning Diffusion trains it: a step
/// k ~ U{0, …, N−1}, x_k = sqrt(ᾱ_k) x1 + sqrt(1 − ᾱ_k) ε, the network sees x_k
/// and k (as a float) and regresses ε. Batch: noise (B, T, D) = ε, time (B,) = k.
class DdpmObjective : public Objective {
 public:
  explicit DdpmObjective(const DdpmConfig& config) : schedule_(config) {}

  ObjectiveBatch Draw(const torch::Tensor& x1, at::Generator& generator) const override;
  torch::Tensor Loss(models::Network& net, const ObjectiveBatch& batch,
                     models::Conditioning conditioning) const override;

  const DdpmSchedule& schedule() const { return schedule_; }

 private:
  DdpmSchedule schedule_;
};

}  // namespace flowplan::objectives
