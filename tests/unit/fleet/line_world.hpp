#pragma once

// Stations on the x axis, for the dispatcher's tests of station lines (admission by predicted
// arrival, the expected queue wait): the roadmap's times are straight lines at 1 m/s, every dock
// cycle's motion 2 s, every dwell 2 s, and a robot's travel is its distance to the task's pickup. `map` must
// outlive what these return.

#include <cmath>
#include <string>
#include <utility>

#include "fleet/fleet/dispatcher.hpp"

namespace fleet::test {

/// A transport task with 2 s to load and 2 s to unload.
inline Task transportTask(std::string id, std::string pickup, std::string dropoff) {
  Task t;
  t.id = std::move(id);
  t.pickup = std::move(pickup);
  t.dropoff = std::move(dropoff);
  t.loadNs = 2'000'000'000;
  t.unloadNs = 2'000'000'000;
  return t;
}

inline StationTimes straightLineTimes(const StationMap& map) {
  const auto x = [&map](const std::string& name) { return map.find(name)->pose.x; };
  StationTimes times;
  times.toStation = [x](Vec2 from, const std::string& name) { return std::hypot(from.x - x(name), from.y); };
  times.between = [x](const std::string& a, const std::string& b) { return std::abs(x(a) - x(b)); };
  times.dockMove = [](const std::string&) { return 2.0; };
  return times;
}

inline TravelCost distanceToPickup(const StationMap& map) {
  return
      [&map](const RobotInfo& r, const Task& t) { return std::abs(r.pose.x - map.find(t.pickup)->pose.x); };
}

}  // namespace fleet::test
