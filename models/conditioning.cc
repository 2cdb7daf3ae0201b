#include "models/conditioning.h"

#include "jit/library.h"

namespace flowplan::models {

torch::Tensor Inpaint(const torch::Tensor& x, const torch::Tensor& start, const torch::Tensor& goal) {
  return jit::CallFunction("inpaint", {x, start, goal}).toTensor();
}

torch::Tensor ConditionVector(Conditioning conditioning, const torch::Tensor& start, const torch::Tensor& goal) {
  const c10::IValue out =
      jit::CallFunction("condition_vector", {start, goal, conditioning == Conditioning::kInpaint});
  return out.isNone() ? torch::Tensor() : out.toTensor();
}

}  // namespace flowplan::models
