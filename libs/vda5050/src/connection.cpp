#include "fleet/vda5050/connection.hpp"

#include "json_reader.hpp"

namespace fleet::vda5050 {

nlohmann::json toJson(const Connection& m) {
  nlohmann::json j;
  writeHeader(j, m.header);
  j["connectionState"] = m.connectionState;
  return j;
}

Expected<Connection> parseConnection(const nlohmann::json& j) {
  return detail::parseAs<Connection>(j, "connection", [](const detail::JsonReader& r) {
    Connection m;
    m.header = detail::readHeader(r);
    m.connectionState = r.oneOf("connectionState", {"ONLINE", "OFFLINE", "CONNECTIONBROKEN"});
    return m;
  });
}

Expected<Connection> parseConnection(const std::string& text) {
  return detail::parseTextWith<Connection>(text, "connection", &parseConnection);
}

}  // namespace fleet::vda5050
