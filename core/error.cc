#include "core/error.h"

#include <cstdio>

namespace flowplan {

std::string Error::OneLine(const std::string& text) {
  std::string out;
  out.reserve(text.size());
  for (const char c : text) {
    const auto byte = static_cast<unsigned char>(c);
    if (byte >= 0x20 && byte != 0x7f) {
      out += c;
    } else if (c == '\n') {
      out += "\\n";
    } else if (c == '\r') {
      out += "\\r";
    } else if (c == '\t') {
      out += "\\t";
    } else {
      char escape[5];
      std::snprintf(escape, sizeof(escape), "\\x%02x", byte);
      out += escape;
    }
  }
  return out;
}

}  // namespace flowplan

namespace flowplan::internal {

void ThrowInternal(const char* condition, const char* file, int line) {
  throw InternalError(std::string("internal error: ") + file + ":" + std::to_string(line) +
                      ": condition '" + condition + "' failed");
}

}  // namespace flowplan::internal
