#pragma once

#include <functional>
#include <map>
#include <set>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "fleet/fleet/allocator.hpp"
#include "fleet/fleet/station_map.hpp"

namespace fleet {

/// The kind of station a charge (Charging) or park (Parking) task goes to.
StationKind targetKind(TaskKind k);
/// A charge or park task that names no station: the dispatcher chooses one when it assigns it.
bool needsStation(const Task& t);

/// The station a charge or park task without one is given when it is assigned: among the stations
/// of its kind that no active task targets ("free"), the one the robot reaches soonest, preferring
/// those no other robot stands on (a robot parked there would block the newcomer). Built once per
/// allocation; every station chosen in it is taken at once, so two tasks never get the same one.
class StationChooser {
 public:
  /// `targeted`: stations that active tasks go to. `robots`: every robot, for who stands where
  /// (a lost robot stands nowhere); a robot within `standReach` (m) of a station stands on it.
  StationChooser(const StationMap& stations, std::set<std::string, std::less<>> targeted,
                 std::span<const RobotInfo> robots, double standReach);

  /// A task's candidates with their travel functions, built once per task (not per robot).
  /// Move-only: a travel function may refer to its task in `tasks` (perPair does), whose address a
  /// move keeps and a copy would not.
  struct Options {
    std::vector<const Station*> stations;
    std::vector<Task> tasks;  ///< the task with each candidate as its station
    std::vector<RobotTravel> travel;

    Options() = default;
    Options(Options&&) = default;
    Options& operator=(Options&&) = default;
    Options(const Options&) = delete;
    Options& operator=(const Options&) = delete;
    ~Options() = default;
  };
  /// The free stations of the task's kind (travel of each from `travel`, the task with that station).
  [[nodiscard]] Options options(const Task& t, const TravelModel& travel) const;

  struct Pick {
    const Station* station = nullptr;  ///< null: no free station the robot can reach
    double travelS = kInfeasible;
    bool blocked = false;  ///< another robot stands on it (chosen only when every free one is)
  };
  /// The best station among `o` still free for robot `r`.
  [[nodiscard]] Pick best(const Options& o, const RobotInfo& r) const;

  void take(std::string_view station) { taken_.emplace(station); }
  [[nodiscard]] bool taken(std::string_view station) const { return taken_.contains(station); }
  /// How many stations of kind `k` the site has, and how many of them are free.
  [[nodiscard]] std::size_t countOfKind(StationKind k) const;
  [[nodiscard]] std::size_t freeOfKind(StationKind k) const;

 private:
  [[nodiscard]] bool blockedFor(const Station& s, const RobotInfo& r) const;

  const StationMap& stations_;
  std::set<std::string, std::less<>> taken_;
  /// Station name -> ids of the robots standing on it.
  std::map<std::string, std::vector<std::string>, std::less<>> standing_;
};

}  // namespace fleet
