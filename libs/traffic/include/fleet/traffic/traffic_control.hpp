#pragma once

// The traffic layer in one object, free of DDS: the lifelong planner (Pibt) plans every robot's
// moves a few steps ahead of the fleet, the plan is executed by dependencies (Execution), and each
// robot is released its route a few nodes at a time. A traffic manager service wraps it; the virtual
// fleet (virtual_fleet.hpp) drives it in tests and benchmarks.
//
// Planning runs ahead of the robots: a step is added while a robot on its way has fewer than two
// nodes planned past its last report. The plan is kept in time: each robot decides its next move
// when the plan has it at the end of its last one (edge and turn at their real durations), so a
// robot with long edges does not fall behind a plan that moved everyone one edge per step. A robot
// that falls `maxLag` edges' time behind the plan (a person in the aisle, a slow dock) holds back
// only the robots that depend on it;
// the unreleased plan is then dropped and planned again from where everyone's release ends, so the
// fleet does not keep planning around where the late robot was supposed to be. Held robots (docking,
// faulted, paused, a vendor's vehicle that does not follow) are obstacles the plan goes around.
//
// The planner is one of two cores (TrafficOptions::core): the timed core (the default since
// 2026-12-06) — every robot's timed path by windowed prioritized planning over safe intervals
// (prioritized_planner.hpp), planned again from where the releases end and appended to the same
// execution (traffic_control_timed.cpp) — or PIBT as above.

#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "fleet/traffic/execution.hpp"
#include "fleet/traffic/graph.hpp"
#include "fleet/traffic/pibt.hpp"
#include "fleet/traffic/prioritized_planner.hpp"

