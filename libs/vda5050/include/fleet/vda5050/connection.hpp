#pragma once

// The connection message: ONLINE/OFFLINE from the vehicle, CONNECTIONBROKEN as its last will.

#include <nlohmann/json.hpp>

#include <string>

#include "fleet/core/expected.hpp"
#include "fleet/vda5050/header.hpp"

namespace fleet::vda5050 {

struct Connection {
  Header header;
  std::string connectionState = "ONLINE";  // ONLINE, OFFLINE, CONNECTIONBROKEN
};

nlohmann::json toJson(const Connection& m);
Expected<Connection> parseConnection(const nlohmann::json& j);
Expected<Connection> parseConnection(const std::string& text);

}  // namespace fleet::vda5050
