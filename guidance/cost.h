#pragma once

// Guidance costs on whole trajectories (SPEC section 2): a Cost maps raw
// (de-normalized) trajectories and a scene's obstacles to one number per
// trajectory, and gives its gradient by formulas written out in C++ and in
// TorchScript (so that guidance works in an exported planner under
// torch.inference_mode(), where autograd cannot run). Value() is plain tensor
// code, differentiable by autograd; tests hold the written-out gradient to
// autograd and to finite differences.
//
// Shapes: B trajectories, T states, D state dims, K obstacles, W workspace dims.

#include <torch/torch.h>

#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "jit/script_writer.h"

namespace flowplan::guidance {

struct CostAndGradient {
  torch::Tensor value;     // (B,) cost per trajectory
  torch::Tensor gradient;  // (B, T, D) ∂(Σ_b value_b)/∂x
};

class Cost {
 public:
  virtual ~Cost() = default;

  /// x: (B, T, D) raw states; obstacles: (K, W+1) rows [centre, radius] (K may be 0) -> (B,).
  virtual torch::Tensor Value(const torch::Tensor& x, const torch::Tensor& obstacles) const = 0;

  /// Value() and its gradient with respect to x, without autograd.
  virtual CostAndGradient ValueAndGradient(const torch::Tensor& x, const torch::Tensor& obstacles) const = 0;

  /// Adds `def <name>(self, x: Tensor, obstacles: Tensor) -> Tuple[Tensor, Tensor]`
  /// computing ValueAndGradient, with any buffers and helper methods it needs
  /// (named after `name`).
  virtual void WriteScript(jit::ScriptModule& module, const std::string& name) const = 0;
};

/// Σ_i weight_i · cost_i.
class WeightedSumCost : public Cost {
 public:
  struct Term {
    std::string name;  // e.g. "collision"; names the term's script method
    double weight = 1.0;
    std::shared_ptr<const Cost> cost;
  };
  explicit WeightedSumCost(std::vector<Term> terms) : terms_(std::move(terms)) {}

  torch::Tensor Value(const torch::Tensor& x, const torch::Tensor& obstacles) const override;
  CostAndGradient ValueAndGradient(const torch::Tensor& x, const torch::Tensor& obstacles) const override;
  void WriteScript(jit::ScriptModule& module, const std::string& name) const override;

  const std::vector<Term>& terms() const { return terms_; }

 private:
  std::vector<Term> terms_;
};

}  // namespace flowplan::guidance
