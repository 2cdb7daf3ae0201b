#include "jit/library.h"

#include <torch/csrc/jit/api/compilation_unit.h>
#include <torch/csrc/jit/frontend/sugared_value.h>
#include <torch/csrc/jit/runtime/graph_executor.h>

#include <map>
#include <regex>
#include <memory>

#include "core/error.h"
#include "core/format.h"

namespace flowplan::jit {

const char* const kScriptNamespace = "__torch__.flowplan";

namespace {

/// `ops.NAMESPACE.op`: an operator registered by a library (TORCH_LIBRARY),
/// as saved files spell it.
struct OpsNamespaces : public torch::jit::SugaredValue {
  std::string kind() const override { return "operator namespaces"; }
  std::shared_ptr<torch::jit::SugaredValue> attr(const torch::jit::SourceRange&, torch::jit::GraphFunction&,
                                                 const std::string& field) override {
    return std::make_shared<torch::jit::BuiltinModule>(field);
  }
};

/// Resolves `torch` to the ATen builtins, `ops` to registered operators,
/// `Exception` (for `raise`) and any other name to a function of `unit`.
class FunctionResolver : public torch::jit::Resolver {
 public:
  explicit FunctionResolver(std::shared_ptr<torch::jit::CompilationUnit> unit) : unit_(std::move(unit)) {}

  std::shared_ptr<torch::jit::SugaredValue> resolveValue(const std::string& name, torch::jit::GraphFunction&,
                                                         const torch::jit::SourceRange&) override {
    if (name == "torch") return std::make_shared<torch::jit::BuiltinModule>("aten");
    if (name == "ops") return std::make_shared<OpsNamespaces>();
    if (name == "Exception") return std::make_shared<torch::jit::ExceptionValue>("Exception");
    if (torch::jit::Function* function = unit_->find_function(c10::QualifiedName(std::string(kScriptNamespace) + "." + name))) {
      return std::make_shared<torch::jit::FunctionValue>(function);
    }
    return nullptr;
  }

  c10::TypePtr resolveType(const std::string&, const torch::jit::SourceRange&) override { return nullptr; }

 private:
  std::shared_ptr<torch::jit::CompilationUnit> unit_;
};

bool StartsWith(const std::string& line, const char* prefix) { return line.rfind(prefix, 0) == 0; }

/// The compiler's complaint in one line: its first non-empty line, and the line of the source it points at
/// ("undefined value undefined_name, line 5").
std::string CompileError(const std::string& message) {
  std::string first;
  size_t begin = 0;
  while (first.empty() && begin < message.size()) {
    size_t end = message.find('\n', begin);
    if (end == std::string::npos) end = message.size();
    first = message.substr(begin, end - begin);
    while (!first.empty() && (first.back() == ':' || first.back() == ' ')) first.pop_back();
    begin = end + 1;
  }
  std::smatch line;
  if (std::regex_search(message, line, std::regex(R"(, line (\d+))"))) first += ", line " + line[1].str();
  return first;
}

struct Library {
  std::shared_ptr<torch::jit::CompilationUnit> unit = std::make_shared<torch::jit::CompilationUnit>();
  torch::jit::ResolverPtr resolver = std::make_shared<FunctionResolver>(unit);

