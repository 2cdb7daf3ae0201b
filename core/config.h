#pragma once

// Config structs: plain structs with in-class defaults and ONE field list, a
// templated `Visit` method, used for YAML loading, YAML saving and key listings:
//
//   struct TrainerConfig {
//     int batch_size = 256;
//     double lr = 2e-4;
//     template <class V> void Visit(V& v) {
//       v.Field("batch_size", batch_size, "trajectories per optimizer step", config::Positive());
//       v.Field("lr", lr, "peak learning rate", config::Positive());
//     }
//   };
//
// Supported field types: bool, int, int64_t, double, std::string, enums that have an
// ADL-visible `EnumEntries(E)` (see below), nested config structs, and std::vector /
// std::array of any of these. Unknown keys, wrong types and values outside the
// field's bounds throw flowplan::Error naming the source, line, key and value.

#include <yaml-cpp/yaml.h>

#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <set>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

#include "core/error.h"
#include "core/format.h"

namespace flowplan::config {

/// The source name of key=value overrides in error messages.
inline constexpr const char* kCommandLine = "command line";

/// Bounds on a numeric field (applied to every element of a list field).
struct Bounds {
  double lo = -std::numeric_limits<double>::infinity();
  double hi = std::numeric_limits<double>::infinity();
  bool lo_open = false;
  bool hi_open = false;
  const char* expected = nullptr;  // e.g. "a positive number"; null: derived from lo/hi
  bool allow_infinite = false;     // .inf / -.inf accepted (when inside [lo, hi]), e.g. "no cap"

  bool Contains(double x) const {
    return (lo_open ? x > lo : x >= lo) && (hi_open ? x < hi : x <= hi);
  }
  std::string Describe() const;
};

inline Bounds Unbounded() { return {}; }
inline Bounds Positive() {
  return {0.0, std::numeric_limits<double>::infinity(), true, false, "a positive value"};
}
inline Bounds NonNegative() {
  return {0.0, std::numeric_limits<double>::infinity(), false, false, "a non-negative value"};
}
inline Bounds AtLeast(double lo) { return {lo, std::numeric_limits<double>::infinity()}; }
inline Bounds InRange(double lo, double hi) { return {lo, hi}; }
inline Bounds Probability() { return {0.0, 1.0, false, false, "a probability in [0, 1]"}; }
/// A positive value or .inf (meaning "no limit").
inline Bounds PositiveOrInfinite() {
  return {0.0, std::numeric_limits<double>::infinity(), true, false, "a positive value or .inf", true};
}

/// Names of an enum's values, returned by an ADL-visible function declared next to
/// the enum:  `inline const config::EnumNames<Mode>& EnumEntries(Mode) {...}`.
template <class E>
using EnumNames = std::vector<std::pair<E, const char*>>;

/// Where a YAML value came from, for error messages.
struct Location {
  std::string source;  // "configs/x.yaml" or "command line"
  std::string key;     // dotted key, e.g. "train.batch_size"
  int line = -1;       // 1-based line in the source, -1 if unknown

