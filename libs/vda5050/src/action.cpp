#include "fleet/vda5050/action.hpp"

#include "json_reader.hpp"

namespace fleet::vda5050 {

nlohmann::json toJson(const Action& a) {
  nlohmann::json j;
  j["actionType"] = a.actionType;
  j["actionId"] = a.actionId;
  j["blockingType"] = a.blockingType;
  if (a.actionDescription) {
    j["actionDescription"] = *a.actionDescription;
  }
  if (!a.actionParameters.empty()) {
    auto& params = j["actionParameters"] = nlohmann::json::array();
    for (const auto& p : a.actionParameters) {
      params.push_back({{"key", p.key}, {"value", p.value}});
    }
  }
  return j;
}

namespace detail {

Action readAction(const JsonReader& r) {
  Action a;
  a.actionType = r.str("actionType");
  a.actionId = r.str("actionId");
  a.blockingType = r.oneOf("blockingType", {"NONE", "SOFT", "HARD"});
  a.actionDescription = r.optStr("actionDescription");
  for (const auto& p : r.optArray("actionParameters")) {
    const auto& v = p.raw("value");
    if (v.is_null()) {
      throw BadField(p.path() + ".value: must not be null");
    }
    a.actionParameters.push_back({p.str("key"), v});
  }
  return a;
}

}  // namespace detail
}  // namespace fleet::vda5050
