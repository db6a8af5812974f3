#include "fleet/vda5050/instant_actions.hpp"

#include "json_reader.hpp"

namespace fleet::vda5050 {

nlohmann::json toJson(const InstantActions& m) {
  nlohmann::json j;
  writeHeader(j, m.header);
  auto& actions = j["actions"] = nlohmann::json::array();
  for (const auto& a : m.actions) {
    actions.push_back(toJson(a));
  }
  return j;
}

Expected<InstantActions> parseInstantActions(const nlohmann::json& j) {
  return detail::parseAs<InstantActions>(j, "instantActions", [](const detail::JsonReader& r) {
    InstantActions m;
    m.header = detail::readHeader(r);
    for (const auto& a : r.array("actions")) {
      m.actions.push_back(detail::readAction(a));
    }
    return m;
  });
}

Expected<InstantActions> parseInstantActions(const std::string& text) {
  return detail::parseTextWith<InstantActions>(text, "instantActions", &parseInstantActions);
}

}  // namespace fleet::vda5050
