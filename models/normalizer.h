#pragma once

#include <torch/torch.h>

#include "jit/script_writer.h"

namespace flowplan::models {

/// Per-dimension min–max normalization to [-1, 1] (SPEC section 2). Fitted on
/// the training split only; travels with every checkpoint and export.
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

  /// Adds the buffers lo, hi (D,) and the methods normalize(x), denormalize(x)
  /// (clamping first) and denormalize_unclamped(x), x (..., D), to an exported module.
  void WriteScript(jit::ScriptModule& module) const;

  const torch::Tensor& lo() const { return lo_; }  // (D,)
  const torch::Tensor& hi() const { return hi_; }  // (D,)
  int64_t dim() const { return lo_.defined() ? lo_.size(0) : 0; }
  bool fitted() const { return lo_.defined(); }

 private:
  void CheckInput(const torch::Tensor& x) const;
  torch::Tensor lo_;  // (D,) float32
  torch::Tensor hi_;  // (D,) float32
};

}  // namespace flowplan::models
