#include "models/normalizer.h"

#include "core/error.h"
#include "jit/library.h"

namespace flowplan::models {

MinMaxNormalizer::MinMaxNormalizer(torch::Tensor lo, torch::Tensor hi)
    : lo_(lo.to(torch::kFloat32).contiguous()), hi_(hi.to(torch::kFloat32).contiguous()) {
  if (lo_.dim() != 1 || hi_.sizes() != lo_.sizes()) {
    throw Error("normalizer: expected lo and hi of shape (D,), got " + std::to_string(lo_.dim()) +
                "-d and " + std::to_string(hi_.dim()) + "-d");
  }
  if (!(hi_ > lo_).all().item<bool>()) throw Error("normalizer: expected hi > lo in every dimension");
  module_ = jit::ModuleBuilder("Normalizer").Buffer("lo", lo_).Buffer("hi", hi_).Methods("models/normalizer.py").Build();
}

MinMaxNormalizer MinMaxNormalizer::Fit(const torch::Tensor& states) {
  if (states.dim() < 2 || states.numel() == 0) {
    throw Error("normalizer: expected a non-empty (N, T, D) or (M, D) tensor");
  }
  const torch::Tensor flat = states.reshape({-1, states.size(-1)}).to(torch::kFloat32);
  torch::Tensor lo = std::get<0>(flat.min(0));
  torch::Tensor hi = std::get<0>(flat.max(0));
  const torch::Tensor flat_dims = (hi - lo) < 1e-6;
  lo = torch::where(flat_dims, lo - 0.5, lo);
  hi = torch::where(flat_dims, hi + 0.5, hi);
  return MinMaxNormalizer(lo, hi);
}

void MinMaxNormalizer::CheckInput(const torch::Tensor& x) const {
  FLOWPLAN_DEMAND(fitted());
  if (x.dim() < 1 || x.size(-1) != dim()) {
    throw Error("normalizer: expected (..., " + std::to_string(dim()) + "), got last dimension " +
                (x.dim() ? std::to_string(x.size(-1)) : std::string("none")));
  }
}

torch::Tensor MinMaxNormalizer::Normalize(const torch::Tensor& x) const {
  CheckInput(x);
  return jit::Call(module_, "normalize", {x}).toTensor();
}

torch::Tensor MinMaxNormalizer::DenormalizeUnclamped(const torch::Tensor& x) const {
  CheckInput(x);
  return jit::Call(module_, "denormalize_unclamped", {x}).toTensor();
}

torch::Tensor MinMaxNormalizer::Denormalize(const torch::Tensor& x) const {
  CheckInput(x);
  return jit::Call(module_, "denormalize", {x}).toTensor();
}

}  // namespace flowplan::models
