#pragma once

#include <torch/torch.h>

namespace flowplan::trainer {

/// Cuts every trajectory into its two halves: (B, T, D) -> (2B, T/2, D), first
/// halves then second halves. Each half keeps its own first and last state,
/// which become its conditions.
/// @throws flowplan::Error if T is odd.
torch::Tensor SplitHalves(const torch::Tensor& x);

/// The data of one training step (split-batch mixing, SPEC section 2), the
/// same for every objective: `batch_size` trajectories drawn uniformly with
/// replacement from `data`, and, with probability `split_prob`, every one of
/// them cut into its halves.
/// data: (N, T, D) normalized -> (B, T, D), or (2B, T/2, D) when split.
torch::Tensor DrawTrainingTrajectories(const torch::Tensor& data, int64_t batch_size, double split_prob,
                                       at::Generator& generator);

}  // namespace flowplan::trainer