  std::string Prefix() const;  // "configs/x.yaml:12: train.batch_size"
};

/// One line of a key listing, for `flowplan config keys` and --help texts.
struct KeyInfo {
  std::string key;
  std::string default_value;
  std::string help;
};

/// The config name of an enum value (its EnumEntries() name), e.g. "inpaint".
template <class E>
const char* EnumName(E value) {
  for (const auto& [v, name] : EnumEntries(E{})) {
    if (v == value) return name;
  }
  return "?";
}

namespace internal {

template <class T, class = void>
struct IsConfigStruct : std::false_type {};
template <class T>
struct IsConfigStruct<T, std::void_t<decltype(std::declval<T&>().template Visit<int>(
                             std::declval<int&>()))>> : std::true_type {};

template <class T, class = void>
struct HasEnumEntries : std::false_type {};
template <class T>
struct HasEnumEntries<T, std::void_t<decltype(EnumEntries(std::declval<T>()))>>
    : std::true_type {};

template <class T>
struct IsVector : std::false_type {};
template <class T>
struct IsVector<std::vector<T>> : std::true_type {};

template <class T>
struct IsArray : std::false_type {};
template <class T, std::size_t N>
struct IsArray<std::array<T, N>> : std::true_type {};

/// Shortest decimal text that reads back as exactly `value`.
std::string FormatDouble(double value);
/// One-line text of a YAML node for "got ..." in error messages.
std::string Describe(const YAML::Node& node);
[[noreturn]] void ThrowExpected(const Location& where, const std::string& expected,
                                const YAML::Node& got);
int LineOf(const YAML::Node& node);

/// Reads `text` as a decimal integer: an optional sign, then 0 or digits
/// without a leading zero (yaml-cpp alone would read 010 as octal 8 and 0x10
/// as 16). False for anything else and for values outside long long.
bool ParseDecimal(const std::string& text, long long& value);

template <class E>
std::string EnumChoices() {
  std::string out;
  for (const auto& [value, name] : EnumEntries(E{})) {
    if (!out.empty()) out += ", ";
    out += name;
  }
  return out;
}

template <class T>
void DecodeScalar(const YAML::Node& node, T& out, const Location& where, const Bounds& bounds) {
  if constexpr (std::is_same_v<T, bool>) {
    if (!node.IsScalar() || !YAML::convert<bool>::decode(node, out))
      ThrowExpected(where, "true or false", node);
  } else if constexpr (std::is_integral_v<T>) {
    long long value = 0;
    if (!node.IsScalar() || !ParseDecimal(node.Scalar(), value) ||
        value < static_cast<long long>(std::numeric_limits<T>::min()) ||
        value > static_cast<long long>(std::numeric_limits<T>::max()))
      ThrowExpected(where, "a decimal integer", node);
    if (!bounds.Contains(static_cast<double>(value))) ThrowExpected(where, bounds.Describe(), node);
    out = static_cast<T>(value);
  } else if constexpr (std::is_floating_point_v<T>) {
    double value = 0.0;
    if (!node.IsScalar() || !YAML::convert<double>::decode(node, value))
      ThrowExpected(where, "a number", node);
    if (!(value == value)) ThrowExpected(where, "a number", node);
    if (std::isinf(value) && !bounds.allow_infinite) ThrowExpected(where, "a finite number", node);
    if (!bounds.Contains(value)) ThrowExpected(where, bounds.Describe(), node);
    out = static_cast<T>(value);
  } else if constexpr (std::is_same_v<T, std::string>) {
    if (!node.IsScalar()) ThrowExpected(where, "a string", node);
    out = node.Scalar();
  } else if constexpr (std::is_enum_v<T>) {
    static_assert(HasEnumEntries<T>::value, "enum fields need an ADL-visible EnumEntries(E)");
    if (node.IsScalar()) {
      for (const auto& [value, name] : EnumEntries(T{})) {
        if (node.Scalar() == name) {
          out = value;
          return;
        }
      }
    }
    ThrowExpected(where, "one of " + EnumChoices<T>(), node);
  } else {
    static_assert(sizeof(T) == 0, "unsupported config field type");
  }
}

template <class T>
YAML::Node EncodeScalar(const T& value) {
  if constexpr (std::is_same_v<T, bool>) {
    return YAML::Node(value ? "true" : "false");
  } else if constexpr (std::is_integral_v<T>) {
    return YAML::Node(std::to_string(value));
  } else if constexpr (std::is_floating_point_v<T>) {
    return YAML::Node(FormatDouble(static_cast<double>(value)));
  } else if constexpr (std::is_same_v<T, std::string>) {
    return YAML::Node(value);
  } else if constexpr (std::is_enum_v<T>) {
    return YAML::Node(std::string(EnumName(value)));
  } else {
    static_assert(sizeof(T) == 0, "unsupported config field type");
  }
}

template <class T>
void Decode(const YAML::Node& node, T& out, const Location& where, const Bounds& bounds);
template <class T>
YAML::Node Encode(const T& value);

}  // namespace internal

/// Reads fields from a YAML mapping; every key in the mapping must be a field.
class YamlReader {
 public:
  /// `prefix` is the dotted path of `node` ("" at the top level).
  YamlReader(const YAML::Node& node, std::string source, std::string prefix);