namespace fleet::traffic {

/// The planner at the traffic layer's core.
enum class PlannerCore : std::uint8_t {
  /// Lifelong PIBT one step at a time (pibt.hpp), kept in time by the plan's clock, with the
  /// evasions, detours, untangling and escalation that keep it moving on a roadmap.
  Pibt,
  /// Windowed prioritized planning over safe intervals (prioritized_planner.hpp): every robot's
  /// timed path from where its release ends, planned again every `TrafficOptions::replanEvery` s
  /// (and when a robot runs short), appended to the execution in time order.
  Sipp,
};
const char* toString(PlannerCore c);
/// "pibt" or "sipp"; nullopt for anything else.
std::optional<PlannerCore> plannerCoreFrom(std::string_view name);

struct TrafficOptions {
  PlannerCore core = PlannerCore::Sipp;
  /// The timed core (PlannerCore::Sipp): its window and searches, how often it plans again (s of
  /// the traffic layer's clock), and the clock's step per update() when setNow() is not called.
  PrioritizedOptions prioritized{};
  double replanEvery = 2.0;
  double replanAtLeast = 1.0;
  double tick = 0.1;
  /// A robot may be behind the plan by this many lattice edges' time (0.7 s each) before the
  /// unreleased plan is dropped and planned again.
  std::int64_t maxLag = 24;
  /// Planner steps per update() at most: a step of the timed plan moves only the robots due then,
  /// so the plan's clock advances by ~timedQuantum a step (8 a 0.1 s update keeps it ahead of the
  /// robots; at 300 robots 64 let it run minutes ahead, re-planning all the while).
  std::int64_t maxStepsPerUpdate = 16;
  /// Turns the planner's heading-table searches may relax per update(), spread over its steps:
  /// it replaces pibt.headingWorkPerStep with this ÷ maxStepsPerUpdate. 100,000 turns took up to
  /// ~4 ms on the site for 100 (docs/benchmarks.md, "Heading tables").
  std::size_t headingWorkPerUpdate = 100000;
  /// A robot planned to stand this many steps in a row stops asking for steps at once; while only
  /// such robots want planning, one step is planned every `standingEvery` updates.
  int standingSteps = 2;
  int standingEvery = 5;
  /// A robot planned to stand still this many of its decisions short of its goal makes the robots
  /// standing in its way (on nodes its next few nodes exclude) drive away for `evadeSeconds` of plan
  /// time (PIBT moves robots one step at a time; a robot whose footprint reaches past the next node
  /// cannot clear the way in one step, so a dock exit or a queue behind a waiting robot would stay
  /// shut). 3 s: about the ten steps an evasion lasted when every step moved every robot one edge
  /// at once; 7 s (ten lattice edges at 0.7 s) kept the robot sent away too long for the one that
  /// stood behind it (TrafficControl.ARobotParkedAcrossTheLaneMakesRoomForTwoStandingInFront).
  int evadeAfter = 6;
  double evadeSeconds = 3.0;
  int evadeLookahead = 3;
  ReleaseOptions release;
  /// Switchable dependencies: a robot whose next node waits on a robot at least this many route
  /// nodes short of the conflict goes first there when that keeps the execution free of deadlock
  /// (Execution::letPass); 0: the plan's order always holds.
  std::int64_t letPassBehind = 1;
  /// Detours on: on a roadmap robots wait in line at stations and stand at docks, and an agent
  /// whose shortest way passes one would otherwise wait beside a free way round (docs/algorithms.md).
  /// Moves into what a standing robot excludes cost 1 s more (PibtOptions::occupiedCost): the
  /// virtual fleet did 106.5 → 121.8 tasks at 100 robots on the site for 100 and 64.1 → 74.5 at
  /// 20 with every robot working (docs/benchmarks.md, "Pushing priced").
  PibtOptions pibt{.detourAfter = 4, .occupiedCost = 1.0F};
  /// The plan is kept in time: each robot decides its next move when the plan has it at the end of
  /// its last one (the edge's duration plus `turnTime`), a robot planned to stand again `timedWait`
  /// s later; robots due within `timedQuantum` s of the earliest decide together, the others are
  /// left driving (docs/algorithms.md, "A plan kept in time").
  double timedQuantum = 0.1;
  double timedWait = 0.5;
  /// s of turning on the spot at `at` between `prev` and `next` beyond the edge's duration
  /// (Roadmap::extraTurn), for the timed plan; empty: none.
  std::function<double(NodeId prev, NodeId at, NodeId next)> turnTime{};
};

/// A station robots dock at one at a time: its dock node and the nodes to wait on in line,
/// nearest to the station first, and the approach node between the queue and the dock (kNoNode:
/// none).
struct StationLine {
  NodeId dock = kNoNode;
  std::vector<NodeId> queue;
  NodeId approach = kNoNode;
};

class Roadmap;

/// The lines of a roadmap's pickup, drop-off and charging stations (their dock, queue and approach
/// nodes); parking places take no line: a robot parks where it is sent and leaves when it is needed.
std::vector<StationLine> stationLines(const Roadmap& roadmap);

struct TrafficStats {
  std::uint64_t steps = 0;    ///< planner steps
  std::uint64_t replans = 0;  ///< unreleased plan dropped and planned again
  std::uint64_t refusedReports = 0;
  std::uint64_t evasions = 0;  ///< robots sent out of another's way
  std::uint64_t passes = 0;    ///< robots let past late ones (switched dependencies)
  /// Timed plans the execution refused a move of (PlannerCore::Sipp; the plan is conflict-free by
  /// construction, so this stays 0).
  std::uint64_t refusedMoves = 0;
};

/// Times a robot reported the last node of its base short of where it was being taken, by why the
/// base ended there (Execution::baseCut). `held`: a dependency (a robot planned before it there
/// had not left): a stop the plan asks for. `planEnd`: the planner had not planned it further.
/// `limit`: more was free to release, the robot got there before a longer base reached it (release
/// latency): what a robot on time should never see.
struct BaseEnds {
  std::uint64_t held = 0;
  std::uint64_t planEnd = 0;
  std::uint64_t limit = 0;
  [[nodiscard]] std::uint64_t total() const { return held + planEnd + limit; }
  BaseEnds& operator+=(const BaseEnds& o) {
    held += o.held;
    planEnd += o.planEnd;
    limit += o.limit;
    return *this;
  }
};

class TrafficControl {
 public:
  /// Robots start on `starts` (valid, free of conflicts: std::invalid_argument otherwise).
  TrafficControl(const Graph& graph, std::span<const NodeId> starts, TrafficOptions options = {});

