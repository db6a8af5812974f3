#pragma once

// The stations' lines over time, for admission by predicted arrival (docs/algorithms.md,
// "Admission by predicted arrival"; the line's arithmetic is fleet/core/station_slots.hpp). Each
// served station (pickup, drop-off) has a line of `slots` robots (its dock and queue places) and
// serves a robot in its least dock cycle (station_cycle.hpp, plus the dwell). Robots bound for a
// station are booked with their predicted arrival, in seconds from now on the roadmap's free-flow
// times (RoadmapTravel); the book is rebuilt from the robots' positions whenever the caller likes
// (every tick in the virtual fleet), so a robot that is late is booked later, not lost.

#include <cstddef>
#include <string>
#include <vector>

#include "fleet/core/station_slots.hpp"
#include "fleet/traffic/roadmap_travel.hpp"

namespace fleet::traffic {

class StationBook {
 public:
  /// `docks`: the stations served (their dock nodes). `slots` above 0 replaces every line's length.
  /// `roads` must outlive the book.
  StationBook(const RoadmapTravel& roads, const std::vector<NodeId>& docks, double dwell,
              std::size_t slots = 0);

  /// Free-flow seconds from node `from` to the dock (+infinity: no way).
  [[nodiscard]] double travel(NodeId from, NodeId dock) const;
  /// Seconds the station takes a robot: dwell + its least dock cycle's motion.
  [[nodiscard]] double cycle(NodeId dock) const { return at(dock).cycle; }
  [[nodiscard]] std::size_t slots(NodeId dock) const { return at(dock).slots; }

  void clear();
  /// Books a robot arriving at `dock` in `arrival` s (≤ 0: there now). Returns its booking number
  /// at that dock (for leave()).
  std::size_t book(NodeId dock, double arrival);
  /// Seconds from now until the robot booked as `booking` at `dock` leaves its line, served in
  /// arrival order.
  [[nodiscard]] double leave(NodeId dock, std::size_t booking) const;
  /// The slot a robot arriving in `arrival` s would get at `dock`.
  [[nodiscard]] SlotOffer offer(NodeId dock, double arrival) const;

 private:
  struct Line {
    std::string name;
    double cycle = 0.0;
    std::size_t slots = 0;
    std::vector<double> arrivals;  // booked, in booking order
  };
  [[nodiscard]] const Line& at(NodeId dock) const;
  Line& at(NodeId dock);

  const RoadmapTravel& roads_;
  std::vector<int> index_;  // by dock node: its line, -1: not served
  std::vector<Line> lines_;
};

}  // namespace fleet::traffic
