#pragma once

// Travel times on the roadmap, for assigning tasks (docs/algorithms.md, "Traffic: assignment on the
// roadmap"). In reserved traffic a robot drives the roadmap's edges, so its time to a station is its
// route's: one-way aisles, turns on the spot and the dock's last leg included, which a straight line
// or the grid's shortest path does not know. One backward search per station at construction, so a
// query is a nearest-node lookup and a table read: the dispatcher asks robots × tasks of them a tick.
//
// The times are those of the way the planner routes (with flow guidance, RoadmapOptions::guidance,
// that can be longer than the shortest), free-flow (nobody in the way) and the roadmap as built: closures
// made at run time by the traffic manager are not seen here.

#include <cstddef>
#include <memory>
#include <optional>
#include <string>
#include <unordered_map>
#include <vector>

#include "fleet/core/vec2.hpp"
#include "fleet/traffic/roadmap.hpp"

namespace fleet::traffic {

class RoadmapTravel {
 public:
  explicit RoadmapTravel(std::shared_ptr<const Roadmap> roadmap);

  /// Seconds from `from` to station `name`'s dock: the straight leg to the nearest open node at
  /// cruise speed, then the roadmap. nullopt: no such station, or it has no dock (the robot's disc
  /// does not fit there); +infinity: no route.
  [[nodiscard]] std::optional<double> toStation(Vec2 from, const std::string& name) const;
  /// Seconds from roadmap node `from` to station `name`'s dock (nullopt and +infinity as above).
  [[nodiscard]] std::optional<double> fromNode(NodeId from, const std::string& name) const;
  /// Seconds from station `a`'s dock to station `b`'s (nullopt and +infinity as above).
  [[nodiscard]] std::optional<double> between(const std::string& a, const std::string& b) const;
  /// Robots the station's line holds at once: its dock and its queue nodes; 0 when it has no dock.
  [[nodiscard]] std::size_t lineCapacity(const std::string& name) const;
  /// Seconds of the station's least dock cycle without its dwell (station_cycle.hpp): enter from
  /// the queue head, leave; 0 when it has no dock.
  [[nodiscard]] double dockMoveSeconds(const std::string& name) const;

  [[nodiscard]] const Roadmap& roadmap() const { return *roadmap_; }

 private:
  struct StationTable {
    NodeId dock = kNoNode;
    std::size_t line = 0;
    double move = 0.0;
    std::vector<float> toDock;  ///< seconds from every node to the dock
  };
  [[nodiscard]] const StationTable* find(const std::string& name) const;

  std::shared_ptr<const Roadmap> roadmap_;
  std::unordered_map<std::string, StationTable> stations_;
};

}  // namespace fleet::traffic
