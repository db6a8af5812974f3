#include "fleet/fleet/station_choice.hpp"

#include <algorithm>
#include <cmath>
#include <tuple>

namespace fleet {

StationKind targetKind(TaskKind k) {
  return k == TaskKind::Charge ? StationKind::Charging : StationKind::Parking;
}

bool needsStation(const Task& t) {
  return (t.kind == TaskKind::Charge || t.kind == TaskKind::Park) && t.station.empty();
}

StationChooser::StationChooser(const StationMap& stations, std::set<std::string, std::less<>> targeted,
                               std::span<const RobotInfo> robots, double standReach)
    : stations_(stations), taken_(std::move(targeted)) {
  const auto places = [&] {
    auto p = stations.ofKind(StationKind::Charging);
    auto k = stations.ofKind(StationKind::Parking);
    p.insert(p.end(), k.begin(), k.end());
    return p;
  }();
  for (const RobotInfo& r : robots) {
    if (r.lost) {
      continue;
    }
    for (const Station* s : places) {
      if (distance(r.pose.position(), s->pose.position()) <= standReach) {
        standing_[s->name].push_back(r.id);
      }
    }
  }
}

StationChooser::Options StationChooser::options(const Task& t, const TravelModel& travel) const {
  Options o;
  for (const Station* s : stations_.ofKind(targetKind(t.kind))) {
    if (!taken(s->name)) {
      o.stations.push_back(s);
    }
  }
  o.tasks.reserve(o.stations.size());  // no reallocation below: travel functions may refer to them
  for (const Station* s : o.stations) {
    o.tasks.push_back(t);
    o.tasks.back().station = s->name;
    o.travel.push_back(travel(o.tasks.back()));
  }
  return o;
}

bool StationChooser::blockedFor(const Station& s, const RobotInfo& r) const {
  const auto it = standing_.find(s.name);
  return it != standing_.end() &&
         std::any_of(it->second.begin(), it->second.end(), [&](const std::string& id) { return id != r.id; });
}

StationChooser::Pick StationChooser::best(const Options& o, const RobotInfo& r) const {
  Pick p;
  for (std::size_t i = 0; i < o.stations.size(); ++i) {
    const Station* s = o.stations[i];
    if (taken(s->name)) {
      continue;
    }
    const double d = o.travel[i](r);
    if (!std::isfinite(d)) {
      continue;
    }
    const bool blocked = blockedFor(*s, r);
    if (p.station == nullptr || std::tuple(blocked, d) < std::tuple(p.blocked, p.travelS)) {
      p = {s, d, blocked};
    }
  }
  return p;
}

std::size_t StationChooser::countOfKind(StationKind k) const {
  return stations_.ofKind(k).size();
}

std::size_t StationChooser::freeOfKind(StationKind k) const {
  const auto all = stations_.ofKind(k);
  return static_cast<std::size_t>(
      std::count_if(all.begin(), all.end(), [&](const Station* s) { return !taken(s->name); }));
}

}  // namespace fleet
