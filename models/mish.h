#pragma once

#include <torch/torch.h>

namespace flowplan::models {

/// Mish(x) = x · tanh(softplus(x)), elementwise, with its gradient: the
/// activation of the UNet and the transformer's time embedding. A bfloat16
/// input (bf16 autocast) is widened to float32 first. Float32 CPU tensors go
/// through one fused, vectorised pass forward and one backward (LibTorch
/// 1.13's `mish` and its backward compute elementwise tanh and log1p
/// without SIMD: a third of a training step); anything else goes to
/// torch::mish. Within 4e-7 relative (plus 1e-30) of torch::mish, its
/// gradient within 2e-6 relative plus 1e-6 (tests/models/mish_test.cc). The TorchScript networks
/// keep torch.mish.
torch::Tensor Mish(const torch::Tensor& x);

}  // namespace flowplan::models
