#include "core/error.hpp"

namespace lasercell::internal {

void ThrowCheckFailure(const char* condition, const char* file, int line,
                       const std::string& message) {
  throw InternalError("internal check failed: " + std::string(condition) + " at " + file + ":" +
                      std::to_string(line) + (message.empty() ? "" : " (" + message + ")") +
                      "; this is a lasercell bug, please report it with the input that caused it");
}

}  // namespace lasercell::internal
