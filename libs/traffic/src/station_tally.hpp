#pragma once

// The virtual fleet's station ledger (VirtualFleetResult::stations), counted as a load test's
// ledger counts it (docs/algorithms.md, "Robot-time and station ledgers"): per pickup and drop-off,
// its dock arrivals; its dock cycle, from one arrival to the next when the next robot stood in the
// station's line (a queue place or the approach) as the last one left (station_cycle.hpp's
// quantity); its utilisation (some robot stands on the dock, whatever its goal); its queue (robots
// whose goal is the dock and that do not stand on it), over the run and as a series of means.

#include <cstddef>
#include <cstdint>
#include <vector>

#include "fleet/traffic/graph.hpp"
#include "fleet/traffic/virtual_fleet.hpp"

namespace fleet::traffic {

class Roadmap;

class StationTally {
 public:
  /// The queue series takes one mean every `seriesEvery` s (at least a tick: the caller checks).
  StationTally(const Roadmap& roadmap, double seriesEvery);

  /// The nodes of the line of the station docked at `dock`: its queue places and its approach.
  [[nodiscard]] const std::vector<NodeId>& lineNodes(NodeId dock) const {
    return lineNodes_[static_cast<std::size_t>(dock)];
  }
  /// A robot leaves the dock `dock` after its dwell; `nextInLine`: another robot of the station's
  /// line stands on one of its line's nodes.
  void left(NodeId dock, bool nextInLine);
  /// A robot reached the dock `dock` at `now` to dwell there.
  void arrived(NodeId dock, double now);
  /// The tick from `now` to `now + dt`: robots stand on `standing` (a robot on no edge), and one
  /// robot is in the queue of each dock in `queued` (once per robot). A series mean closes at each
  /// multiple of seriesEvery the tick reaches.
  void tick(double now, double dt, const std::vector<NodeId>& standing, const std::vector<NodeId>& queued);
  /// The ledger of the visited stations, in the roadmap's order.
  [[nodiscard]] std::vector<VirtualFleetResult::StationLedger> ledger() const;

 private:
  const Roadmap& roadmap_;
  double every_;
  std::vector<std::vector<NodeId>> lineNodes_;
  std::vector<double> lastArrival_;
  std::vector<std::uint8_t> queuedAtLeave_;
  std::vector<std::size_t> visits_;
  std::vector<std::vector<double>> cycles_;
  std::vector<double> dockedS_, queueS_, bucketS_;
  std::vector<std::size_t> queueNow_, queueMax_;
  std::vector<std::uint8_t> dockedNow_;
  std::vector<std::vector<double>> series_;
  double ran_ = 0.0;
  double bucketRan_ = 0.0;
  double nextClose_ = 0.0;
};

}  // namespace fleet::traffic
