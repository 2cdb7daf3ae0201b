#pragma once

#include "guidance/cost.h"

namespace flowplan::guidance {

/// The constant-velocity Gaussian-process prior of GPMP2 / MPD (SPEC section 2)
/// on states x = [q (J), q̇ (J), ...]: with Φ = [[I, dt·I], [0, I]] and
/// e_i = x_{i+1} − Φ x_i over the first 2J entries,
///   C = Σ_i e_iᵀ Q⁻¹ e_i,   Q⁻¹ = [[12/dt³, −6/dt²], [−6/dt², 4/dt]] ⊗ I/σ².
/// Zero exactly when the positions move at the recorded constant velocity.
class SmoothnessCost : public Cost {
 public:
  /// @param num_joints J; @param dt s between states; @param sigma the prior's σ
  SmoothnessCost(int64_t num_joints, double dt, double sigma);

  torch::Tensor Value(const torch::Tensor& x, const torch::Tensor& obstacles) const override;
  CostAndGradient ValueAndGradient(const torch::Tensor& x, const torch::Tensor& obstacles) const override;
  void WriteScript(jit::ScriptModule& module, const std::string& name) const override;

 private:
  void Check(const torch::Tensor& x) const;

  int64_t J_;
  double dt_;
  double a_, b_, c_;  // the entries 12/(dt³σ²), −6/(dt²σ²), 4/(dt σ²) of Q⁻¹
};

}  // namespace flowplan::guidance
