#pragma once

#include <stdexcept>
#include <string>

namespace flowplan {

/// An error the user can cause and fix: a bad config key or value, a missing or
/// corrupt file, an unreachable target. Its message is one line that names the
/// file, key or value at fault; `main` prints it and exits non-zero. Control
/// characters a message quotes from the input (a newline inside a bad value)
/// are written as escapes (\n, \r, \t, \xNN), so it stays one line.
class Error : public std::runtime_error {
 public:
  explicit Error(const std::string& message) : std::runtime_error(OneLine(message)) {}

  /// `text` with every control character written as an escape.
  static std::string OneLine(const std::string& text);
};

/// A broken internal invariant: a bug in flowplan, never the user's fault.
class InternalError : public std::logic_error {
 public:
  explicit InternalError(const std::string& message) : std::logic_error(message) {}
};

namespace internal {
[[noreturn]] void ThrowInternal(const char* condition, const char* file, int line);
}  // namespace internal

}  // namespace flowplan

/// Checks an internal invariant; a failure is a bug and throws InternalError.
#define FLOWPLAN_DEMAND(condition)                                               \
  do {                                                                           \
    if (!(condition)) ::flowplan::internal::ThrowInternal(#condition, __FILE__, __LINE__); \
  } while (false)
