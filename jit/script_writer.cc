#include "jit/script_writer.h"

#include <cstdio>
#include <cstdlib>

#include "core/error.h"

namespace flowplan::jit {

std::string ScriptWriter::Tensor(const std::string& name, const torch::Tensor& value) {
  std::string attribute = prefix_;
  for (char c : name) attribute += (c == '.') ? '_' : c;
  module_.Buffer(attribute, value);
  return "self." + attribute;
}

std::string ScriptWriter::Let(const std::string& expr) {
  const std::string var = "v" + std::to_string(next_var_++);
  Line(var + " = " + expr);
  return var;
}

void ScriptWriter::Line(const std::string& code) { lines_.emplace_back(depth_, code); }

std::string ScriptWriter::Body(int base_indent) const {
  std::string out;
  for (const auto& [depth, code] : lines_) {
    out += std::string(static_cast<size_t>(4 * (base_indent + depth)), ' ') + code + "\n";
  }
  return out;
}

std::string ScriptFloat(double value) {
  char buffer[64];
  std::snprintf(buffer, sizeof(buffer), "%.17g", value);
  std::string text = buffer;
  if (text == "inf") return "float(\"inf\")";
  if (text == "-inf") return "-float(\"inf\")";
  if (text.find_first_of(".eEn") == std::string::npos) text += ".0";
  return text;
}

std::string ScriptIntList(const std::vector<int64_t>& values) {
  std::string out = "[";
  for (size_t i = 0; i < values.size(); ++i) out += (i ? ", " : "") + std::to_string(values[i]);
  return out + "]";
}

}  // namespace flowplan::jit