  template <class T>
  void Field(const char* name, T& value, const char* /*help*/, Bounds bounds = {}) {
    seen_.insert(name);
    if (!node_.IsMap()) return;
    const YAML::Node child = node_[name];
    if (!child.IsDefined()) return;
    internal::Decode(child, value, Where(name, child), bounds);
  }

  /// Throws if the mapping holds a key no Field() asked for.
  void Finish() const;

 private:
  Location Where(const std::string& name, const YAML::Node& child) const;

  YAML::Node node_;
  std::string source_;
  std::string prefix_;
  std::set<std::string> seen_;
};

/// Writes every field into a YAML mapping.
class YamlWriter {
 public:
  template <class T>
  void Field(const char* name, const T& value, const char* /*help*/, Bounds /*bounds*/ = {}) {
    node_[name] = internal::Encode(value);
  }
  YAML::Node node() const { return node_; }

 private:
  YAML::Node node_{YAML::NodeType::Map};
};

/// Lists every leaf key with its current value and help text.
class KeyLister {
 public:
  explicit KeyLister(std::string prefix = "") : prefix_(std::move(prefix)) {}

  template <class T>
  void Field(const char* name, const T& value, const char* help, Bounds /*bounds*/ = {}) {
    const std::string key = prefix_.empty() ? name : prefix_ + "." + name;
    if constexpr (internal::IsConfigStruct<T>::value) {
      KeyLister child(key);
      const_cast<T&>(value).Visit(child);
      for (auto& k : child.keys_) keys_.push_back(std::move(k));
    } else {
      YAML::Emitter out;
      out << YAML::Flow << internal::Encode(value);
      std::string text = help;
      if constexpr (std::is_enum_v<T>) text += " (" + internal::EnumChoices<T>() + ")";
      keys_.push_back({key, out.c_str(), text});
    }
  }
  const std::vector<KeyInfo>& keys() const { return keys_; }

 private:
  std::string prefix_;
  std::vector<KeyInfo> keys_;
};

/// Collects every numeric leaf (int, int64_t, double; not bool) with its value.
class NumberLister {
 public:
  explicit NumberLister(std::string prefix = "") : prefix_(std::move(prefix)) {}

  template <class T>
  void Field(const char* name, const T& value, const char* /*help*/, Bounds /*bounds*/ = {}) {
    const std::string key = prefix_.empty() ? name : prefix_ + "." + name;
    if constexpr (internal::IsConfigStruct<T>::value) {
      NumberLister child(key);
      const_cast<T&>(value).Visit(child);
      for (auto& entry : child.numbers_) numbers_.push_back(std::move(entry));
    } else if constexpr (std::is_arithmetic_v<T> && !std::is_same_v<T, bool>) {
      numbers_.emplace_back(key, static_cast<double>(value));
    }
  }
  const std::vector<std::pair<std::string, double>>& numbers() const { return numbers_; }

