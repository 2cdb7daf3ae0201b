#include "models/script_writer.h"

#include <cstdio>
#include <cstdlib>

#include "core/error.h"

namespace flowplan::models {

std::string ScriptWriter::Tensor(const std::string& name, const torch::Tensor& value) {
  std::string attribute = "p_";
  for (char c : name) attribute += (c == '.') ? '_' : c;
  for (const auto& [existing, tensor] : tensors_) FLOWPLAN_DEMAND(existing != attribute);
  tensors_.emplace_back(attribute, value.detach().clone());
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
  if (text.find_first_of(".eEn") == std::string::npos) text += ".0";
  return text;
}

}  // namespace flowplan::models
