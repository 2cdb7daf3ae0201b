#pragma once

#include <torch/torch.h>

namespace flowplan::models {

/// Mish(x) = x · tanh(softplus(x)), elementwise, with its gradient: the
/// activation of the UNet and the transformer's time embedding. A bfloat16
/// input (bf16 autocast) is widened to float32 first. Float32 CPU tensors go
/// through one fused, vectorised pass forward and one backward (LibTorch
/// 1.13's `mish` and its backward compute elementwise tanh and log1p
/// without SIMD: more than a quarter of a training step); anything else goes
/// to torch::mish. Within 4e-7 relative of torch::mish for x ≥ -87 (below,
/// -0 where it is under 1.5e-36), its gradient within 2e-6 relative plus 1e-6
/// (tests/models/mish_test.cc); the same bits for any thread count. No second
/// derivative. The TorchScript networks keep torch.mish.
torch::Tensor Mish(const torch::Tensor& x);

}  // namespace flowplan::models
