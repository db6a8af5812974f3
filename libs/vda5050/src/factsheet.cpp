#include "fleet/vda5050/factsheet.hpp"

#include <algorithm>
#include <cmath>

#include "json_reader.hpp"

namespace fleet::vda5050 {

namespace {
std::vector<std::string> strings(const detail::JsonReader& r, const char* key) {
  const auto& v = r.raw(key);
  if (!v.is_array()) {
    throw detail::BadField(r.path() + "." + key + ": expected an array of strings");
  }
  std::vector<std::string> out;
  for (const auto& s : v) {
    if (!s.is_string()) {
      throw detail::BadField(r.path() + "." + key + ": expected an array of strings");
    }
    out.push_back(s.get<std::string>());
  }
  return out;
}
}  // namespace

nlohmann::json toJson(const Factsheet& m) {
  nlohmann::json j;
  writeHeader(j, m.header);
  j["typeSpecification"] = {{"seriesName", m.seriesName},
                            {"agvKinematic", m.agvKinematic},
                            {"agvClass", m.agvClass},
                            {"maxLoadMass", m.maxLoadMass},
                            {"localizationTypes", m.localizationTypes},
                            {"navigationTypes", m.navigationTypes}};
  j["physicalParameters"] = {{"speedMin", m.speedMin},
                             {"speedMax", m.speedMax},
                             {"accelerationMax", m.accelerationMax},
                             {"decelerationMax", m.decelerationMax},
                             {"heightMax", m.heightMax},
                             {"width", m.width},
                             {"length", m.length}};
  j["protocolLimits"] = {{"maxStringLens", nlohmann::json::object()},
                         {"maxArrayLens", nlohmann::json::object()},
                         {"timing",
                          {{"minOrderInterval", m.minOrderInterval},
                           {"minStateInterval", m.minStateInterval},
                           {"defaultStateInterval", m.defaultStateInterval}}}};
  auto actions = nlohmann::json::array();
  for (const auto& a : m.agvActions) {
    actions.push_back({{"actionType", a}, {"actionScopes", {"INSTANT", "NODE"}}});
  }
  j["protocolFeatures"] = {{"optionalParameters", nlohmann::json::array()}, {"agvActions", actions}};
  // The footprint as the 2-D envelope around the kinematic centre.
  auto envelopes = nlohmann::json::array();
  for (const auto& e : m.envelopes2d) {
    auto points = nlohmann::json::array();
    for (const auto& [x, y] : e.points) {
      points.push_back({{"x", x}, {"y", y}});
    }
    envelopes.push_back({{"set", e.set}, {"polygonPoints", points}});
  }
  if (m.envelopes2d.empty()) {
    const double hx = m.length / 2.0;
    const double hy = m.width / 2.0;
    envelopes.push_back({{"set", "default"},
                         {"polygonPoints",
                          {{{"x", hx}, {"y", hy}},
                           {{"x", -hx}, {"y", hy}},
                           {{"x", -hx}, {"y", -hy}},
                           {{"x", hx}, {"y", -hy}}}}});
  }
  j["agvGeometry"] = {{"envelopes2d", envelopes}};
  j["loadSpecification"] = nlohmann::json::object();
  return j;
}

Expected<Factsheet> parseFactsheet(const nlohmann::json& j) {
  return detail::parseAs<Factsheet>(j, "factsheet", [](const detail::JsonReader& r) {
    Factsheet m;
    m.header.headerId = static_cast<std::uint32_t>(r.has("headerId") ? r.uint("headerId") : 0);
    m.header.timestamp = r.optStr("timestamp").value_or("");
    m.header.version = r.str("version");
    m.header.manufacturer = r.str("manufacturer");
    m.header.serialNumber = r.str("serialNumber");
    const auto t = r.object("typeSpecification");
    m.seriesName = t.str("seriesName");
    m.agvKinematic = t.oneOf("agvKinematic", {"DIFF", "OMNI", "THREEWHEEL"});
    m.agvClass = t.oneOf("agvClass", {"FORKLIFT", "CONVEYOR", "TUGGER", "CARRIER"});
    m.maxLoadMass = t.number("maxLoadMass");
    m.localizationTypes = strings(t, "localizationTypes");
    m.navigationTypes = strings(t, "navigationTypes");
    const auto p = r.object("physicalParameters");
    m.speedMin = p.number("speedMin");
    m.speedMax = p.number("speedMax");
    m.accelerationMax = p.number("accelerationMax");
    m.decelerationMax = p.number("decelerationMax");
    m.heightMax = p.number("heightMax");
    m.width = p.number("width");
    m.length = p.number("length");
    if (m.width <= 0.0 || m.length <= 0.0) {
      throw detail::BadField(p.path() + ": width and length must be positive");
    }
    const auto timing = r.object("protocolLimits").object("timing");
    m.minOrderInterval = timing.number("minOrderInterval");
    m.minStateInterval = timing.number("minStateInterval");
    m.defaultStateInterval = timing.optNumber("defaultStateInterval").value_or(1.0);
    for (const auto& a : r.object("protocolFeatures").array("agvActions")) {
      m.agvActions.push_back(a.str("actionType"));
    }
    const auto geometry = r.object("agvGeometry");
    if (geometry.has("envelopes2d")) {
      for (const auto& e : geometry.array("envelopes2d")) {
        Envelope2d env{e.str("set"), {}};
        for (const auto& point : e.array("polygonPoints")) {
          env.points.emplace_back(point.number("x"), point.number("y"));
        }
        // A polygon of fewer than 3 points outlines nothing: skipped rather than refusing the
        // whole factsheet (the vehicle could never join for one bad envelope).
        if (env.points.size() >= 3) {
          m.envelopes2d.push_back(std::move(env));
        }
      }
    }
    (void)r.object("loadSpecification");
    return m;
  });
}

Footprint footprint(const Factsheet& f) {
  Footprint out;
  for (const auto& e : f.envelopes2d) {
    for (const auto& [x, y] : e.points) {
      const double r = std::hypot(x, y);
      if (r > out.radius) {
        out = {r, "envelope '" + e.set + "'"};
      }
    }
  }
  if (f.envelopes2d.empty()) {
    out = {std::hypot(f.width, f.length) / 2.0, "width x length"};
  }
  // However the envelopes are drawn, the vehicle is at least as wide and as long as it says.
  if (const double half = std::max(f.width, f.length) / 2.0; half > out.radius) {
    out = {half, "width and length"};
  }
  return out;
}

Expected<Factsheet> parseFactsheet(const std::string& text) {
  return detail::parseTextWith<Factsheet>(text, "factsheet", &parseFactsheet);
}

}  // namespace fleet::vda5050
