#pragma once

// Actions to run at once, outside any order: pause, resume, cancel, charging, factsheet request.

#include <nlohmann/json.hpp>

#include <string>
#include <vector>

#include "fleet/core/expected.hpp"
#include "fleet/vda5050/action.hpp"
#include "fleet/vda5050/header.hpp"

namespace fleet::vda5050 {

struct InstantActions {
  Header header;
  std::vector<Action> actions;
};

nlohmann::json toJson(const InstantActions& m);
Expected<InstantActions> parseInstantActions(const nlohmann::json& j);
Expected<InstantActions> parseInstantActions(const std::string& text);

}  // namespace fleet::vda5050
