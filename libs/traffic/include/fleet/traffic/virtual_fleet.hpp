#pragma once

// A fleet of point robots that do exactly what the traffic layer releases to them, late at random:
// every edge takes its planned duration stretched by a random factor, now and then a robot stops
// for a while on an edge (a person in the aisle), and it dwells at each station. Tasks are drawn at
// random (pickup station, then drop-off station) and chained: a robot that finishes one takes the
// next at once (saturated, no trip home), so throughput measures the traffic layer, not the task
// supply. It checks what the traffic layer promises: robots never hold conflicting nodes, their
// centres never come closer than the roadmap's contact distance, nobody waits for ever.
//
// It is not the simulator: no kinematics beyond the edge durations, no sensors, no local avoidance.
// It answers "how good is the plan and its execution" in milliseconds per simulated minute, and is
// the reference the full-stack figures are compared with.

#include <array>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "fleet/core/robot_activity.hpp"
#include "fleet/traffic/roadmap.hpp"
#include "fleet/traffic/traffic_control.hpp"
#include "fleet/traffic/wait_cause.hpp"

namespace fleet::traffic {

enum class Admission { None, Slots, Arrival };

/// A transport task of the virtual fleet: its pickup's and its drop-off's dock nodes.
struct VirtualTask {
  NodeId pickup = kNoNode;
  NodeId dropoff = kNoNode;
};

struct VirtualFleetOptions {
  std::size_t robots = 20;
  std::uint64_t seed = 1;
  double duration = 600.0;   ///< s simulated
  double dt = 0.1;           ///< s between traffic updates
  double dwell = 2.0;        ///< s at the pickup and again at the drop-off
  double jitter = 0.2;       ///< every edge takes its duration × U(1, 1 + jitter)
  double stopChance = 0.01;  ///< per edge: the robot stops on it for U(0, stopMax) s
  double stopMax = 10.0;
  /// The robots' turns on the spot take this times the roadmap's turn time (extraTurn); the plans
  /// are unchanged. 1: the robot; 0: one that turns at once — what turning costs the fleet.
  double turnScale = 1.0;
  bool stationLines = true;  ///< robots wait in line at the stations' queue nodes (TrafficControl)
  /// How tasks are admitted. Slots: a task is given only when its pickup and its drop-off each
  /// have a free place in their line (dock and queue places; `stationSlots` places instead when
  /// above 0, a fixed cap), the lines' places scaled by the admission governor as in the fleet
  /// manager (fleet/core/admission_governor.hpp); a robot counts at its pickup until it has loaded and at
  /// its drop-off for the whole task. Arrival: each place is taken from the robot's predicted arrival until
  /// it is served (StationBook). A robot with no admissible task drives to the nearest parking place no robot
  /// is sent to and asks again every second. None: every task at once.
  Admission admission = Admission::Slots;
  std::size_t stationSlots = 0;
  /// Tasks only between these pickups and drop-offs (by name); empty: all of them.
  std::vector<std::string> stations;
  /// A task list to run instead of drawn tasks: each robot that asks takes the next one, whatever
  /// the admission, and the run ends when the last one is done (VirtualFleetResult::duration is then
  /// the time that took). One robot on a fleet's drawn list is that list's lone robot as it drives
  /// here (the same jitter, people and turns), against the fleet bound's ideal motion.
  std::vector<VirtualTask> list;
  /// s of simulated time between recorded frames (VirtualFleetResult::frames); 0: none.
  double recordEvery = 0.0;
  /// s over which each station's queue is averaged for its series (StationLedger::queueSeries).
  double queueSeriesEvery = 10.0;
  TrafficOptions traffic;
};

/// One robot in a recorded frame.
struct RobotFrame {
  Vec2 position;
  NodeId target = kNoNode;  ///< its task's station dock (kNoNode: none)
  int phase = 0;            ///< 0 to the pickup, 1 to the drop-off
  bool dwelling = false;
  std::vector<NodeId> base;     ///< released: it may drive these
  std::vector<NodeId> horizon;  ///< planned after the base
};

struct FleetFrame {
  double time = 0.0;
  std::size_t tasksDone = 0;
  std::vector<RobotFrame> robots;
};

struct VirtualFleetResult {
  std::size_t robots = 0;
  double duration = 0.0;
  std::size_t tasksDone = 0;
  double tasksPerHour = 0.0;
  double meanTaskTime = 0.0;       ///< s from taking a task to leaving its drop-off
  double minSeparation = 0.0;      ///< m between two robot centres, over the whole run
  std::size_t contacts = 0;        ///< ticks with two centres closer than the roadmap's contact distance
  std::size_t holdViolations = 0;  ///< ticks with two robots holding conflicting nodes
  /// Robots that drove off their station's line sideways while still in it (a line is one way: the
  /// robot loses its place, the next in line goes before it). The planner never plans it: 0.
  std::size_t lineLeaves = 0;
  double longestWait = 0.0;  ///< s the longest a robot with a task went without reaching a node
  /// Where and on whom that longest wait was, as it ended or at the end of the run: "robot 7 at
  /// node 312 (24.5, 7.5), D-3 queue, from 118.0 s, goal node 1071 (D-3), waiting on 3@1070".
  std::string longestWaitAt;
  std::uint64_t plannerSteps = 0;
  std::uint64_t replans = 0;
  std::uint64_t refusedReports = 0;
  std::uint64_t evasions = 0;     ///< robots sent out of another's way (TrafficStats)
  std::uint64_t detours = 0;      ///< detour tables the planner computed (PibtStats)
  std::uint64_t escalations = 0;  ///< agents the planner escalated out of a wait cycle
  std::uint64_t untangles = 0;    ///< knots the planner searched a way out of
  std::uint64_t passes = 0;       ///< robots let past late ones (TrafficStats)
  /// The timed core (PlannerCore::Sipp): robots planned before one whose way they stood on, robots
  /// sent to a refuge off it, and moves the execution refused (0: the plans are conflict-free).
  std::uint64_t yields = 0;
  std::uint64_t refuges = 0;
  std::uint64_t refusedMoves = 0;
  /// The timed core's single-robot searches: how many, how many found no way, states expanded and
  /// goals' driving-time tables computed.
  SippStats search;
  /// The admission governor's factor on the lines' places at the end (admission by slots; 1: none).
  double lineScale = 1.0;
  BaseEnds baseEnds;         ///< the robots' base ends reached short of their target, summed
  double updateP50Ms = 0.0;  ///< wall time of one traffic update (planning and releases)
  double updateP99Ms = 0.0;
  double density = 0.0;  ///< robots ÷ roadmap nodes
  /// Where the robots' time went, fractions of robot-time summing to 1: driving an edge, dwelling at
  /// a station, standing with planned nodes not released yet (waiting on other robots' progress),
  /// and standing with nothing planned ahead (the plan keeps it there, or it has arrived).
  double driving = 0.0;
  double dwelling = 0.0;
  double waitingOnOthers = 0.0;
  double standingPlanned = 0.0;
  /// Each robot's time in the nine ledger categories (fleet/core/robot_activity.hpp), classified per
  /// tick: dwelling at a station; no task (no admissible one: the station cap); held by a person
  /// (a random stop on an edge); turning and docking (an edge's turn time, and edges into or out of
  /// a station's dock or approach node); driving (any other edge); waiting on another robot
  /// (standing with a task, whether nodes ahead are not released yet or the plan keeps it there).
  /// Charging, faulted and held by safety do not happen here. Each adds up to `duration`.
  std::vector<ActivityLedger> robotTime;
  /// The tasks in the order they were drawn (the list the fleet bound is computed on), and where
  /// each robot started.
  using DrawnTask = VirtualTask;
  std::vector<DrawnTask> tasks;
  std::vector<NodeId> starts;
  /// Robots waiting longer than a minute at the end: where, for what, behind whom.
  std::vector<std::string> stalls;
  std::vector<FleetFrame> frames;  ///< when VirtualFleetOptions::recordEvery > 0
  /// The station ledger: per visited pickup and drop-off, its dock arrivals and its dock cycle —
  /// from one arrival to the next, counted when the next robot was in line as the last one left —
  /// its utilisation (time some robot stood on the dock ÷ the run, whatever that robot's goal) and
  /// its queue (robots whose goal is the dock and that do not stand on it: mean over the run and
  /// most at once), as a load test's ledger counts them.
  struct StationLedger {
    std::string name;
    std::size_t visits = 0;
    std::size_t cycles = 0;
    double cycleP50 = 0.0;  ///< s
    double cycleP90 = 0.0;
    double utilisation = 0.0;
    double queueMean = 0.0;
    std::size_t queueMax = 0;
    /// The queue over the run: its mean over each `seriesEvery` s, in order (the last one over
    /// what was left of the run, when that is shorter).
    std::vector<double> queueSeries;
    double seriesEvery = 0.0;
  };
  std::vector<StationLedger> stations;
  /// Where the robots waited on other robots: the "waiting on another robot" of `robotTime`, split
  /// by the place each robot stood (waitPlaces), most first; adds up to the fleet's waiting time.
  struct WaitPlace {
    std::string place;
    double seconds = 0.0;  ///< robot-seconds
  };
  std::vector<WaitPlace> waits;
  /// The same waiting split by what the robot waited on did (wait_cause.hpp), in kWaitCauses'
  /// order: robot-seconds, adding up to the fleet's waiting time.
  std::array<double, kWaitCauses.size()> waitCauses{};
  /// Driving per task (docs/algorithms.md, "Driving per task"), summed over the tasks done and those
  /// under way at the end: the seconds their robots drove (turns and docking included, stops for
  /// people not); the free-flow seconds of the way they made (from where the robot was when it took
  /// the task to the pickup, then on to the drop-off, nobody in the way: StationBook::travel; for a
  /// task under way, that less the free flow still left); the part of the driving on edges that
  /// brought the robot no nearer its goal (pushed aside, evading, going round); and the tasks they
  /// add up to (1 for each done, the share of its free flow made for each under way).
  double taskDriven = 0.0;
  double taskFreeFlow = 0.0;
  double taskDrivenAway = 0.0;
  double taskShare = 0.0;
};

/// Per node, the place a robot standing there is at, as the wait ledger names it: "<station> dock",
/// "<station> approach", "<station> queue", "<station> exit" for a pickup's, drop-off's or charger's
/// nodes, "parking", and lane nodes "lane by <station>" within `near` m of the nearest pickup or
/// drop-off dock, otherwise "lane".
std::vector<std::string> waitPlaces(const Roadmap& roadmap, double near = 2.0);

/// A robot's wait as VirtualFleetResult::longestWaitAt gives it: where (node, position and its
/// place in `places`), since when, its goal (and the station docked there) and whom it waits on
/// (robot and the node it stands on; none: its own plan keeps it there).
std::string describeWait(const Roadmap& roadmap, const std::vector<std::string>& places, std::size_t robot,
                         NodeId at, double from, NodeId goal,
                         std::span<const std::pair<std::size_t, NodeId>> on);

/// Runs the virtual fleet on `roadmap`. Robots start on the parking docks (then on spread-out lane
/// nodes if there are more robots than parking places). Throws std::invalid_argument when the
/// roadmap has no pickup or no drop-off station or the robots do not fit.
VirtualFleetResult runVirtualFleet(Roadmap& roadmap, const VirtualFleetOptions& options);

std::string formatResult(const VirtualFleetResult& r);

}  // namespace fleet::traffic
