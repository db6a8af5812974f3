#include "fleet/fleet/station_map.hpp"

#include <cmath>
#include <nlohmann/json.hpp>

#include "fleet/core/ids.hpp"
#include "fleet/fleet/errors.hpp"

namespace fleet {
namespace {

constexpr std::array<std::pair<std::string_view, StationKind>, 4> kKinds = {
    {{"pickup", StationKind::Pickup},
     {"dropoff", StationKind::Dropoff},
     {"charging", StationKind::Charging},
     {"parking", StationKind::Parking}}};

}  // namespace

std::string_view toString(StationKind k) {
  for (const auto& [name, kind] : kKinds) {
    if (kind == k) {
      return name;
    }
  }
  return "unknown";
}

Expected<void> StationMap::add(Station s) {
  if (!isValidId(s.name)) {
    return unexpected(errc::kInvalid, "station name '" + s.name + "' is not a valid id");
  }
  if (s.kinds == 0) {
    return unexpected(errc::kInvalid, "station '" + s.name + "' has no kind");
  }
  if (stations_.contains(s.name)) {
    return unexpected(errc::kConflict, "station '" + s.name + "' defined twice");
  }
  std::string key = s.name;
  stations_.emplace(std::move(key), std::move(s));
  return {};
}

const Station* StationMap::find(std::string_view name) const {
  auto it = stations_.find(name);
  return it == stations_.end() ? nullptr : &it->second;
}

std::vector<const Station*> StationMap::ofKind(StationKind k) const {
  std::vector<const Station*> out;
  for (const auto& [name, s] : stations_) {
    if (s.has(k)) {
      out.push_back(&s);
    }
  }
  return out;
}

std::vector<const Station*> StationMap::all() const {
  std::vector<const Station*> out;
  out.reserve(stations_.size());
  for (const auto& kv : stations_) {
    out.push_back(&kv.second);
  }
  return out;
}

Expected<StationMap> StationMap::fromJson(const nlohmann::json& doc) {
  std::vector<std::string> problems;
  const nlohmann::json* list = &doc;
  std::string base;
  if (doc.is_object()) {
    if (!doc.contains("stations")) {
      return unexpected(errc::kInvalid, "stations: required");
    }
    list = &doc.at("stations");
    base = "stations";
  }
  if (!list->is_array()) {
    return unexpected(errc::kInvalid, (base.empty() ? std::string("(root)") : base) + ": expected an array");
  }
  StationMap map;
  for (std::size_t i = 0; i < list->size(); ++i) {
    // The simulator's scenario files write a station as {"name", "kind", "pose": [x, y, theta]};
    // accept that form too, so one scenario file can configure the whole fleet.
    nlohmann::json e = (*list)[i];
    if (e.is_object() && e.contains("pose") && e["pose"].is_array() && !e.contains("x") && !e.contains("y")) {
      const auto& pose = e["pose"];
      if (pose.size() >= 1)
        e["x"] = pose[0];
      if (pose.size() >= 2)
        e["y"] = pose[1];
      if (pose.size() >= 3)
        e["theta"] = pose[2];
    }
    if (e.is_object() && e.contains("kind") && !e.contains("kinds")) {
      e["kinds"] = nlohmann::json::array({e["kind"]});
    }
    const std::string p = base + "[" + std::to_string(i) + "]";
    if (!e.is_object()) {
      problems.push_back(p + ": expected an object");
      continue;
    }
    Station s;
    bool ok = true;
    if (!e.contains("name") || !e["name"].is_string()) {
      problems.push_back(p + ".name: required string");
      ok = false;
    } else {
      s.name = e["name"].get<std::string>();
    }
    for (const char* key : {"x", "y", "theta"}) {
      const bool required = std::string_view(key) != "theta";
      if (!e.contains(key)) {
        if (required) {
          problems.push_back(p + "." + key + ": required number");
          ok = false;
        }
        continue;
      }
      if (!e[key].is_number() || !std::isfinite(e[key].get<double>())) {
        problems.push_back(p + "." + key + ": expected a finite number");
        ok = false;
        continue;
      }
      const double v = e[key].get<double>();
      (std::string_view(key) == "x" ? s.pose.x : std::string_view(key) == "y" ? s.pose.y : s.pose.theta) = v;
    }
    s.pose.theta = wrapAngle(s.pose.theta);
    if (!e.contains("kinds") || !e["kinds"].is_array() || e["kinds"].empty()) {
      problems.push_back(p + ".kinds: required non-empty array of pickup/dropoff/charging/parking");
      ok = false;
    } else {
      for (std::size_t k = 0; k < e["kinds"].size(); ++k) {
        const auto& kj = e["kinds"][k];
        bool found = false;
        if (kj.is_string()) {
          for (const auto& [name, kind] : kKinds) {
            if (kj.get<std::string>() == name) {
              s.kinds |= static_cast<std::uint8_t>(kind);
              found = true;
            }
          }
        }
        if (!found) {
          problems.push_back(p + ".kinds[" + std::to_string(k) + "]: unknown kind " + kj.dump() +
                             " (expected pickup, dropoff, charging or parking)");
          ok = false;
        }
      }
    }
    if (ok) {
      if (auto r = map.add(std::move(s)); !r) {
        problems.push_back(p + ": " + r.error().message);
      }
    }
  }
  if (!problems.empty()) {
    std::string msg;
    for (const auto& pr : problems) {
      msg += (msg.empty() ? "" : "; ") + pr;
    }
    return unexpected(errc::kInvalid, msg);
  }
  return map;
}

}  // namespace fleet
