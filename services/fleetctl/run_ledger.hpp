#pragma once

// The robot-time and station ledgers of a run, from the robots' states step by step (the
// simulator's replay: pose, charging, the agent's mode, task and activity). Pure: no DDS, no I/O.
// - Robot time: every robot's time in the nine categories of fleet/core/robot_activity.hpp, filed
//   step by step under the state it had at the step's start, so each robot's adds up to its run
//   time. The agent's `activity` when it says one; when it does not (Unset: agents that predate the
//   field), derived from its mode and task (activityFromMode), a charging robot as charging.
// - Stations: a robot is docked at a station while its centre is within `dockTolerance` of the
//   station's pose. Per station: visits (dock arrivals), utilisation (time some robot is docked ÷
//   run time), queue length over time (robots whose current goal is that station and are not
//   docked there: the goal is the task's pickup until the robot has been docked there, then its
//   drop-off), and the dock cycle — from one robot's dock arrival to the next's, counted when the
//   next stood in the station's line as the first left (within `lineReach` of the dock: its queue
//   places and approach as the roadmap lays them out), so it is the station's own cycle as the
//   fleet bound's c_s is (station_cycle.hpp), not the next robot's drive from afar — and the
//   occupancy per visit. The virtual fleet counts its cycles the same way (virtual_fleet.cpp).
//   And the docking time per visit: from the robot's last step within `dockTolerance` of the
//   station's entry (the start of its last leg) to its arrival at the dock, against the roadmap's
//   time for that leg (a robot on timed releases docks within it + 2 s).

#include <cstddef>
#include <map>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "fleet/core/robot_activity.hpp"
#include "fleet/core/vec2.hpp"

namespace fleet::ctl {

struct LedgerStation {
  std::string name;
  Vec2 dock{};
  /// m from the dock within which a robot bound for the station stands in its line (the farthest
  /// of its queue places and approach, plus a tolerance); 0: wherever it is.
  double lineReach = 0.0;
  /// Where the last leg into the dock starts (its approach, or its queue's head for a station
  /// entered along a row) and the modelled time of the span the ledger times (from the last step
  /// within `dockTolerance` of the entry to the first within it of the dock: the leg less twice the
  /// tolerance, at cruise); without an entry no docking time is measured.
  bool hasEntry = false;
  Vec2 entry{};
  double dockModelS = 0.0;
};

struct LedgerTask {
  std::string pickup;
  std::string dropoff;
};

struct RobotSample {
  Vec2 position;
  bool charging = false;
  std::string mode;      ///< RobotMode's text name, as the replay has it
  std::string task;      ///< empty: none
  std::string activity;  ///< RobotActivity's text name; empty or "unset": not said
};

class RunLedger {
 public:
  RunLedger(std::vector<std::string> robots, std::vector<LedgerStation> stations,
            std::map<std::string, LedgerTask> tasks, double dockTolerance = 0.25, double seriesEveryS = 10.0);

  /// The robots' states at time `t` (s; one sample per robot, in the constructor's order; a step
  /// with another count, or a time not after the last, is skipped and counted).
  void step(double t, const std::vector<RobotSample>& robots);

  /// loadtest.json's "robot_time": categories, the fleet's shares, per robot seconds and shares,
  /// and where the categories came from ("activity", "mode" or both).
  [[nodiscard]] nlohmann::json robotTimeJson() const;
  /// loadtest.json's "stations": the visited stations, busiest (utilisation) first.
  [[nodiscard]] nlohmann::json stationsJson() const;
  [[nodiscard]] const ActivityLedger& robot(std::size_t i) const { return ledgers_.at(i); }
  [[nodiscard]] std::size_t skippedSteps() const { return skipped_; }

 private:
  struct StationAcc {
    std::size_t visits = 0;
    double dockedS = 0.0;
    double queueIntegral = 0.0;
    std::size_t queueMax = 0;
    double lastArrival = -1.0;
    bool nextQueued = false;  ///< someone was queued when the last robot left
    std::vector<double> cycles;
    std::vector<double> occupancy;
    std::vector<double> docking;      ///< s from leaving the entry to docked, per visit
    std::vector<std::size_t> series;  ///< queue length every seriesEveryS
  };
  struct RobotAcc {
    RobotActivity activity = RobotActivity::NoTask;
    int docked = -1;  ///< station index
    double dockedSince = 0.0;
    std::string task;
    bool pickedUp = false;
    int goal = -1;
    int atEntry = -1;  ///< station whose entry it was at last (-1: none since its last dock)
    double entryT = 0.0;
  };
  int stationAt(Vec2 p) const;
  int stationIndex(const std::string& name) const;

  std::vector<std::string> robots_;
  std::vector<LedgerStation> stations_;
  std::map<std::string, LedgerTask> tasks_;
  double tolerance_;
  double seriesEvery_;
  std::vector<ActivityLedger> ledgers_;
  std::vector<RobotAcc> state_;
  std::vector<StationAcc> acc_;
  double first_ = -1.0;
  double last_ = -1.0;
  double nextSeries_ = 0.0;
  std::size_t skipped_ = 0;
  std::size_t saidSteps_ = 0;
  std::size_t derivedSteps_ = 0;
};

/// The lines a run prints: the fleet's robot time and the busiest station.
std::vector<std::string> ledgerLines(const nlohmann::json& robotTime, const nlohmann::json& stations);

}  // namespace fleet::ctl
