#pragma once

// TorchScript source generation. LibTorch's C++ API cannot script or trace an
// nn::Module, so every piece that must run inside an exported planner (a
// network, the normalizer, a robot's kinematics, a cost, a sampler) writes its
// computation as TorchScript source next to its C++ implementation, and tests
// hold the two to each other. A ScriptModule collects the pieces' buffers,
// attributes and methods and compiles them into one torch::jit::Module.

#include <torch/script.h>
#include <torch/torch.h>

#include <string>
#include <utility>
#include <vector>

namespace flowplan::jit {

/// The buffers, attributes and method source of a module under construction.
class ScriptModule {
 public:
  /// Registers `value` (detached, cloned) as the buffer `name` and returns the
  /// expression that reads it ("self.<name>").
  /// @throws flowplan::InternalError if the name is taken.
  std::string Buffer(const std::string& name, const torch::Tensor& value);

  /// Registers a constant attribute, e.g. Attribute("horizon", c10::IntType::get(), 64).
  void Attribute(const std::string& name, const c10::TypePtr& type, const c10::IValue& value);

  /// Appends the source of one or more complete `def` blocks (methods take `self`).
  void Define(const std::string& source);

  /// Compiles everything into a module. Methods may call each other in any order.
  /// @throws flowplan::InternalError with the compiler's message if the source does not compile.
  torch::jit::Module Build(const std::string& class_name) const;

  /// The method source so far (for error messages and debugging).
  const std::string& source() const { return source_; }

 private:
  std::vector<std::pair<std::string, torch::Tensor>> buffers_;
  std::vector<std::tuple<std::string, c10::TypePtr, c10::IValue>> attributes_;
  std::string source_;
};

/// Writes the body of one method, line by line, registering the tensors it
/// reads as buffers of `module` under `prefix` (so that the parts of a module
/// never share a name).
class ScriptWriter {
 public:
  ScriptWriter(ScriptModule& module, std::string prefix) : module_(module), prefix_(std::move(prefix)) {}

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
  ScriptModule& module_;
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
