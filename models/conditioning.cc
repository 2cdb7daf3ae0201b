#include "models/conditioning.h"

namespace flowplan::models {

torch::Tensor Inpaint(const torch::Tensor& x, const torch::Tensor& start, const torch::Tensor& goal) {
  const int64_t T = x.size(1);
  return torch::cat({start.unsqueeze(1), x.slice(1, 1, T - 1), goal.unsqueeze(1)}, 1);
}

torch::Tensor ConditionVector(Conditioning conditioning, const torch::Tensor& start, const torch::Tensor& goal) {
  if (conditioning != Conditioning::kDirect) return torch::Tensor();
  return torch::cat({start, goal}, -1);
}

}  // namespace flowplan::models
