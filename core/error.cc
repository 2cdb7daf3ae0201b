#include "core/error.h"

namespace flowplan::internal {

void ThrowInternal(const char* condition, const char* file, int line) {
  throw InternalError(std::string("internal error: ") + file + ":" + std::to_string(line) +
                      ": condition '" + condition + "' failed");
}

}  // namespace flowplan::internal
