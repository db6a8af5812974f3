// The wait ledger's place names (virtual_fleet.hpp, waitPlaces): a station's own nodes by their
// role, parking, and lane nodes by the nearest pickup or drop-off dock within reach; and a wait
// described by its place, its goal and whom it waits on (describeWait).

#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include "fleet/traffic/virtual_fleet.hpp"

namespace fleet::traffic {

std::vector<std::string> waitPlaces(const Roadmap& roadmap, double near) {
  const Graph& g = roadmap.graph;
  std::vector<std::string> out(g.size());
  std::vector<std::pair<Vec2, const std::string*>> docks;
  for (const auto& s : roadmap.stations) {
    if (s.dock == kNoNode)
      continue;
    const bool served = s.kind == site::StationKind::Pickup || s.kind == site::StationKind::Dropoff;
    if (served)
      docks.emplace_back(g.position(s.dock), &s.name);
    if (s.kind == site::StationKind::Parking) {
      out[static_cast<std::size_t>(s.dock)] = "parking";
      continue;
    }
    const auto label = [&](NodeId v, const char* what) {
      if (v != kNoNode && out[static_cast<std::size_t>(v)].empty())
        out[static_cast<std::size_t>(v)] = s.name + " " + what;
    };
    label(s.dock, "dock");
    label(s.approach, "approach");
    for (NodeId q : s.queue)
      label(q, "queue");
    label(s.exit, "exit");
  }
  for (NodeId v = 0; static_cast<std::size_t>(v) < g.size(); ++v) {
    auto& l = out[static_cast<std::size_t>(v)];
    if (!l.empty())
      continue;
    if (roadmap.kind(v) == NodeKind::Parking) {
      l = "parking";
      continue;
    }
    const std::string* best = nullptr;
    double bestD = near;
    for (const auto& [p, name] : docks) {
      if (const double d = (p - g.position(v)).norm(); d <= bestD) {
        bestD = d;
        best = name;
      }
    }
    l = best != nullptr ? "lane by " + *best : "lane";
  }
  return out;
}

std::string describeWait(const Roadmap& roadmap, const std::vector<std::string>& places, std::size_t robot,
                         NodeId at, double from, NodeId goal,
                         std::span<const std::pair<std::size_t, NodeId>> on) {
  std::ostringstream os;
  os.setf(std::ios::fixed);
  os.precision(1);
  const Vec2 p = roadmap.graph.position(at);
  os << "robot " << robot << " at node " << at << " (" << p.x << ", " << p.y << "), "
     << places[static_cast<std::size_t>(at)] << ", from " << from << " s, goal node " << goal;
  for (const auto& s : roadmap.stations) {
    if (goal != kNoNode && s.dock == goal)
      os << " (" << s.name << ")";
  }
  os << ", waiting on";
  for (const auto& [q, v] : on)
    os << " " << q << "@" << v;
  if (on.empty())
    os << " nobody named (its plan keeps it there)";
  return os.str();
}

}  // namespace fleet::traffic
