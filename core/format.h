#pragma once

// Small text helpers shared by error messages, logs and JSON reports.

#include <cstdint>
#include <string>
#include <vector>

namespace flowplan {

/// "(2, 64, 4)" for a shape.
std::string ShapeText(const std::vector<int64_t>& shape);

/// `parts` joined by `separator`: Join({"a", "b"}, ",") == "a,b".
std::string Join(const std::vector<std::string>& parts, const std::string& separator = ", ");

/// The first line of a (possibly multi-line) message, e.g. LibTorch's errors.
std::string FirstLine(const std::string& text);

/// The last non-empty line of a message, e.g. the assertion of a TorchScript error.
std::string LastLine(const std::string& text);

/// A JSON number with up to 7 significant digits; "null" for NaN and infinities.
std::string JsonNumber(double value);

/// A number for a message, to 4 significant digits ("%.4g").
std::string ShortNumber(double value);

/// A JSON string literal, quoted and escaped.
std::string JsonString(const std::string& text);

/// Comma-separated finite numbers ("0.5,0,0.2"); `option` names them in errors.
/// @throws flowplan::Error naming the field that is empty or not a finite number.
std::vector<double> ParseNumbers(const std::string& text, const std::string& option);

}  // namespace flowplan