 private:
  std::string prefix_;
  std::vector<std::pair<std::string, double>> numbers_;
};

namespace internal {

template <class T>
void Decode(const YAML::Node& node, T& out, const Location& where, const Bounds& bounds) {
  if constexpr (IsConfigStruct<T>::value) {
    if (!node.IsMap()) ThrowExpected(where, "a mapping of keys", node);
    YamlReader reader(node, where.source, where.key);
    out.Visit(reader);
    reader.Finish();
  } else if constexpr (IsVector<T>::value) {
    if (!node.IsSequence()) ThrowExpected(where, "a list", node);
    T result(node.size());
    for (std::size_t i = 0; i < node.size(); ++i) {
      Location element = where;
      element.key += "[" + std::to_string(i) + "]";
      element.line = LineOf(node[i]) > 0 ? LineOf(node[i]) : where.line;
      Decode(node[i], result[i], element, bounds);
    }
    out = std::move(result);
  } else if constexpr (IsArray<T>::value) {
    if (!node.IsSequence() || node.size() != out.size())
      ThrowExpected(where, "a list of " + std::to_string(out.size()) + " values", node);
    T result = out;
    for (std::size_t i = 0; i < node.size(); ++i) {
      Location element = where;
      element.key += "[" + std::to_string(i) + "]";
      Decode(node[i], result[i], element, bounds);
    }
    out = result;
  } else {
    DecodeScalar(node, out, where, bounds);
  }
}

template <class T>
YAML::Node Encode(const T& value) {
  if constexpr (IsConfigStruct<T>::value) {
    YamlWriter writer;
    const_cast<T&>(value).Visit(writer);
    return writer.node();
  } else if constexpr (IsVector<T>::value || IsArray<T>::value) {
    YAML::Node list(YAML::NodeType::Sequence);
    for (const auto& element : value) list.push_back(Encode(element));
    list.SetStyle(YAML::EmitterStyle::Flow);
    return list;
  } else {
    return EncodeScalar(value);
  }
}

/// Writes `value` to `out` straight from its fields (no YAML::Node tree, whose assignments cost time quadratic
/// in its size): mappings and lists of mappings in block style, lists of scalars in flow style. With
/// `skip_unset`, fields holding NaN (an unset number) are left out.
template <class T>
void Emit(YAML::Emitter& out, const T& value, bool skip_unset);

/// The visitor of Emit: one key and value per field.
class EmitWriter {
 public:
  EmitWriter(YAML::Emitter& out, bool skip_unset) : out_(out), skip_unset_(skip_unset) {}
  template <class T>
  void Field(const char* name, const T& value, const char* /*help*/, Bounds /*bounds*/ = {}) {
    if constexpr (std::is_floating_point_v<T>) {
      if (skip_unset_ && value != value) return;
    }
    out_ << YAML::Key << name << YAML::Value;
    Emit(out_, value, skip_unset_);
  }

 private:
  YAML::Emitter& out_;
  bool skip_unset_;
};

template <class T>
void Emit(YAML::Emitter& out, const T& value, bool skip_unset) {
  if constexpr (IsConfigStruct<T>::value) {
    out << YAML::BeginMap;
    EmitWriter writer(out, skip_unset);
    const_cast<T&>(value).Visit(writer);
    out << YAML::EndMap;
  } else if constexpr (IsVector<T>::value || IsArray<T>::value) {
    using Element = typename T::value_type;
    const bool nested = IsConfigStruct<Element>::value || IsVector<Element>::value || IsArray<Element>::value;
    out << (nested && !value.empty() ? YAML::Block : YAML::Flow) << YAML::BeginSeq;
    for (const auto& element : value) Emit(out, element, skip_unset);
    out << YAML::EndSeq;
  } else {
    out << EncodeScalar(value).Scalar();
  }
}

/// Appends `value` as JSON to `out`: a struct as an object of its fields, a list as an array, a number in the
/// shortest form that reads back to it (null when not finite: YAML's .inf and .nan have no JSON form), an enum as
/// its name.
template <class T>
void EmitJson(std::string& out, const T& value);

/// The visitor of EmitJson: one key and value per field.
class JsonWriter {
 public:
  explicit JsonWriter(std::string& out) : out_(out) {}
  template <class T>
  void Field(const char* name, const T& value, const char* /*help*/, Bounds /*bounds*/ = {}) {
    out_ += (first_ ? "" : ", ") + JsonString(name) + ": ";
    first_ = false;
    EmitJson(out_, value);
  }

