#include "fleet_bound.hpp"

#include <algorithm>
#include <cmath>
#include <map>
#include <stdexcept>
#include <utility>

#include "fleet/site/disc_distance.hpp"

namespace fleet::ctl {

namespace {

bool finiteNonNegative(double x) {
  return std::isfinite(x) && x >= 0.0;
}

std::optional<std::string> badInput(const FleetBoundInput& in) {
  if (in.starts.empty()) {
    return "no robot";
  }
  if (in.tasks.empty()) {
    return "no task";
  }
  if (!std::isfinite(in.cruise) || in.cruise <= 0.0 || !finiteNonNegative(in.radius)) {
    return "cruise must be > 0 and radius >= 0, both finite";
  }
  for (const auto& s : in.starts) {
    if (!s.isFinite()) {
      return "a robot start is not finite";
    }
  }
  bool anyStation = false;
  for (const auto& t : in.tasks) {
    if (t.stops.empty()) {
      return "a task without a stop";
    }
    for (const auto& stop : t.stops) {
      if (!finiteNonNegative(stop.dwellS)) {
        return "a stop's dwell (load, unload, wait) is negative or not finite";
      }
      anyStation = anyStation || !stop.station.empty();
    }
  }
  if (!anyStation) {
    return "no task visits a station";
  }
  return std::nullopt;
}

}  // namespace

Expected<FleetBound> fleetBound(const planning::OccupancyGrid& freeMap, const FleetBoundInput& in) {
  if (auto why = badInput(in)) {
    return unexpected("bad_input", *why);
  }
  if (freeMap.size() == 0) {
    return unexpected("bad_input", "the map is empty");
  }
  std::map<std::string, const BoundStation*> byName;
  for (const auto& s : in.stations) {
    byName[s.name] = &s;
  }
  for (const auto& t : in.tasks) {
    for (const auto& stop : t.stops) {
      if (!stop.station.empty() && !byName.count(stop.station)) {
        return unexpected("unknown_station", "station '" + stop.station + "' is not on the site");
      }
    }
  }
  // The chain's stations in order (a wait where the robot stands adds dwell, no way), and every
  // leg of it grouped by its goal so that each station's field is built once.
  std::vector<std::string> chain;
  double dwell = 0.0;
  for (const auto& t : in.tasks) {
    for (const auto& stop : t.stops) {
      dwell += stop.dwellS;
      if (!stop.station.empty()) {
        chain.push_back(stop.station);
      }
    }
  }
  std::map<std::string, std::vector<Vec2>> froms;  // goal station → from points
  auto dock = [&](const std::string& name) { return byName.at(name)->geometry.dock; };
  for (const auto& s : in.starts) {
    froms[chain.front()].push_back(s);
  }
  for (std::size_t i = 1; i < chain.size(); ++i) {
    froms[chain[i]].push_back(dock(chain[i - 1]));
  }
  std::map<std::pair<std::string, std::pair<double, double>>, double> length;
  try {
    site::DiscDistance free(freeMap, in.radius, 2);
    for (const auto& [goal, points] : froms) {
      for (const Vec2& from : points) {
        const auto key = std::make_pair(goal, std::make_pair(from.x, from.y));
        if (length.count(key)) {
          continue;
        }
        auto d = free.length(from, dock(goal));
        if (!d) {
          return unexpected(d.error().code, "to " + goal + " from (" + std::to_string(from.x) + ", " +
                                                std::to_string(from.y) + "): " + d.error().message);
        }
        length[key] = *d;
      }
    }
  } catch (const std::invalid_argument& e) {
    return unexpected("bad_input", e.what());
  }
  auto way = [&](Vec2 from, const std::string& goal) {
    return length.at(std::make_pair(goal, std::make_pair(from.x, from.y)));
  };

  FleetBound b;
  b.robots = in.starts.size();
  b.tasks = in.tasks.size();
  double first = way(in.starts.front(), chain.front());
  for (const auto& s : in.starts) {
    first = std::min(first, way(s, chain.front()));  // the best start: the bound stays one
  }
  b.chainDriveM = first;
  for (std::size_t i = 1; i < chain.size(); ++i) {
    b.chainDriveM += way(dock(chain[i - 1]), chain[i]);
  }
  b.chainS = b.chainDriveM / in.cruise + dwell;
  const auto n = static_cast<double>(b.tasks);
  b.lonePerH = b.chainS > 0.0 ? 3600.0 * n / b.chainS : 0.0;
  b.robotPerH = static_cast<double>(b.robots) * b.lonePerH;

  // Station loads: visits and the dwell they bring.
  std::map<std::string, std::pair<std::size_t, double>> visits;  // name → (visits, dwell sum)
  for (const auto& t : in.tasks) {
    for (const auto& stop : t.stops) {
      if (!stop.station.empty()) {
        auto& v = visits[stop.station];
        ++v.first;
        v.second += stop.dwellS;
      }
    }
  }
  for (const auto& [name, v] : visits) {
    StationLoad s;
    s.name = name;
    s.visits = v.first;
    s.share = static_cast<double>(v.first) / n;
    s.moveS = dockMoveSeconds(byName.at(name)->geometry, in.radius, in.cruise);
    s.cycleS = s.moveS + v.second / static_cast<double>(v.first);
    s.boundPerH = s.cycleS > 0.0 ? 3600.0 / (s.cycleS * s.share) : 0.0;
    b.stations.push_back(s);
  }
  // A station whose cycle takes no time bounds nothing (boundPerH 0): it sorts last.
  std::stable_sort(b.stations.begin(), b.stations.end(), [](const StationLoad& x, const StationLoad& y) {
    return y.boundPerH <= 0.0 ? x.boundPerH > 0.0 : (x.boundPerH > 0.0 && x.boundPerH < y.boundPerH);
  });
  if (!b.stations.empty() && b.stations.front().boundPerH > 0.0) {
    b.stationPerH = b.stations.front().boundPerH;
    b.bindingStation = b.stations.front().name;
  } else {
    b.stationPerH = b.robotPerH;  // no station time: the robots bind
  }
  return b;
}

}  // namespace fleet::ctl

#include "fleet/traffic/roadmap.hpp"

namespace fleet::ctl {

std::vector<BoundStation> boundStations(const traffic::Roadmap& roadmap) {
  const auto& g = roadmap.graph;
  std::vector<BoundStation> out;
  for (const auto& s : roadmap.stations) {
    if (s.dock == traffic::kNoNode) {
      continue;
    }
    out.push_back({s.name, traffic::dockGeometry(g, s)});
  }
  return out;
}

}  // namespace fleet::ctl
