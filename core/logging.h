#pragma once

#include <string>

namespace flowplan {

/// Sets the console log format ("[12:00:01.234] [info] message") and level
/// ("debug", "info", "warn", "error").
/// @throws flowplan::Error for an unknown level.
void SetUpLogging(const std::string& level);

}  // namespace flowplan
