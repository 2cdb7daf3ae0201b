#include "core/logging.h"

#include <spdlog/spdlog.h>

#include "core/error.h"

namespace flowplan {

void SetUpLogging(const std::string& level) {
  spdlog::set_pattern("[%H:%M:%S.%e] [%^%l%$] %v");
  const auto parsed = spdlog::level::from_str(level);
  if (parsed == spdlog::level::off && level != "off") {
    throw Error("--log-level: expected one of debug, info, warn, error, off, got \"" + level + "\"");
  }
  spdlog::set_level(parsed);
}

}  // namespace flowplan
