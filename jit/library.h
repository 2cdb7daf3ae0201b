#pragma once

// flowplan's planning-time computations are written once, as TorchScript
// source files kept in the repository (`*.py` beside the C++ of their folder)
// and embedded in the binary at build time (cmake/embed_scripts.cmake). The
// same files are the Python package `flowplan.script` (python/: each file a
// module, `flowplan.script.geometry.box` for geometry/box.py), importable and
// tested with pytest. Two kinds of file:
//  - function files: free functions (geometry, costs' formulas, the normalizer's
//    maps), compiled once per process into one compilation unit, in the order
//    the folders register them, so that a file may call the functions of any
//    file registered before it by name (and imports them by name for Python);
//  - class files: one class whose methods are those of a module class (a
//    robot, a cost term, a sampler, the planner), compiled onto a
//    torch::jit::Module that ModuleBuilder fills with buffers, attributes and
//    submodules. Methods may call every library function by name and their
//    submodules' methods.
// Before compiling, flowplan blanks the imports and a class file's `class`
// line and takes its body out of the class (CompiledSource), so line numbers
// in compiler messages are the file's.
// The module a planner is built from is what runs in-process and what
// `flowplan export` saves: the exported file carries the printed code of every
// method and function it calls, and loads with nothing but LibTorch or PyTorch.
// Settings are attributes or arguments, never text spliced into source.

#include <torch/csrc/jit/frontend/resolver.h>
#include <torch/script.h>

#include <string>
#include <utility>
#include <vector>

namespace flowplan::jit {

/// One TorchScript file of the repository, embedded at build time.
struct EmbeddedScript {
  const char* path;  // relative to the repository, e.g. "geometry/box.py"
  const char* text;
  bool functions;    // true: free functions; false: the methods of one module class
};

/// Every embedded file: the function files in compilation order, then the class files.
const std::vector<EmbeddedScript>& EmbeddedScripts();

/// The source TorchScript compiles from a `flowplan.script` file's text: the import statements blanked, and a
/// class file's `class Name:` line blanked and its body dedented by one level (4 spaces).
std::string CompiledSource(const std::string& text);

/// CompiledSource of the embedded file `path`. @throws flowplan::InternalError if there is none.
const std::string& ScriptText(const std::string& path);

/// The namespace of every flowplan class and function in TorchScript ("__torch__.flowplan").
extern const char* const kScriptNamespace;

/// Resolves `torch` and every library function by its bare name. The first
/// call compiles the function files (thread-safe; later calls are free).
/// @throws flowplan::InternalError with the compiler's message if a file does not compile.
torch::jit::ResolverPtr LibraryResolver();

/// Builds a module: buffers, attributes and submodules first, then the methods
/// of one or more class files (or of text a user wrote, e.g. a cost).
class ModuleBuilder {
 public:
  /// `class_name` without the namespace, e.g. "Arm". Several modules may share a
  /// class name: each built module has a class type of its own, and saving
  /// tells them apart.
  explicit ModuleBuilder(const std::string& class_name);

  /// Registers a copy of `value` (detached) as a buffer: it follows .to(device).
  ModuleBuilder& Buffer(const std::string& name, const torch::Tensor& value);
  /// Registers an attribute of `value`'s type (float, int, bool, str, List[...], Dict[str, ...]).
  ModuleBuilder& Attribute(const std::string& name, const c10::IValue& value);
  /// Registers an attribute of an explicit type (for empty lists and dicts).
  ModuleBuilder& Attribute(const std::string& name, const c10::TypePtr& type, const c10::IValue& value);
  ModuleBuilder& Submodule(const std::string& name, const torch::jit::Module& module);
  /// Adds the methods of the embedded class file `path`.
  ModuleBuilder& Methods(const std::string& path);
  /// Adds methods from source text a user wrote; `where` names it in compile errors.
  ModuleBuilder& MethodsFromText(const std::string& text, const std::string& where);
  /// Adds methods from source text flowplan generated (a network's forward pass).
  ModuleBuilder& GeneratedMethods(const std::string& text, const std::string& where);

  /// Compiles the methods. @throws flowplan::InternalError if an embedded file does
  /// not compile, flowplan::Error naming `where` if user text does not.
  torch::jit::Module Build();

 private:
  torch::jit::Module module_;
  std::vector<std::pair<std::string, std::string>> sources_;  // (where, text)
  std::vector<bool> user_;                                    // per source: written by a user
  bool built_ = false;
};

/// Runs `module.method(args..., kwargs)` with the graph executor's rewrites
/// off for the call (LibTorch keeps that switch per thread): every call runs the
/// graph as compiled, so results and speed do not depend on which call or
/// thread came first. The profiling executor would instead spend its first
/// calls on every thread profiling, and would wrap autograd regions in
/// differentiable graphs whose inputs break under inference mode.
/// A failed assertion inside the script
/// becomes flowplan::Error carrying the assertion's message (its last line,
/// e.g. "plan: start: expected (B, 14)"), so that scripts can check their
/// arguments with one clear line.
c10::IValue Call(const torch::jit::Module& module, const std::string& method, std::vector<c10::IValue> args,
                 const torch::jit::Kwargs& kwargs = {});

/// Runs the library function `name` (e.g. "scene_distance") on `args`, with
/// the executor and errors as Call.
c10::IValue CallFunction(const std::string& name, std::vector<c10::IValue> args);

/// The message a TorchScript failure carries, without its traceback: the last
/// line, with a leading "AssertionError: " or "RuntimeError: " removed.
std::string ScriptErrorMessage(const std::exception& e);

}  // namespace flowplan::jit
