#include "guidance/cost.h"

#include "core/error.h"

namespace flowplan::guidance {

torch::Tensor WeightedSumCost::Value(const torch::Tensor& x, const torch::Tensor& obstacles) const {
  torch::Tensor total = torch::zeros({x.size(0)}, x.options());
  for (const Term& term : terms_) {
    if (term.weight != 0.0) total = total + term.weight * term.cost->Value(x, obstacles);
  }
  return total;
}

CostAndGradient WeightedSumCost::ValueAndGradient(const torch::Tensor& x, const torch::Tensor& obstacles) const {
  CostAndGradient total{torch::zeros({x.size(0)}, x.options()), torch::zeros_like(x)};
  for (const Term& term : terms_) {
    if (term.weight == 0.0) continue;
    const CostAndGradient part = term.cost->ValueAndGradient(x, obstacles);
    total.value = total.value + term.weight * part.value;
    total.gradient = total.gradient + term.weight * part.gradient;
  }
  return total;
}

void WeightedSumCost::WriteScript(jit::ScriptModule& module, const std::string& name) const {
  std::string s = "def " + name + "(self, x: Tensor, obstacles: Tensor) -> Tuple[Tensor, Tensor]:\n";
  s += "    value = torch.zeros([x.size(0)], dtype=x.dtype, device=x.device)\n";
  s += "    gradient = torch.zeros_like(x)\n";
  for (const Term& term : terms_) {
    if (term.weight == 0.0) continue;
    const std::string method = name + "_" + term.name;
    term.cost->WriteScript(module, method);
    const std::string w = jit::ScriptFloat(term.weight);
    s += "    part_value, part_gradient = self." + method + "(x, obstacles)\n";
    s += "    value = value + " + w + " * part_value\n";
    s += "    gradient = gradient + " + w + " * part_gradient\n";
  }
  s += "    return value, gradient\n";
  module.Define(s);
}

}  // namespace flowplan::guidance
