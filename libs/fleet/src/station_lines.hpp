#pragma once

// The stations' lines as the dispatcher books them (docs/algorithms.md, "Admission by predicted
// arrival", "Assignment: expected queue wait"): per station, the predicted arrivals of the robots
// bound for it, the motion part of its dock cycle and its places. Admission by predicted arrival
// asks a line for a place; assignment asks how long a robot would wait in a task's two lines. The
// line's arithmetic is fleet/core/station_slots.hpp.

#include <cmath>
#include <cstddef>
#include <functional>
#include <string>
#include <unordered_map>
#include <utility>
#include <vector>

#include "fleet/core/clock.hpp"
#include "fleet/core/station_slots.hpp"
#include "fleet/fleet/dispatcher.hpp"

namespace fleet {

class StationLines {
 public:
  struct Line {
    std::vector<double> arrivals;  ///< s from now
    double move = 0.0;             ///< s of the dock cycle without the dwell
    std::size_t slots = 0;         ///< 0: no limit
  };

  StationLines(const StationTimes& times, std::function<std::size_t(const std::string&)> capacity)
      : times_(times), capacity_(std::move(capacity)) {}

  /// The line of station `s`, made (empty) on first use.
  Line& line(const std::string& s);

  /// Seconds a robot `toPickup` s from transport task `t`'s pickup would wait in its two lines: at
  /// the pickup behind the robots booked there before it, then at the drop-off behind those booked
  /// before it gets there (served first come, first served; each for the station's dock motion and
  /// the task's dwell). 0 when it cannot get there at all (the travel says so).
  [[nodiscard]] double expectedWait(const Task& t, double toPickup) {
    if (!std::isfinite(toPickup)) {
      return 0.0;
    }
    const Line& p = line(t.pickup);
    const SlotOffer atPickup = offerSlot(p.arrivals, toPickup, p.move + nsToSec(t.loadNs), 0);
    const double between = times_.between(t.pickup, t.dropoff);
    if (!std::isfinite(between)) {
      return atPickup.wait;
    }
    const Line& d = line(t.dropoff);
    return atPickup.wait +
           offerSlot(d.arrivals, atPickup.leave + between, d.move + nsToSec(t.unloadNs), 0).wait;
  }

 private:
  const StationTimes& times_;
  std::function<std::size_t(const std::string&)> capacity_;
  std::unordered_map<std::string, Line> lines_;
};

}  // namespace fleet
