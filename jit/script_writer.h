#pragma once

// TorchScript source generation for the networks, the one kind of
// computation that is written twice: LibTorch's C++ API cannot script or
// trace an nn::Module, so a network (models/) writes its forward pass as
// TorchScript source, op for op, next to its C++ implementation, with its
// parameters as buffers of a module (jit::ModuleBuilder), and tests hold the
// two to each other. Everything else that runs at planning time is written
// once, as TorchScript files (jit/library.h).

#include <torch/script.h>
#include <torch/torch.h>

#include <string>
#include <utility>
#include <vector>

#include "jit/library.h"

namespace flowplan::jit {

/// Writes the body of one method, line by line, registering the tensors it
/// reads as buffers of `module` under `prefix` (so that the parts of a module
/// never share a name).
class ScriptWriter {
 public:
  ScriptWriter(ModuleBuilder& module, std::string prefix) : module_(module), prefix_(std::move(prefix)) {}

  /// Registers `value` (a parameter or constant) under an attribute name made
  /// from `prefix` and `name` (dots become underscores) and returns the
  /// expression that reads it.
  std::string Tensor(const std::string& name, const torch::Tensor& value);
  /// Emits `<fresh> = <expr>` and returns the fresh variable's name.
  std::string Let(const std::string& expr);
  /// Emits one raw line (indented by the current depth).
  void Line(const std::string& code);
  void Indent() { ++depth_; }
  void Dedent() { --depth_; }

  /// Lines emitted so far, each indented with 4 spaces per depth plus `base_indent` levels.
  std::string Body(int base_indent) const;

 private:
  ModuleBuilder& module_;
  std::string prefix_;
  std::vector<std::pair<int, std::string>> lines_;
  int depth_ = 0;
  int next_var_ = 0;
};

/// Formats a float so that TorchScript reads back the same double.
std::string ScriptFloat(double value);

/// Formats an integer list as a TorchScript literal: "[1, 2, 3]".
std::string ScriptIntList(const std::vector<int64_t>& values);

}  // namespace flowplan::jit
