#pragma once

// The fleet bound of a run (docs/algorithms.md, "Fleet bound"): the most tasks per hour a fleet
// could do on a task list, min(robot bound, station bound).
// - Robot bound = robots × a lone robot's rate on the same list: every task posted at once and done
//   in posting order, each chained from the last stop of the one before (the first from the best
//   robot start), with ideal motion — the disc's shortest way on the free map at the cruise speed —
//   plus each stop's dwell (a transport task: load and unload).
// - Station bound = min over stations s of 3600 / (c_s × f_s): c_s the station's mean least dock
//   cycle over its visits (station_cycle.hpp, with each visit's dwell), f_s its visits per task.
// Computed from the site and the list alone (no simulation). Pure: no DDS, no logging.

#include <cstddef>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "fleet/core/expected.hpp"
#include "fleet/core/vec2.hpp"
#include "fleet/planning/occupancy_grid.hpp"
#include "fleet/traffic/station_cycle.hpp"

namespace fleet::ctl {

using traffic::DockGeometry;
using traffic::dockMoveSeconds;

struct BoundStation {
  std::string name;
  DockGeometry geometry;  ///< dock = the station's pose
};

/// One stop of a task: a station visited (empty: a wait where the robot stands) and its dwell.
struct ListStop {
  std::string station;
  double dwellS = 0.0;
};

/// One task of the list, in posting order: its stops in order (a transport task is its pickup with
/// the load time and its drop-off with the unload time; a multi-stop task, each of its steps).
struct ListTask {
  std::vector<ListStop> stops;
  static ListTask transport(std::string pickup, std::string dropoff, double loadS, double unloadS) {
    return {{{std::move(pickup), loadS}, {std::move(dropoff), unloadS}}};
  }
};

struct FleetBoundInput {
  std::vector<BoundStation> stations;
  std::vector<ListTask> tasks;  ///< posting order
  std::vector<Vec2> starts;     ///< the robots' start positions: robots = starts.size()
  double radius = 0.3;          ///< m: the robots' disc
  double cruise = 0.8;          ///< m/s
};

struct StationLoad {
  std::string name;
  std::size_t visits = 0;  ///< the list's stops there (a transport task: its pickup and drop-off)
  double share = 0.0;      ///< f_s = visits ÷ tasks
  double moveS = 0.0;      ///< the cycle's motion part
  double cycleS = 0.0;     ///< c_s = moveS + mean dwell of its visits
  double boundPerH = 0.0;  ///< 3600 ÷ (c_s × f_s); 0: none (a cycle of no time)
};

struct FleetBound {
  std::size_t robots = 0;
  std::size_t tasks = 0;
  double chainDriveM = 0.0;  ///< the lone robot's way through the list
  double chainS = 0.0;       ///< its time: way ÷ cruise + every dwell
  double lonePerH = 0.0;     ///< 3600 × tasks ÷ chainS
  double robotPerH = 0.0;    ///< robots × lonePerH
  double stationPerH = 0.0;  ///< the least station bound (the robot bound when no station bounds)
  std::string bindingStation;
  std::vector<StationLoad> stations;  ///< the visited ones, busiest (least bound) first
  [[nodiscard]] bool robotsBind() const { return robotPerH <= stationPerH; }
  [[nodiscard]] double perH() const { return robotsBind() ? robotPerH : stationPerH; }
};

/// Errors: "bad_input" (no robot, no task, a cruise ≤ 0, a negative dwell or radius, anything not
/// finite), "unknown_station" (a task names a station not given), and the way's own errors
/// ("unreachable", "no_room", "off_map") with the leg named. Never throws on bad input.
[[nodiscard]] Expected<FleetBound> fleetBound(const planning::OccupancyGrid& freeMap,
                                              const FleetBoundInput& in);

}  // namespace fleet::ctl

namespace fleet::traffic {
class Roadmap;
}

namespace fleet::ctl {

/// The stations as the bound takes them: the roadmap's dock, approach point, first queue place
/// and exit (what the traffic manager lays out from the site).
[[nodiscard]] std::vector<BoundStation> boundStations(const traffic::Roadmap& roadmap);

}  // namespace fleet::ctl