  Library() {
    for (const EmbeddedScript& script : EmbeddedScripts()) {
      if (!script.functions) continue;
      try {
        unit->define(c10::QualifiedName(kScriptNamespace), ScriptText(script.path), resolver, nullptr);
      } catch (const std::exception& e) {
        throw InternalError(std::string(script.path) + ": does not compile: " + e.what());
      }
    }
  }
};

const Library& TheLibrary() {
  static const Library library;  // never destroyed before the modules that call into it
  return library;
}

std::string StripPrefix(std::string line) {
  for (const char* prefix : {"RuntimeError: ", "AssertionError: ", "Exception: ", "builtins.", "RuntimeError: "}) {
    const std::string p = prefix;
    if (line.rfind(p, 0) == 0) line = line.substr(p.size());
  }
  return line;
}

}  // namespace

std::string CompiledSource(const std::string& text) {
  std::string out;
  enum { kNone, kParenthesised, kContinued } import = kNone;  // an import statement going on past its first line
  bool in_class = false;
  int quotes = 0;  // 0 outside a triple-quoted string, else 1 (""") or 2 (''')
  size_t begin = 0;
  while (begin <= text.size()) {
    size_t end = text.find('\n', begin);
    if (end == std::string::npos) end = text.size();
    std::string line = text.substr(begin, end - begin);
    const std::string code = line.substr(0, line.find('#'));  // the line without its comment
    const bool continued = !code.empty() && code.find_last_not_of(" \t") != std::string::npos &&
                           code[code.find_last_not_of(" \t")] == '\\';
    if (quotes == 0 && import != kNone) {
      if (import == kParenthesised && code.find(')') != std::string::npos) import = kNone;
      if (import == kContinued && !continued) import = kNone;
      line.clear();
    } else if (quotes == 0 && (StartsWith(line, "import ") || StartsWith(line, "from "))) {
      import = continued                                                                           ? kContinued
               : code.find('(') != std::string::npos && code.find(')') == std::string::npos ? kParenthesised
                                                                                             : kNone;
      line.clear();
    } else if (quotes == 0 && StartsWith(line, "class ")) {
      in_class = true;
      line.clear();
    } else if (quotes == 0 && in_class && !line.empty() && line[0] != ' ' && line[0] != '#') {
      in_class = false;  // back at module level
    }
    if (in_class && StartsWith(line, "    ")) line.erase(0, 4);
    // Triple-quoted strings that open or close on this line.
    for (size_t at = 0; at + 3 <= line.size(); ++at) {
      const bool double_quotes = line.compare(at, 3, "\"\"\"") == 0, single = line.compare(at, 3, "'''") == 0;
      if (quotes == 0 && (double_quotes || single) && line.substr(0, at).find('#') == std::string::npos) {
        quotes = double_quotes ? 1 : 2;
        at += 2;
      } else if ((quotes == 1 && double_quotes) || (quotes == 2 && single)) {
        quotes = 0;
        at += 2;
      }
    }
    out += line;
    if (end < text.size()) out += '\n';
    begin = end + 1;
  }
  return out;
}

const std::string& ScriptText(const std::string& path) {
  static const std::map<std::string, std::string> texts = [] {
    std::map<std::string, std::string> out;
    for (const EmbeddedScript& script : EmbeddedScripts()) out.emplace(script.path, CompiledSource(script.text));
    return out;
  }();
  const auto found = texts.find(path);
  if (found == texts.end()) throw InternalError("no embedded TorchScript file " + path);
  return found->second;
}

torch::jit::ResolverPtr LibraryResolver() { return TheLibrary().resolver; }

ModuleBuilder::ModuleBuilder(const std::string& class_name)
    : module_(c10::QualifiedName(std::string(kScriptNamespace) + "." + class_name)) {}

ModuleBuilder& ModuleBuilder::Buffer(const std::string& name, const torch::Tensor& value) {
  module_.register_buffer(name, value.detach().clone());
  return *this;
}

ModuleBuilder& ModuleBuilder::Attribute(const std::string& name, const c10::IValue& value) {
  module_.register_attribute(name, value.type(), value);
  return *this;
}

ModuleBuilder& ModuleBuilder::Attribute(const std::string& name, const c10::TypePtr& type,
                                        const c10::IValue& value) {
  module_.register_attribute(name, type, value);
  return *this;
}

ModuleBuilder& ModuleBuilder::Submodule(const std::string& name, const torch::jit::Module& module) {
  module_.register_module(name, module);
  return *this;
}

ModuleBuilder& ModuleBuilder::Methods(const std::string& path) {
  sources_.emplace_back(path, ScriptText(path));
  user_.push_back(false);
  return *this;
}

ModuleBuilder& ModuleBuilder::MethodsFromText(const std::string& text, const std::string& where) {
  sources_.emplace_back(where, CompiledSource(text));
  user_.push_back(true);
  return *this;
}

ModuleBuilder& ModuleBuilder::GeneratedMethods(const std::string& text, const std::string& where) {
  sources_.emplace_back(where, text);
  user_.push_back(false);
  return *this;
}

torch::jit::Module ModuleBuilder::Build() {
  FLOWPLAN_DEMAND(!built_);
  built_ = true;
  // One compilation of all sources, so that their methods may call each other in any order.
  std::string all;
  for (const auto& [where, text] : sources_) all += text + "\n";
  try {
    module_.define(all, LibraryResolver());
  } catch (const std::exception& e) {
    // A user's text is the likely culprit; otherwise the fault is flowplan's.
    std::string users;
    for (size_t i = 0; i < sources_.size(); ++i) {
      if (user_[i]) users += (users.empty() ? "" : ", ") + sources_[i].first;
    }
    const std::string message = e.what();
    if (!users.empty()) throw Error(users + ": does not compile as TorchScript: " + CompileError(message));
    std::string files;
    for (const auto& source : sources_) files += (files.empty() ? "" : ", ") + source.first;
    throw InternalError(module_.type()->name()->qualifiedName() + " (" + files + "): does not compile: " + message);
  }
  return module_;
}

std::string ScriptErrorMessage(const std::exception& e) {
  std::string text = e.what();
  // c10::Error carries a backtrace after the message; JITException the script's traceback before it.
  if (const auto* c10_error = dynamic_cast<const c10::Error*>(&e)) text = c10_error->what_without_backtrace();
  while (!text.empty() && (text.back() == '\n' || text.back() == ' ')) text.pop_back();
  return StripPrefix(LastLine(text));
}

c10::IValue Call(const torch::jit::Module& module, const std::string& method, std::vector<c10::IValue> args,
                 const torch::jit::Kwargs& kwargs) {
  const torch::jit::GraphOptimizerEnabledGuard as_compiled(false);
  try {
    return module.get_method(method)(std::move(args), kwargs);
  } catch (const Error&) {
    throw;
  } catch (const std::exception& e) {
    throw Error(ScriptErrorMessage(e));
  }
}

c10::IValue CallFunction(const std::string& name, std::vector<c10::IValue> args) {
  const Library& library = TheLibrary();
  torch::jit::Function* function =
      library.unit->find_function(c10::QualifiedName(std::string(kScriptNamespace) + "." + name));
  if (function == nullptr) throw InternalError("no TorchScript library function " + name);
  const torch::jit::GraphOptimizerEnabledGuard as_compiled(false);
  try {
    return (*function)(std::move(args));
  } catch (const std::exception& e) {
    throw Error(ScriptErrorMessage(e));
  }
}

}  // namespace flowplan::jit
