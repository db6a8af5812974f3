#include "fleet/core/log_text.hpp"

#include <nlohmann/json.hpp>

namespace fleet {

std::string escapeForLog(std::string_view text) {
  const std::string quoted =
      nlohmann::json(std::string(text)).dump(-1, ' ', false, nlohmann::json::error_handler_t::replace);
  return quoted.substr(1, quoted.size() - 2);
}

}  // namespace fleet
