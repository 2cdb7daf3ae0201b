#pragma once

// The UNet1D's forward pass for planning, as a few fused native loops: the
// network flowplan plans with at small batches, where LibTorch spends most of
// a pass on its per-operator cost (docs/performance.md, "Latency at B = 1").
// It computes what models::UNet1D computes (the same layers, float32, no
// gradient) from the UNet's parameters packed once into one flat tensor, and
// is registered as the TorchScript operator `flowplan::unet1d`
// (kernels/unet1d_op.cc) so that a planner's script can call it. Tested
// against the LibTorch network (tests/kernels/unet1d_kernel_test.cc).

#include <torch/torch.h>

#include <functional>
#include <string>
#include <vector>

namespace flowplan::kernels {

/// What the packed parameters and the forward pass need to know of a UNet1D
/// (models::UNetConfig plus the data's sizes).
struct UNet1DShape {
  int64_t state_dim = 0;       // D
  int64_t cond_dim = 0;        // C (0: no global condition)
  std::vector<int64_t> down_dims;
  int64_t kernel_size = 5;
  int64_t groups = 8;
  int64_t time_embed_dim = 32;
  double time_scale = 1.0;
  double norm_eps = 1e-5;

  /// The number of floats PackUNet1D writes for this shape.
  int64_t PackedSize() const;
};

/// The UNet's parameters, read by `parameter(name)` under models::UNet1D's
/// names ("time_in.weight", "down0_block0.block0.conv.weight", ...), rearranged
/// for the kernel into one float32 tensor of PackedSize() numbers. Throws
/// std::runtime_error naming a parameter whose shape does not fit the shape.
torch::Tensor PackUNet1D(const UNet1DShape& shape, const std::function<torch::Tensor(const std::string&)>& parameter);

/// The forward pass: x (B, T, D) float32, t (B,), cond (B, C) or undefined,
/// packed from PackUNet1D with the same shape -> (B, T, D). Batch elements
/// run in parallel on LibTorch's intra-op threads, each on one thread, so the
/// result does not depend on the thread count. No autograd: an input that
/// requires grad is refused (the scripted network sends such inputs to
/// LibTorch's operators instead).
torch::Tensor UNet1DForward(const torch::Tensor& x, const torch::Tensor& t, const torch::Tensor& cond,
                            const torch::Tensor& packed, const UNet1DShape& shape);

}  // namespace flowplan::kernels