  [[nodiscard]] std::size_t robots() const { return goal_.size(); }
  /// A robot joins on `start` (refused with PlanStepError when another robot holds or is released a
  /// node conflicting with it: try again when it has moved on). Returns its index.
  std::size_t addRobot(NodeId start);

  /// kNoNode: none (the robot stays where it is unless someone needs the place). Refused (false)
  /// for a node off the graph or closed.
  bool setGoal(std::size_t robot, NodeId goal, int priority = 0);
  [[nodiscard]] NodeId goal(std::size_t robot) const { return goal_.at(robot); }
  /// Where the planner is taking it now: its goal, its place in a station's line or where it is
  /// sent out of another robot's way.
  [[nodiscard]] NodeId target(std::size_t robot) const { return target_.at(robot); }
  /// Stations whose dock takes one robot at a time. A robot whose goal is such a dock joins its
  /// line: the first in line is planned to the dock, the next ones to the queue nodes in order (the
  /// last queue node for everyone beyond), so robots wait in line instead of crowding the dock's
  /// only way in and out. The line moves up when the robot at the dock gets another goal. Robots
  /// already standing in the queue (or on the approach or the dock) keep the order they stand in
  /// and go before those still on their way: the queue is one way, so a robot that joined the line
  /// earlier but arrives later could never get past them.
  void setStations(std::vector<StationLine> stations);
  /// Robots in line for the station whose dock is `dock`, the one at the dock first.
  [[nodiscard]] std::vector<std::size_t> line(NodeId dock) const;

  /// A held robot stands where it is and is planned around (docking, faulted, paused, manual).
  void setHeld(std::size_t robot, bool held);
  /// The robot stands at its last reported node and will not drive on (held there by a person for
  /// long): what was released beyond that node is taken back and it is planned from there, so it
  /// can be sent another way (the traffic manager's yielding). Its agent must get the shorter
  /// release before the person lets it go on.
  void retractStanding(std::size_t robot);
  [[nodiscard]] bool held(std::size_t robot) const { return held_.at(robot) != 0; }

  /// The robot reports it has arrived at `node`; refused reports leave it held where it was.
  Report reached(std::size_t robot, NodeId node);
  /// Last node the robot reported, and whether that is its goal.
  [[nodiscard]] NodeId at(std::size_t robot) const { return execution_.at(robot); }
  [[nodiscard]] bool arrived(std::size_t robot) const;

  /// Plans as far ahead as the options say (re-planning first if a robot fell too far behind).
  /// Returns the number of steps planned.
  int update();
  /// The traffic layer's clock (s), for the timed core's plans; without it each update() is
  /// `TrafficOptions::tick` s.
  void setNow(double seconds) {
    now_ = seconds;
    nowGiven_ = true;
  }
  /// What the robot may drive now and what it may expect after that.
  Release release(std::size_t robot) { return execution_.release(robot); }
  [[nodiscard]] std::vector<std::size_t> waitingOn(std::size_t robot) const {
    return execution_.waitingOn(robot);
  }

  /// One line on where the robot is and what holds it: its node, goal and target, whether it is
  /// held, how far it is planned and released, the robots it waits on (index@node), and each way
  /// out of its node with the robots whose node excludes it ("[33 held]": one held there, which the
  /// plan goes round rather than pushes). For reports of robots that do not move.
  [[nodiscard]] std::string explain(std::size_t robot) const;

  /// Call after closing or reopening nodes or edges: drops the planner's distances and plans again
  /// from the released ends.
  void graphChanged();
  /// A standing cost (s) of driving into each node: the collision-probability map's weight on the
  /// plan, and a yield's. The PIBT core routes by it (Pibt::setNodeCost); the timed core plans it
  /// as time (Sipp::setNodeCost). Plans already released stand; new steps route by it.
  void setNodeCost(std::vector<float> cost);
  /// The running core's node costs (empty: none).
  [[nodiscard]] std::span<const float> nodeCost() const;

