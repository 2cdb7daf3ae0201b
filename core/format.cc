#include "core/format.h"

#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <cstdio>

#include "core/error.h"

namespace flowplan {

std::string ShapeText(const std::vector<int64_t>& shape) {
  std::string out = "(";
  for (size_t i = 0; i < shape.size(); ++i) out += (i ? ", " : "") + std::to_string(shape[i]);
  return out + (shape.size() == 1 ? ",)" : ")");
}

std::string Join(const std::vector<std::string>& parts, const std::string& separator) {
  std::string out;
  for (size_t i = 0; i < parts.size(); ++i) out += (i ? separator : "") + parts[i];
  return out;
}

std::string FirstLine(const std::string& text) { return text.substr(0, text.find('\n')); }

std::string LastLine(const std::string& text) {
  size_t end = text.find_last_not_of("\n ");
  if (end == std::string::npos) return "";
  const size_t begin = text.rfind('\n', end);
  return text.substr(begin == std::string::npos ? 0 : begin + 1, end + 1 - (begin == std::string::npos ? 0 : begin + 1));
}

std::string JsonNumber(double value) {
  if (!std::isfinite(value)) return "null";
  char buffer[32];
  std::snprintf(buffer, sizeof(buffer), "%.7g", value);
  return buffer;
}

std::string ShortNumber(double value) {
  char buffer[32];
  std::snprintf(buffer, sizeof(buffer), "%.4g", value);
  return buffer;
}

std::string JsonString(const std::string& text) {
  std::string out = "\"";
  for (const char c : text) {
    switch (c) {
      case '"': out += "\\\""; break;
      case '\\': out += "\\\\"; break;
      case '\n': out += "\\n"; break;
      case '\t': out += "\\t"; break;
      case '\r': out += "\\r"; break;
      default:
        if (static_cast<unsigned char>(c) < 0x20) {
          char escaped[8];
          std::snprintf(escaped, sizeof(escaped), "\\u%04x", c);
          out += escaped;
        } else {
          out += c;
        }
    }
  }
  return out + "\"";
}

std::vector<double> ParseNumbers(const std::string& text, const std::string& option) {
  std::vector<double> values;
  size_t begin = 0;
  while (true) {
    const size_t end = text.find(',', begin);
    const std::string field = text.substr(begin, end == std::string::npos ? std::string::npos : end - begin);
    const std::string where = option + " value " + std::to_string(values.size() + 1) + " \"" + field + "\"";
    char* rest = nullptr;
    errno = 0;
    const double value = std::strtod(field.c_str(), &rest);
    if (field.empty() || rest != field.c_str() + field.size() || field.find_first_of(" \t") != std::string::npos) {
      throw Error(where + ": not a number (expected comma-separated numbers)");
    }
    if (errno == ERANGE || !std::isfinite(value)) throw Error(where + ": not a finite number");
    values.push_back(value);
    if (end == std::string::npos) break;
    begin = end + 1;
  }
  return values;
}

}  // namespace flowplan
