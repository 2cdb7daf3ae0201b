#pragma once

#include <torch/torch.h>

#include <string>

#include "core/config.h"

namespace flowplan::models {

/// The arithmetic a training step's forward and backward passes run in.
/// Master weights, gradients, optimizer state, EMA, checkpoints, validation
/// and planning stay float32 either way.
enum class Precision {
  kFp32,  // float32 throughout
  kBf16,  // LibTorch's CPU autocast: convolutions, linear layers and matrix products in bfloat16
};

inline const config::EnumNames<Precision>& EnumEntries(Precision) {
  static const config::EnumNames<Precision> names = {{Precision::kFp32, "fp32"}, {Precision::kBf16, "bf16"}};
  return names;
}

/// Runs the LibTorch CPU operators of its scope, on the calling thread only,
/// under autocast to `precision` (nothing for kFp32). Autocast's state is kept
/// per thread, so every worker thread that computes a loss opens its own
/// scope; backward may run after the scope, on the dtypes the forward pass
/// recorded. Leaving the outermost scope drops the cached bfloat16 copies of
/// the weights, which the optimizer is about to change. A kFp32 scope does
/// not switch off an enclosing bf16 one.
class AutocastScope {
 public:
  explicit AutocastScope(Precision precision);
  ~AutocastScope();
  AutocastScope(const AutocastScope&) = delete;
  AutocastScope& operator=(const AutocastScope&) = delete;

 private:
  bool active_ = false;
  bool was_enabled_ = false;
  at::ScalarType previous_dtype_ = at::kBFloat16;
};

/// x as float32 if it is bfloat16, else x itself (float32 and float64 pass
/// untouched, without an autograd node). Under bf16 autocast the layers before
/// them return bfloat16, and LibTorch 1.13 has no bfloat16 CPU kernel for
/// mish, while group_norm and layer_norm refuse a bfloat16 input with float32
/// weights; the networks pass the inputs of those layers and of softmax, and
/// their own outputs, through this, so they train under autocast and compute
/// bit-for-bit what they did before in float32 and float64.
inline torch::Tensor WidenBfloat16(const torch::Tensor& x) {
  return x.scalar_type() == torch::kBFloat16 ? x.to(torch::kFloat32) : x;
}

/// What this CPU offers for bfloat16 and which kernels bf16 training runs on
/// it, for the log: e.g. "AMX-BF16 and AVX512-BF16: oneDNN runs bfloat16
/// convolutions and matrix products on AMX tiles". From the CPU's flags
/// (Linux /proc/cpuinfo).
std::string DescribeBf16Kernels();

}  // namespace flowplan::models