  [[nodiscard]] const TrafficStats& stats() const { return stats_; }
  /// s of plan time of the newest planned step.
  [[nodiscard]] double planClock() const { return clock_; }
  [[nodiscard]] const BaseEnds& baseEnds(std::size_t robot) const { return baseEnds_.at(robot); }
  [[nodiscard]] const PibtStats& plannerStats() const { return planner_->stats(); }
  [[nodiscard]] const Execution& execution() const { return execution_; }
  [[nodiscard]] const Pibt& planner() const { return *planner_; }
  /// The timed core's statistics (PlannerCore::Sipp; zero otherwise).
  [[nodiscard]] const PrioritizedStats& timedStats() const { return timed_.stats(); }
  /// The timed core's single-robot searches (their count, states expanded, failures, goal tables).
  [[nodiscard]] const SippStats& searchStats() const { return timed_.searchStats(); }

 private:
  /// A robot leaving a dock goes before every task priority a WMS sends (small integers).
  static constexpr int kLeavingBoost = 1 << 20;
  void replan();
  void leaveLine(std::size_t robot);
  void updateLine(std::size_t station);
  void orderLine(std::size_t station);
  void plannerGoal(std::size_t robot, NodeId goal);
  void plannerPriority(std::size_t robot);
  void afterStep();
  void freeDocks();
  void clearWayFor(std::size_t robot);
  enum class Need : std::uint8_t { None, Later, Now };
  [[nodiscard]] Need needsPlanning() const;
  /// Where the robot stands for the lines: the planner's position (PIBT) or its last report.
  [[nodiscard]] NodeId standing(std::size_t robot) const;
  [[nodiscard]] bool leavingDock(std::size_t robot) const;
  // The timed core (traffic_control_timed.cpp).
  int updateTimed();
  /// Robots waiting on late ones go first where that keeps the execution free of deadlock.
  void letLatePass();
  int planTimed();

  const Graph& graph_;
  TrafficOptions options_;
  std::unique_ptr<Pibt> planner_;
  Execution execution_;
  std::vector<NodeId> goal_;
  std::vector<std::uint8_t> held_;
  std::vector<int> priority_;
  std::vector<StationLine> stations_;
  std::vector<std::vector<std::size_t>> lines_;  ///< per station, robots in line
  std::vector<std::int64_t> leaving_;            ///< per station: robot still on its dock after its turn, -1
  std::vector<std::size_t> firstClear_;          ///< per station: first queue node clear of the dock's ways
  std::vector<std::int32_t> stationOfDock_;      ///< per node: station index, -1
  std::vector<std::int32_t> inLine_;             ///< per robot: station index, -1
  std::vector<NodeId> target_;                   ///< per robot: the planner's goal (line place, evasion)
  std::vector<int> stall_;                       ///< planned steps standing short of its target
  std::vector<NodeId> lastEnd_;                  ///< planned end after the previous step
  std::vector<std::int64_t> evadeUntil_;         ///< step its evasion ends, -1
  std::vector<BaseEnds> baseEnds_;
  TrafficStats stats_;
  int sinceStep_ = 0;  ///< update() calls since the last planned step
  // The plan kept in time.
  void beforeTimedStep();
  void afterTimedStep();
  void forgetStepTimes(std::int64_t before);
  [[nodiscard]] bool lagging(std::int64_t oldest) const;
  [[nodiscard]] std::int64_t evadeClock() const;
  std::vector<double> ready_;       ///< per robot: plan time of its next decision
  std::vector<std::uint8_t> busy_;  ///< per robot: still driving in the plan this step
  std::vector<double> stepTime_;    ///< plan time of plan steps stepTimeFirst_, stepTimeFirst_ + 1, ...
  std::int64_t stepTimeFirst_ = 0;
  std::vector<NodeId> before_;  ///< the planner's positions before a step (kept: no allocation a step)
  std::vector<NodeId> came_;    ///< per robot: the node before its planned end (kNoNode: none)
  double clock_ = 0.0;
  // The timed core.
  PrioritizedPlanner timed_;
  double now_ = 0.0;
  bool nowGiven_ = false;
  double lastTimedPlan_ = -1e18;
  std::vector<double> lastGoalAt_;  ///< per robot: when it last reached its target
};

}  // namespace fleet::traffic
