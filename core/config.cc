#include "core/config.h"

#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>

namespace flowplan::config {

std::string Bounds::Describe() const {
  if (expected != nullptr) return expected;
  const bool has_lo = std::isfinite(lo);
  const bool has_hi = std::isfinite(hi);
  if (has_lo && has_hi) {
    return std::string("a value in ") + (lo_open ? "(" : "[") + internal::FormatDouble(lo) + ", " +
           internal::FormatDouble(hi) + (hi_open ? ")" : "]");
  }
  if (has_lo) return std::string("a value ") + (lo_open ? "> " : ">= ") + internal::FormatDouble(lo);
  if (has_hi) return std::string("a value ") + (hi_open ? "< " : "<= ") + internal::FormatDouble(hi);
  return "a value";
}

std::string Location::Prefix() const {
  std::string out = source;
  // Overrides are one-line snippets: their line numbers would only mislead.
  if (line > 0 && source != kCommandLine) out += ":" + std::to_string(line);
  if (!key.empty()) out += ": " + key;
  return out;
}

namespace internal {

std::string FormatDouble(double value) {
  if (std::isinf(value)) return value > 0 ? ".inf" : "-.inf";
  if (std::isnan(value)) return ".nan";
  char buffer[512];
  std::string shortest;
  for (int precision = 1; precision <= 17; ++precision) {
    std::snprintf(buffer, sizeof(buffer), "%.*g", precision, value);
    if (std::strtod(buffer, nullptr) == value) break;
  }
  shortest = buffer;
  // Plain decimals read better than exponents (10.0, not 1e+01) when they are no longer.
  for (int decimals = 1; decimals <= 17; ++decimals) {
    std::snprintf(buffer, sizeof(buffer), "%.*f", decimals, value);
    if (std::strtod(buffer, nullptr) == value) {
      if (std::strlen(buffer) <= shortest.size() + 2) shortest = buffer;
      break;
    }
  }
  // Keep a float looking like a float so that it reads back as a number field.
  if (shortest.find_first_of(".eEn") == std::string::npos) shortest += ".0";
  return shortest;
}

std::string Describe(const YAML::Node& node) {
  if (!node.IsDefined() || node.IsNull()) return "nothing (null)";
  if (node.IsScalar()) return "\"" + node.Scalar() + "\"";
  YAML::Emitter out;
  out << YAML::Flow << node;
  return out.c_str();
}

int LineOf(const YAML::Node& node) {
  if (!node.IsDefined()) return -1;
  const YAML::Mark mark = node.Mark();
  return mark.is_null() ? -1 : mark.line + 1;
}

bool ParseDecimal(const std::string& text, long long& value) {
  const size_t first_digit = !text.empty() && (text[0] == '+' || text[0] == '-') ? 1 : 0;
  if (first_digit == text.size() || text.find_first_not_of("0123456789", first_digit) != std::string::npos) {
    return false;
  }
  if (text[first_digit] == '0' && text.size() > first_digit + 1) return false;  // a leading zero
  errno = 0;
  value = std::strtoll(text.c_str(), nullptr, 10);
  return errno != ERANGE;
}

void ThrowExpected(const Location& where, const std::string& expected, const YAML::Node& got) {
  throw Error(where.Prefix() + ": expected " + expected + ", got " + Describe(got));
}

}  // namespace internal

YamlReader::YamlReader(const YAML::Node& node, std::string source, std::string prefix)
    : node_(node), source_(std::move(source)), prefix_(std::move(prefix)) {}

Location YamlReader::Where(const std::string& name, const YAML::Node& child) const {
  return Location{source_, prefix_.empty() ? name : prefix_ + "." + name, internal::LineOf(child)};
}

void YamlReader::Finish() const {
  if (!node_.IsMap()) return;
  std::set<std::string> keys;
  for (const auto& entry : node_) {
    const std::string key = entry.first.Scalar();
    if (!keys.insert(key).second) {  // yaml-cpp keeps the first and drops the rest without a word
      const Location where{source_, prefix_.empty() ? key : prefix_ + "." + key, internal::LineOf(entry.first)};
      throw Error(where.Prefix() + ": key given twice");
    }
    if (seen_.count(key) != 0) continue;
    std::string known;
    for (const auto& name : seen_) known += (known.empty() ? "" : ", ") + name;
    const Location where{source_, prefix_.empty() ? key : prefix_ + "." + key,
                         internal::LineOf(entry.first)};
    throw Error(where.Prefix() + ": unknown key (known keys here: " + known + ")");
  }
}

YAML::Node ParseYamlText(const std::string& text, const std::string& source) {
  try {
    return YAML::Load(text);
  } catch (const YAML::Exception& e) {
    throw Error(source + ":" + std::to_string(e.mark.line + 1) + ": not valid YAML: " + e.msg);
  }
}

YAML::Node ParseYamlFile(const std::string& path) {
  if (std::filesystem::is_directory(path)) throw Error(path + ": is a folder, not a config file");
  std::ifstream in(path);
  if (!in) throw Error(path + ": cannot open config file");
  std::stringstream text;
  text << in.rdbuf();
  return ParseYamlText(text.str(), path);
}

YAML::Node ParseOverride(const std::string& assignment) {
  const auto equals = assignment.find('=');
  if (equals == std::string::npos || equals == 0) {
    throw Error("command line: \"" + assignment + "\": expected an override of the form key.sub=value");
  }
  const std::string key = assignment.substr(0, equals);
  const std::string value = assignment.substr(equals + 1);
  YAML::Node leaf = ParseYamlText(value, "command line: " + key);
  // Build {a: {b: {c: leaf}}} from the innermost key outwards.
  std::vector<std::string> parts;
  std::stringstream stream(key);
  for (std::string part; std::getline(stream, part, '.');) {
    if (part.empty()) throw Error("command line: \"" + assignment + "\": empty key component");
    parts.push_back(part);
  }
  YAML::Node node = leaf;
  for (auto it = parts.rbegin(); it != parts.rend(); ++it) {
    YAML::Node parent(YAML::NodeType::Map);
    parent[*it] = node;
    node = parent;
  }
  return node;
}

std::string FormatKeys(const std::vector<KeyInfo>& keys) {
  // Align the help texts, but let an unusually long "key = value" push only its own line.
  constexpr std::size_t kMaxWidth = 56;
  std::size_t width = 0;
  for (const auto& k : keys) {
    const std::size_t length = k.key.size() + 3 + k.default_value.size();
    if (length <= kMaxWidth) width = std::max(width, length);
  }
  std::string out;
  for (const auto& k : keys) {
    std::string left = k.key + " = " + k.default_value;
    left.resize(std::max(left.size(), width), ' ');
    out += "  " + left + "  " + k.help + "\n";
  }
  return out;
}

}  // namespace flowplan::config