 private:
  std::string& out_;
  bool first_ = true;
};

template <class T>
void EmitJson(std::string& out, const T& value) {
  if constexpr (IsConfigStruct<T>::value) {
    out += "{";
    JsonWriter writer(out);
    const_cast<T&>(value).Visit(writer);
    out += "}";
  } else if constexpr (IsVector<T>::value || IsArray<T>::value) {
    out += "[";
    bool first = true;
    for (const auto& element : value) {
      if (!first) out += ", ";
      first = false;
      EmitJson(out, element);
    }
    out += "]";
  } else if constexpr (std::is_same_v<T, bool>) {
    out += value ? "true" : "false";
  } else if constexpr (std::is_integral_v<T>) {
    out += std::to_string(value);
  } else if constexpr (std::is_floating_point_v<T>) {
    out += std::isfinite(value) ? FormatDouble(static_cast<double>(value)) : "null";
  } else if constexpr (std::is_same_v<T, std::string>) {
    out += JsonString(value);
  } else if constexpr (std::is_enum_v<T>) {
    out += JsonString(std::string(EnumName(value)));
  } else {
    static_assert(sizeof(T) == 0, "unsupported config field type");
  }
}

}  // namespace internal

/// A config struct as one JSON object (for reports: settings as data, not as YAML text).
template <class T>
std::string ToJson(const T& config) {
  std::string out;
  internal::EmitJson(out, config);
  return out;
}

/// Applies the keys present in `node` onto `config` (keys absent keep their values).
/// @throws flowplan::Error on unknown keys, wrong types and out-of-bounds values.
template <class T>
void Apply(const YAML::Node& node, T& config, const std::string& source) {
  if (!node.IsDefined() || node.IsNull()) return;  // an empty file keeps every default
  internal::Decode(node, config, Location{source, "", internal::LineOf(node)}, Bounds{});
}

/// Parses a YAML file and applies it onto `config`.
/// @throws flowplan::Error if the file is missing or not valid YAML.
YAML::Node ParseYamlFile(const std::string& path);
/// Parses YAML text; `source` names it in errors.
YAML::Node ParseYamlText(const std::string& text, const std::string& source);

/// Turns "a.b.c=value" into the mapping {a: {b: {c: value}}}.
/// @throws flowplan::Error if the text is not of the form key=value.
YAML::Node ParseOverride(const std::string& assignment);

/// Defaults, then the YAML file (if `path` is non-empty), then each "key=value" override.
template <class T>
T Load(const std::string& path, const std::vector<std::string>& overrides) {
  T config;
  if (!path.empty()) Apply(ParseYamlFile(path), config, path);
  for (const auto& assignment : overrides) Apply(ParseOverride(assignment), config, kCommandLine);
  return config;
}

/// Resolved config as YAML text (reads back to the same values). With `skip_unset`, fields holding NaN (an
/// unset number) are left out.
template <class T>
std::string ToYaml(const T& config, bool skip_unset = false) {
  YAML::Emitter out;
  internal::Emit(out, config, skip_unset);
  return std::string(out.c_str()) + "\n";
}

/// Every leaf key with its default (or current) value and help text.
template <class T>
std::vector<KeyInfo> ListKeys(const T& config) {
  KeyLister lister;
  const_cast<T&>(config).Visit(lister);
  return lister.keys();
}

/// Every numeric leaf of `config` (a section) as (prefix.key, value), in field order.
template <class T>
std::vector<std::pair<std::string, double>> ListNumbers(const T& config, const std::string& prefix) {
  NumberLister lister(prefix);
  const_cast<T&>(config).Visit(lister);
  return lister.numbers();
}

/// Formats ListKeys() as aligned text lines.
std::string FormatKeys(const std::vector<KeyInfo>& keys);

}  // namespace flowplan::config
