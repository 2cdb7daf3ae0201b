#pragma once

#include <torch/script.h>
#include <torch/torch.h>

namespace flowplan::models {

/// Per-dimension min–max normalization to [-1, 1] (SPEC section 2). Fitted on
/// the training split only; travels with every checkpoint and export. The maps
/// are the TorchScript class Normalizer (models/normalizer.py), which planners
/// hold as a submodule.
class MinMaxNormalizer {
 public:
  MinMaxNormalizer() = default;
  /// `lo`, `hi`: (D,) per-dimension minimum and maximum in raw units.
  MinMaxNormalizer(torch::Tensor lo, torch::Tensor hi);

  /// Statistics of `states`, (N, T, D) or (M, D), in raw units. A dimension that
  /// never changes gets a unit range so that it maps to a finite value.
  static MinMaxNormalizer Fit(const torch::Tensor& states);

  /// raw -> [-1, 1]; x: (..., D).
  torch::Tensor Normalize(const torch::Tensor& x) const;
  /// [-1, 1] -> raw, clamping to [-1, 1] first; x: (..., D).
  torch::Tensor Denormalize(const torch::Tensor& x) const;
  /// [-1, 1] -> raw without clamping (for costs that need gradients through it).
  torch::Tensor DenormalizeUnclamped(const torch::Tensor& x) const;

  /// The Normalizer module: buffers lo, hi (D,), methods normalize(x),
  /// denormalize(x) (clamping first), denormalize_unclamped(x), x (..., D).
  const torch::jit::Module& module() const { return module_; }

  const torch::Tensor& lo() const { return lo_; }  // (D,)
  const torch::Tensor& hi() const { return hi_; }  // (D,)
  int64_t dim() const { return lo_.defined() ? lo_.size(0) : 0; }
  bool fitted() const { return lo_.defined(); }

 private:
  void CheckInput(const torch::Tensor& x) const;
  torch::Tensor lo_;  // (D,) float32
  torch::Tensor hi_;  // (D,) float32
  torch::jit::Module module_;
};

}  // namespace flowplan::models
