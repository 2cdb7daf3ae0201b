#pragma once

#include "objectives/objective.h"

namespace flowplan::objectives {

/// The conditional OT path x_t = t x1 + (1 − t) x0 (t = 0 noise, t = 1 data).
/// x0, x1: (B, T, D); t: (B,) -> (B, T, D).
torch::Tensor InterpolateOt(const torch::Tensor& x0, const torch::Tensor& x1, const torch::Tensor& t);

/// Conditional flow matching (SPEC section 2): x0 ~ N(0, I), t ~ U[0, 1),
/// the network sees x_t and t and regresses the velocity x1 − x0.
/// Batch: noise (B, T, D) = x0, time (B,) = t.
class FlowMatchingObjective : public Objective {
 public:
  ObjectiveBatch Draw(const torch::Tensor& x1, at::Generator& generator) const override;
  torch::Tensor Loss(models::Network& net, const ObjectiveBatch& batch,
                     models::Conditioning conditioning) const override;
};

}  // namespace flowplan::objectives
