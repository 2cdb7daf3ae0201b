#pragma once

#include <torch/torch.h>

#include "models/velocity_net.h"
#include "models/conditioning.h"

namespace flowplan::trainer {

/// Cuts every trajectory into its two halves: (B, T, D) -> (2B, T/2, D), first
/// halves then second halves. Each half keeps its own first and last state,
/// which become its conditions.
/// @throws flowplan::Error if T is odd.
torch::Tensor SplitHalves(const torch::Tensor& x);

/// The data of one training step (split-batch mixing, SPEC section 2):
/// `batch_size` trajectories drawn uniformly with replacement from `data`, and,
/// with probability `split_prob`, every one of them cut into its halves.
/// data: (N, T, D) normalized -> (B, T, D), or (2B, T/2, D) when split.
torch::Tensor DrawTrainingTrajectories(const torch::Tensor& data, int64_t batch_size, double split_prob,
                                       at::Generator& generator);

/// The conditional OT path x_t = t x1 + (1 - t) x0 (t = 0 noise, t = 1 data).
/// x0, x1: (B, T, D); t: (B,) -> (B, T, D).
torch::Tensor InterpolateOt(const torch::Tensor& x0, const torch::Tensor& x1, const torch::Tensor& t);

/// One batch of the flow-matching objective: data, noise and times.
struct FlowMatchingBatch {
  torch::Tensor x1;  // (B, T, D) normalized data
  torch::Tensor x0;  // (B, T, D) standard-normal noise
  torch::Tensor t;   // (B,) flow times in [0, 1)

  int64_t size() const { return x1.size(0); }
  /// Rows [begin, end) of every tensor.
  FlowMatchingBatch Slice(int64_t begin, int64_t end) const;
};

/// Draws x0 ~ N(0, I) and t ~ U[0, 1) for data x1 (B, T, D).
FlowMatchingBatch DrawFlowMatchingBatch(const torch::Tensor& x1, at::Generator& generator);

/// Conditional flow-matching loss on the OT path (SPEC section 2):
/// x_t = t x1 + (1 - t) x0, target x1 - x0, mean squared error.
/// Under inpainting, states 0 and T-1 of x_t are the data's first and last
/// states, and the loss covers the T - 2 interior states only (the ends are
/// overwritten at sampling time, so their prediction carries no signal).
/// @returns scalar loss, the mean over the batch's elements
torch::Tensor FlowMatchingLoss(models::VelocityNet& net, const FlowMatchingBatch& batch,
                               models::Conditioning conditioning);

/// DrawFlowMatchingBatch() then FlowMatchingLoss(). x1: (B, T, D) normalized.
torch::Tensor FlowMatchingLoss(models::VelocityNet& net, const torch::Tensor& x1,
                               models::Conditioning conditioning, at::Generator& generator);

}  // namespace flowplan::trainer
