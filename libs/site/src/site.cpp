#include "fleet/site/site.hpp"

#include <limits>

namespace fleet::site {

namespace {
constexpr const char* kStationKinds[] = {"pickup", "dropoff", "charging", "parking"};
constexpr const char* kZoneKinds[] = {"no_go", "speed_limit", "one_way"};
}  // namespace

const char* toString(StationKind k) {
  return kStationKinds[static_cast<int>(k)];
}

std::optional<StationKind> stationKindFromString(const std::string& s) {
  for (int i = 0; i < 4; ++i) {
    if (s == kStationKinds[i]) {
      return static_cast<StationKind>(i);
    }
  }
  return std::nullopt;
}

const char* toString(ZoneKind k) {
  return kZoneKinds[static_cast<int>(k)];
}

const Station* Site::station(const std::string& stationName) const {
  for (const auto& s : stations) {
    if (s.name == stationName) {
      return &s;
    }
  }
  return nullptr;
}

std::vector<const Station*> Site::ofKind(StationKind k) const {
  std::vector<const Station*> out;
  for (const auto& s : stations) {
    if (s.kind == k) {
      out.push_back(&s);
    }
  }
  return out;
}

planning::OccupancyGrid Site::drivable() const {
  planning::OccupancyGrid g = map;
  for (std::size_t i = 0; i < layers.noGo.size() && i < g.size(); ++i) {
    if (layers.noGo[i]) {
      g.setBlocked(g.cellOf(i));
    }
  }
  return g;
}

double Site::speedLimitAt(Vec2 p) const {
  const auto c = map.cellAt(p);
  if (!c || layers.speedLimit.size() != map.size()) {
    return std::numeric_limits<double>::infinity();
  }
  return static_cast<double>(layers.speedLimit[map.index(*c)]);
}

}  // namespace fleet::site
