#pragma once

#include <torch/torch.h>

#include "models/velocity_net.h"
#include "planning/conditioning.h"

namespace flowplan::trainer {

/// Cuts every trajectory into its two halves: (B, T, D) -> (2B, T/2, D), first
/// halves then second halves. Each half keeps its own first and last state,
/// which become its conditions.
/// @throws flowplan::Error if T is odd.
torch::Tensor SplitHalves(const torch::Tensor& x);

/// The conditional OT path x_t = t x1 + (1 - t) x0 (t = 0 noise, t = 1 data).
/// x0, x1: (B, T, D); t: (B,) -> (B, T, D).
torch::Tensor InterpolateOt(const torch::Tensor& x0, const torch::Tensor& x1, const torch::Tensor& t);

/// Conditional flow-matching loss on the OT path (SPEC section 2):
/// t ~ U[0, 1], x0 ~ N(0, I), x_t = t x1 + (1 - t) x0, target x1 - x0, MSE.
/// Under inpainting, states 0 and T-1 of x_t are the data's first and last
/// states, and the loss covers the T - 2 interior states only (the ends are
/// overwritten at sampling time, so their prediction carries no signal).
/// @param x1  (B, T, D) normalized data
/// @returns scalar loss
torch::Tensor FlowMatchingLoss(models::VelocityNet& net, const torch::Tensor& x1,
                               planning::Conditioning conditioning, at::Generator& generator);

}  // namespace flowplan::trainer
