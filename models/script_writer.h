#pragma once

#include <torch/torch.h>

#include <string>
#include <utility>
#include <vector>

namespace flowplan::models {

/// Collects the TorchScript source of a method together with the tensors it
/// reads, so that a network written in C++ can write itself out as TorchScript
/// that computes the same function. LibTorch C++ cannot script an nn::Module,
/// so each network mirrors its forward() as text, op for op; the export tests
/// check the two agree.
class ScriptWriter {
 public:
  /// Registers `value` (a parameter or constant) under a flattened attribute
  /// name derived from `name` and returns the expression that reads it.
  std::string Tensor(const std::string& name, const torch::Tensor& value);
  /// Emits `<fresh> = <expr>` and returns the fresh variable's name.
  std::string Let(const std::string& expr);
  /// Emits one raw line (indented by the current depth).
  void Line(const std::string& code);
  void Indent() { ++depth_; }
  void Dedent() { --depth_; }

  /// Lines emitted so far, each indented with 4 spaces per depth plus `base_indent`.
  std::string Body(int base_indent) const;
  /// (attribute name, tensor) pairs in registration order.
  const std::vector<std::pair<std::string, torch::Tensor>>& tensors() const { return tensors_; }

 private:
  std::vector<std::pair<int, std::string>> lines_;
  std::vector<std::pair<std::string, torch::Tensor>> tensors_;
  int depth_ = 0;
  int next_var_ = 0;
};

/// Formats a float so that TorchScript reads back the same double.
std::string ScriptFloat(double value);

}  // namespace flowplan::models
