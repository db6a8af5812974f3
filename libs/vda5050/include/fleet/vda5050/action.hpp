#pragma once

// An action of an order's node or edge, or an instant action (specification 2.1, section 6.11).

#include <nlohmann/json.hpp>

#include <optional>
#include <string>
#include <vector>

namespace fleet::vda5050 {

struct ActionParameter {
  std::string key;
  nlohmann::json value;  // array, boolean, number, string or object
};

struct Action {
  std::string actionType;  // "pick", "drop", "startPause", "stopPause", "cancelOrder", ...
  std::string actionId;
  std::string blockingType = "HARD";  // NONE, SOFT, HARD
  std::optional<std::string> actionDescription;
  std::vector<ActionParameter> actionParameters;
};

nlohmann::json toJson(const Action& a);

}  // namespace fleet::vda5050
