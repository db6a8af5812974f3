#include "fleet/vda5050/vehicle_registry.hpp"

#include <cmath>
#include <cstdio>
#include <utility>

#include "fleet/vda5050/connection.hpp"
#include "fleet/vda5050/header.hpp"

namespace fleet::vda5050 {

const char* toString(VehicleHealth h) {
  switch (h) {
    case VehicleHealth::kUnknown:
      return "unknown";
    case VehicleHealth::kOnline:
      return "online";
    case VehicleHealth::kManual:
      return "manual";
    case VehicleHealth::kFault:
      return "fault";
    case VehicleHealth::kOffline:
      return "offline";
  }
  return "?";
}

std::vector<std::string> vehicleEntryProblems(const std::vector<VehicleEntry>& vehicles) {
  std::vector<std::string> out;
  std::map<std::pair<std::string, std::string>, std::size_t> identities;
  std::map<std::string, std::size_t> ids;
  for (std::size_t i = 0; i < vehicles.size(); ++i) {
    const auto& v = vehicles[i];
    const std::string at = "vehicles[" + std::to_string(i) + "].";
    for (const auto& [key, value] : {std::pair{"manufacturer", &v.manufacturer}, {"serial", &v.serial}}) {
      if (value->empty()) {
        out.push_back(at + key + ": must not be empty");
      } else if (value->find_first_of("#+/") != std::string::npos) {
        out.push_back(at + key + ": \"" + *value +
                      "\" holds an MQTT wildcard or level separator ('#', '+', '/'): its topics would be "
                      "other vehicles' too");
      }
    }
    if (auto [it, fresh] = identities.try_emplace({v.manufacturer, v.serial}, i); !fresh) {
      out.push_back(at + "serial: vehicle " + v.manufacturer + "/" + v.serial + " is vehicles[" +
                    std::to_string(it->second) + "] already (one identity, one vehicle)");
    }
    if (auto [it, fresh] = ids.try_emplace(v.robot_id, i); !fresh) {
      out.push_back(at + "robot: robot id \"" + v.robot_id + "\" is vehicles[" + std::to_string(it->second) +
                    "]'s already");
    }
  }
  return out;
}

VehicleRegistry::VehicleRegistry(std::string interface_name, std::string map_id,
                                 std::vector<VehicleEntry> vehicles, RegistryLimits limits)
    : interface_(std::move(interface_name)), map_id_(std::move(map_id)), limits_(limits) {
  for (auto& e : vehicles) {
    by_topic_prefix_[topicName(interface_, e.manufacturer, e.serial, "")] = e.robot_id;
    const auto id = e.robot_id;
    vehicles_[id].entry = std::move(e);
  }
}

void VehicleRegistry::setSiteBounds(double minX, double minY, double maxX, double maxY) {
  limits_.minX = minX;
  limits_.minY = minY;
  limits_.maxX = maxX;
  limits_.maxY = maxY;
}

RegistryOutcome VehicleRegistry::refuseUnread(VehicleView* v, const Error& e) {
  return refuse(e.code.find(".json.too_") != std::string::npos ? "too_large" : "bad_message", v, e.message);
}

std::optional<std::pair<std::string, std::string>> VehicleRegistry::implausible(const State& s) const {
  if (!speaksVersion(s.header.version)) {
    return std::pair<std::string, std::string>{
        "unsupported_version",
        "protocol version \"" + s.header.version + "\"; this master control speaks 2.0 and 2.1"};
  }
  if (const auto& p = s.agvPosition) {
    if (!std::isfinite(p->x) || !std::isfinite(p->y) || !std::isfinite(p->theta) || p->x < limits_.minX ||
        p->x > limits_.maxX || p->y < limits_.minY || p->y > limits_.maxY) {
      char where[160];
      std::snprintf(where, sizeof where,
                    "agvPosition (%g, %g, theta %g) is outside the site [%g, %g] x [%g, %g]", p->x, p->y,
                    p->theta, limits_.minX, limits_.maxX, limits_.minY, limits_.maxY);
      return std::pair<std::string, std::string>{"implausible_position", where};
    }
  }
  const double b = s.batteryState.batteryCharge;
  if (!std::isfinite(b) || b < 0 || b > 100) {
    return std::pair<std::string, std::string>{
        "implausible_battery", "batteryCharge " + std::to_string(b) + " is not within 0..100 %"};
  }
  return std::nullopt;
}

const VehicleView* VehicleRegistry::find(const std::string& robot_id) const {
  const auto it = vehicles_.find(robot_id);
  return it == vehicles_.end() ? nullptr : &it->second;
}

void VehicleRegistry::ordered(const std::string& robot_id, const Order& order) {
  auto it = vehicles_.find(robot_id);
  if (it == vehicles_.end()) {
    return;
  }
  auto& v = it->second;
  if (!v.state || v.state->orderId != order.orderId) {
    v.ordered_nodes.clear();
    if (v.state) {
      v.ordered_nodes.insert(v.state->lastNodeId);  // where it stands may be reported until it moves
    }
  }
  for (const auto& n : order.nodes) {
    v.ordered_nodes.insert(n.nodeId);
  }
}

bool VehicleRegistry::setHealth(VehicleView& v, VehicleHealth h, std::string reason) {
  const bool changed = v.health != h;
  v.health = h;
  v.reason = std::move(reason);
  return changed;
}

RegistryOutcome VehicleRegistry::refuse(const std::string& kind, VehicleView* v, std::string reason) {
  ++refusals_[kind];
  RegistryOutcome out;
  out.reason = std::move(reason);
  if (v != nullptr) {
    out.robot_id = v->entry.robot_id;
    out.health_changed = setHealth(*v, VehicleHealth::kFault, kind + ": " + out.reason);
  }
  return out;
}

RegistryOutcome VehicleRegistry::onMessage(const std::string& topic, const std::string& payload) {
  const auto slash = topic.rfind('/');
  if (slash == std::string::npos) {
    return refuse("unknown_topic", nullptr,
                  "topic '" + topic + "' is not " + interface_ + "/v2/<m>/<s>/<topic>");
  }
  const auto prefix = topic.substr(0, slash + 1);
  const auto name = topic.substr(slash + 1);
  const auto known = by_topic_prefix_.find(prefix);
  if (known == by_topic_prefix_.end()) {
    return refuse("unknown_serial", nullptr, "no vehicle is configured for '" + prefix + "'");
  }
  auto& v = vehicles_.at(known->second);
  if (payload.size() > limits_.maxMessageBytes) {
    return refuse("too_large", &v,
                  "message of " + std::to_string(payload.size()) + " bytes, more than " +
                      std::to_string(limits_.maxMessageBytes) + " (max_message_bytes)");
  }
  const auto checkHeader = [&](const Header& h) -> std::optional<std::string> {
    if (h.manufacturer != v.entry.manufacturer || h.serialNumber != v.entry.serial) {
      return "message of " + h.manufacturer + "/" + h.serialNumber + " on the topic of " +
             v.entry.manufacturer + "/" + v.entry.serial;
    }
    return std::nullopt;
  };
  RegistryOutcome out;
  out.robot_id = v.entry.robot_id;
  if (name == "connection") {
    auto c = parseConnection(payload);
    if (!c) {
      return refuseUnread(&v, c.error());
    }
    if (auto bad = checkHeader(c->header)) {
      return refuse("wrong_serial", &v, *bad);
    }
    if (c->connectionState == "ONLINE") {
      // Online again; it rejoins traffic control with its next good state.
      out.health_changed = v.health == VehicleHealth::kOffline &&
                           setHealth(v, VehicleHealth::kUnknown, "connected, no state yet");
    } else {
      out.health_changed = setHealth(v, VehicleHealth::kOffline, "connection " + c->connectionState);
    }
    out.accepted = true;
    return out;
  }
  if (name == "factsheet") {
    auto f = parseFactsheet(payload);
    if (!f) {
      return refuseUnread(&v, f.error());
    }
    if (auto bad = checkHeader(f->header)) {
      return refuse("wrong_serial", &v, *bad);
    }
    v.factsheet = std::move(*f);
    out.accepted = true;
    return out;
  }
  if (name != "state") {
    ++refusals_["unknown_topic"];
    out.reason = "topic '" + name + "' is not read by the master control";
    return out;  // visualization and the like: ignored, the vehicle is not blamed
  }
  auto s = parseState(payload);
  if (!s) {
    return refuseUnread(&v, s.error());
  }
  if (auto bad = checkHeader(s->header)) {
    return refuse("wrong_serial", &v, *bad);
  }
  if (auto bad = implausible(*s)) {
    return refuse(bad->first, &v, bad->second);
  }
  if (s->agvPosition && s->agvPosition->mapId != map_id_) {
    return refuse("other_map", &v,
                  "on map '" + s->agvPosition->mapId + "', the fleet's is '" + map_id_ + "'");
  }
  if (v.ordered_nodes.empty()) {
    v.ordered_nodes.insert(s->lastNodeId);  // before any order of ours: where it stands is its start
  } else if (!s->lastNodeId.empty() && !v.ordered_nodes.contains(s->lastNodeId)) {
    return refuse("node_never_ordered", &v, "reports node '" + s->lastNodeId + "', never ordered");
  }
  std::string fatal;
  for (const auto& e : s->errors) {
    if (e.errorLevel == "FATAL") {
      fatal += (fatal.empty() ? "" : ", ") + e.errorType;
    }
  }
  if (s->operatingMode != "AUTOMATIC" && s->operatingMode != "SEMIAUTOMATIC") {
    out.health_changed = setHealth(v, VehicleHealth::kManual, "operating mode " + s->operatingMode);
  } else if (!fatal.empty()) {
    out.health_changed = setHealth(v, VehicleHealth::kFault, "FATAL error(s): " + fatal);
  } else {
    out.health_changed = setHealth(v, VehicleHealth::kOnline, "");
  }
  v.state = std::move(*s);
  out.accepted = true;
  return out;
}

}  // namespace fleet::vda5050
