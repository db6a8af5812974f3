#pragma once

// One robot's stack without DDS: EKF localization (odometry, compass, landmark bearings), a global
// A* path on the inflated map, a path follower with the Lyapunov pose controller, a stop-and-yield
// safety rule on what the sensors see, and task execution (goals with dwell times).
//
// Standoffs between robots are broken by the robot with the larger id backing off and replanning
// (a robot driving home yields to one on an order; one right at the back of a waiting robot makes
// room whatever the ids); in a passage too narrow for two, it backs out along the way it came (seed
// 001's return path over its own trail) to the last place wide enough, and replans from there.
// Stations are entered and left straight along their axis (docs/algorithms.md, sixth round).
//
// The agent wires parts, each in its own file with its own tests: the Localizer (pose estimate,
// what the sensors see, sensor loss), the MotionGate (stop rule and cross-traffic check) and the
// ProgressWatch (no progress towards the goal, a stalled local planner) and the StandoffArbiter
// (what to do about a hold: the priority rule, yield, detour, fail). Task execution, planning and
// carrying out the arbiter's moves (backing out along the trail, backing off) are still here.
//
// With AgentParams::traffic "reserved" the traffic manager's releases are the route instead
// (onRelease, the ReleaseTracker): the robot drives the released nodes with the same local stack
// behind the same motion gate, stops at the end of what was released, reports each node it reaches
// (AgentOutput::traffic), and none of the conduct above runs (no standoff arbiter, back-offs,
// returns, detours or global planning): robots that follow their releases are kept apart by the
// traffic manager's plan, the gate stays for people and the unexpected.

#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "fleet/avoidance/dynamic_window.hpp"
#include "fleet/avoidance/local_planner.hpp"
#include "fleet/avoidance/risk_stepping.hpp"
#include "fleet/avoidance/safety_layer.hpp"
#include "fleet/control/cruise.hpp"
#include "fleet/control/path_follower.hpp"
#include "fleet/messages/messages.hpp"
#include "fleet/planning/lane_map.hpp"
#include "fleet/planning/occupancy_grid.hpp"
#include "fleet/risk/risk_lookup.hpp"
#include "localizer.hpp"
#include "motion_gate.hpp"
#include "other_robot.hpp"
#include "progress_watch.hpp"
#include "release_tracker.hpp"
#include "route_planner.hpp"
#include "standoff_arbiter.hpp"
#include "task_runner.hpp"

namespace fleet::agent {

/// DWA as the agent drives with it: the library's defaults but a 0.8 m carrot. With 1.5 m (Nav2's
/// order) the heading term cut the bend from the band into an aisle and put the robot at the shelf
/// corner, inside the stop rule's gap: the 20-robot scenario took 2173–2322 s for its 100 tasks with
/// 11–16 requeues, against 1613 s and 3 with 0.8 m (docs/benchmarks.md).
avoidance::DwaParams agentDwaDefaults();

struct AgentParams {
  std::string id;
  Pose2 start;
  double radius = 0.3;
  double wheelBase = 0.4;
  double vMax = 0.8;                                  // m/s cruise
  double wMax = 1.5;                                  // rad/s
  double stopGap = 0.35;                              // m of free space kept ahead at standstill
  double robotStopGap = control::kAgentRobotStopGap;  // the same to another robot, in reserved traffic
  double headway = 1.0;                               // s: the stop distance grows with speed
  double blockedBackoffS = 4.0;                       // standoff time before the larger id backs off
  double blockedFailS = 60.0;                         // a task held in a standoff this long fails
  /// One notion of "wants to progress and cannot" for every local planner (robot_agent --config,
  /// "progress"; docs/algorithms.md, "Progress watch").
  ProgressParams progress;
  /// Idle this long [s] away from its start pose (its parking place): drive back there, so a
  /// finished robot does not stay on a drop-off station or in a lane. A new order preempts the
  /// trip. Negative: stay where the last task ended.
  double returnHomeS = 5.0;
  /// No SensorFrame for this long (of the agent's clock): stop, report RM_FAULT, resume on frames.
  double sensorTimeoutS = 0.5;
  /// A* cell cost = step length × (1 + riskWeightGlobal · p): paths at most (1 + w)× the shortest.
  double riskWeightGlobal = 1.0;
  double predictionHorizonS = 3.0;
  double predictionDt = 0.5;
  std::vector<std::pair<std::int32_t, Vec2>> landmarks;
  /// The site's wall faces for the localizer's laser-line updates (shared; null: none).
  std::shared_ptr<const std::vector<estimation::MapSegment>> walls;
  bool lineUpdates = true;  ///< false: the localizer fuses no laser lines (config localization.lines)
  /// Any libs/avoidance planner name ("dwa", "vo", ...): that planner drives along the path, behind
  /// the safety layer; "follow": the Lyapunov path follower. Either way the follower's pose law
  /// docks on stations and the same stop rule and standoff handling apply.
  std::string localPlanner = "dwa";
  avoidance::DwaParams dwa = agentDwaDefaults();  ///< when localPlanner is "dwa" (from --config)
  /// When localPlanner is "risk_stepping" (from --config); "risk_stepping_weighted" forces the weighted rule.
  avoidance::RiskSteppingParams riskStepping;
  avoidance::SafetyParams safety;  ///< the safety layer behind every libs/avoidance planner
  control::VelocityLimits limits{0.8, -0.3, 1.5, 1.0, 3.0};
  /// Global planner on the inflated grid: "astar" (with the risk map as cell cost when one is
  /// received), "wavefront" (distance field from the goal, then descent) or "ompl" (Informed RRT*,
  /// 50 ms budget inside the agent's cycle). Replanning around blockers uses the same planner.
  std::string globalPlanner = "astar";
  /// One-way aisles of the map (shared by every agent of a process); null: plain A*. Set, it
  /// replaces the global planner.
  std::shared_ptr<const planning::LaneMap> lanes;
  /// The site's zones: cost layers every global path keeps to (one-way, speed limits as travel
  /// time; no-go zones are blocked in the maps given to the agent) and the speed limit at a point
  /// (m/s; +inf or empty: none), which the motion gate enforces.
  planning::CostLayers zoneLayers;
  std::function<double(Vec2)> speedLimit;
  /// "reactive": robots keep clear of each other by the standoff conduct (the default for now);
  /// "reserved": the route comes from the traffic manager's releases (see onRelease).
  std::string traffic = "reserved";
};

struct AgentOutput {
  msg::VelocityCommand command;
  msg::RobotState state;
  msg::PredictedDiscs discs;
  std::optional<msg::TaskStatus> status;  // on every task state change
  /// Reserved traffic only: on every node reached, on a change of goal, holding or blocked, and at
  /// least once a second.
  std::optional<msg::TrafficProgress> traffic;
  /// The people the robot sees, a few times a second (AgentNode, PeopleReport); never set by Agent.
  std::optional<msg::PeopleSeen> people;
};

class Agent {
 public:
  /// `grid` is the map inflated by the robot radius (where the centre may go); `raw` the map itself.
  Agent(AgentParams params, std::shared_ptr<const planning::OccupancyGrid> grid,
        std::shared_ptr<const planning::OccupancyGrid> raw);

  void onFrame(const msg::SensorFrame& f);
  /// Other robots' states: used to know who is blocking (the larger id yields).
  void onOtherRobot(const msg::RobotState& s);
  /// A new revision replaces the current order (an empty task id cancels).
  void onAssignment(const msg::TaskAssignment& a);
  /// An order for this robot that cannot be carried out (refused at the edge, or without goals):
  /// drops the current order and reports the task failed with `why`.
  void refuseAssignment(const msg::TaskAssignment& a, const std::string& why);
  /// Reserved traffic: the traffic manager's release for this robot (others, stale ones and ones
  /// that do not start at the node it last reported are ignored and counted). Reactive: ignored.
  void onRelease(const msg::TrafficRelease& r);
  /// The latest risk map (shared by every agent of the process): the local planner's risk term and
  /// the global planner's cell cost. Null: no risk information.
  void onRiskMap(std::shared_ptr<const risk::RiskLookup> risk) {
    route_.setRisk(risk);
    risk_ = std::move(risk);
  }
  AgentOutput step(std::int64_t nowNs, double dt);
  /// True while the sensor stream is considered lost (as of the last step).
  [[nodiscard]] bool sensorLost() const { return localizer_.lost(); }

  [[nodiscard]] Pose2 pose() const { return localizer_.pose(); }
  [[nodiscard]] const std::string& id() const { return p_.id; }
  [[nodiscard]] bool busy() const { return tasks_.busy(); }
  /// The current order is paused by the operator: the robot stands still with it.
  [[nodiscard]] bool paused() const { return tasks_.paused(); }
  /// Driving back to its parking place with no order (see AgentParams::returnHomeS).
  [[nodiscard]] bool homing() const { return tasks_.homing(); }
  [[nodiscard]] std::uint64_t framesRejected() const { return localizer_.rejected(); }
  [[nodiscard]] const LineStats& lineStats() const { return localizer_.lineStats(); }
  /// What the sensors saw as of the last reading (pose, scan, detections, people).
  [[nodiscard]] const Perception& perception() const { return localizer_.perception(); }
  /// Follows the traffic manager's releases (AgentParams::traffic "reserved").
  [[nodiscard]] bool reserved() const { return reserved_; }
  /// Releases taken and ignored (cumulative).
  [[nodiscard]] const ReleaseCounts& releases() const { return releases_.counts(); }
  /// The last roadmap node reached (-1 before any release).
  [[nodiscard]] std::int32_t trafficNode() const { return releases_.node(); }
  /// Reserved traffic: why the robot stands with a task (what last stopped it), and since when
  /// [ns] it has not got 0.1 m further; sinceNs < 0: it has nothing to do. For the operator's
  /// log: a robot that stands for minutes without reporting itself blocked has the traffic manager
  /// waiting on it, and only the robot knows why.
  struct Standing {
    std::string why;
    std::int64_t sinceNs = -1;
    std::optional<Vec2> next;  ///< the next base node, if one is released
    bool byObstacle = false;   ///< last held by a static obstacle (what a rejoin is for)
    bool homing = false;       ///< on its way home with no task
  };
  [[nodiscard]] const Standing& standingStill() const { return standing_; }

  /// What the robot did about being blocked (cumulative), for tests and the service's counters.
  struct Conduct {
    std::uint64_t standoffs = 0;     ///< times it stopped for something in its way (> 1 s)
    std::uint64_t mutualBlocks = 0;  ///< ... for a robot that was itself waiting (a wait cycle)
    std::uint64_t backoffs = 0;      ///< it yielded by backing off a little
    std::uint64_t returns = 0;       ///< it yielded by backing out of a narrow passage (return path)
    std::uint64_t detours = 0;       ///< plans around what blocked it
    /// Whoever drove kept the robot on one spot while nothing held it (the progress watch's stall)
    /// and it recovered: after a sampling planner's local minimum (turning in place at a corner) the
    /// path follower drove for a while; a stalled return ended; a stalled follower re-planned.
    std::uint64_t plannerRecoveries = 0;
    /// Reserved traffic: stuck off its node, it drove back onto it before going on.
    std::uint64_t rejoins = 0;
  };
  [[nodiscard]] const Conduct& conduct() const { return conduct_; }

 private:
  /// The task stack for one cycle (the body of step() while sensors are live).
  AgentOutput drive(std::int64_t nowNs, double dt);
  /// The localizer's stream watch; on loss and on recovery queues a TaskStatus with the reason and
  /// shifts the task's timers so the outage does not count as being blocked.
  bool sensorStreamLost(std::int64_t nowNs);
  /// Command, state and predicted discs for the chosen twist and mode.
  void report(AgentOutput& out, std::int64_t nowNs, double v, double w, msg::RobotMode mode);
  /// Idle and away from home for returnHomeS: start the trip home (an internal order, never reported).
  void maybeReturnHome(std::int64_t nowNs);
  /// Plans to the current goal; with `avoid`, the cells around that point count as blocked (a
  /// detour around whatever stands in the way).
  void startGoal(std::int64_t nowNs, std::optional<Vec2> avoid = std::nullopt);
  void finishTask(TaskStage final, const std::string& reason, std::int64_t nowNs);
  /// At a goal: dwell there for its duration, reporting loading/unloading.
  void enterDwell(std::int64_t nowNs);
  /// Something keeps the robot from moving: does what the standoff arbiter decides (after a while
  /// back off, then detour, then fail).
  void onStandoff(std::int64_t nowNs, bool byRobot, const std::string& blocker, double& v, double& w);
  /// What the motion gate looks at this cycle.
  [[nodiscard]] GateView gateView() const;
  /// The gate's stop rule (see MotionGate); keeps where it found the robot blocked (blockPoint_).
  double clearSpeed(double v, Blocker& blocker);
  /// Nothing within a short distance behind (backing off must not hit what it cannot see coming).
  [[nodiscard]] bool rearClear() const;
  /// After backing off or backing out: re-plan around what blocked the robot, else plainly.
  void endYield(std::int64_t nowNs);
  /// Free width of the map across direction `dir` at `p` [m] (up to 2 x 3 m).
  [[nodiscard]] double freeWidth(Vec2 p, Vec2 dir) const;
  /// Too narrow for another robot to pass this one.
  [[nodiscard]] bool narrow(Vec2 p, Vec2 dir) const;
  /// Yielding inside a narrow passage: plan the way back along the trail to the last point wide
  /// enough (seed 001's return path) and start following it. False when there is no such point.
  bool startReturn(std::int64_t nowNs);
  /// The follower's command, scaled to cruise and limited (shared by driving and returning).
  void followerTwist(const control::PathFollowerOutput& r, double& v, double& w) const;
  /// Stop rule and cross-traffic check on (v, w); true when the robot is held up.
  bool heldUp(double& v, double& w, Blocker& blocker);
  /// Reserved traffic: the task stack for one cycle (in place of the reactive phases).
  void followRelease(std::int64_t nowNs, double dt, double& v, double& w, msg::RobotMode& mode);
  /// Reserved traffic: the twist along the released base (none: stand still).
  void driveBase(std::int64_t nowNs, double dt, double& v, double& w, msg::RobotMode& mode);
  /// Reserved traffic: a leg towards the current goal begins (no plan: the releases are the route).
  void beginLeg(std::int64_t nowNs);
  /// Reserved traffic: where the robot is going (the task's goal; idle, its home), if anywhere.
  [[nodiscard]] std::optional<TaskGoal> trafficGoal() const;
  /// Reserved traffic: the base ends on the current goal (its last leg is the docking).
  [[nodiscard]] bool baseEndsAtGoal() const;
  /// Reserved traffic: the progress report for this cycle, if one is due.
  std::optional<msg::TrafficProgress> trafficProgress(std::int64_t nowNs);

  AgentParams p_;
  std::shared_ptr<const planning::OccupancyGrid> grid_;
  std::shared_ptr<const planning::OccupancyGrid> raw_;
  Localizer localizer_;      // pose, scan, detections, people, sensor loss
  Pose2 lastPlausiblePose_;  // reported while the estimate is implausible (a fault)
  control::PathFollower follower_;
  std::unique_ptr<avoidance::LocalPlanner> planner_;  // null: "follow"
  std::vector<Vec2> path_;                            // remaining path (world frame)
  /// One cycle of the configured avoidance planner; returns the twist and whether it is blocked.
  control::Twist planLocal(bool& blocked);
  std::shared_ptr<const risk::RiskLookup> risk_;

  TaskRunner tasks_;                 // the order, its goals, the phase and the task states reported
  std::int64_t pausedSinceNs_ = -1;  // holding since (its length is added to the task's timers)
  std::int64_t blockedSinceNs_ = -1;
  using Other = OtherRobot;
  MotionGate gate_;  // stop rule and cross-traffic check
  std::vector<Other> others_;
  /// The planning grid with the robots that stand still for a while (parked, loading, charging,
  /// faulted) blocked, so a path goes around them instead of into a queue behind them.
  [[nodiscard]] planning::OccupancyGrid gridAroundStandingRobots(Vec2 goal) const;
  /// The robot's disc at `p` is clear of the raw map's obstacles.
  [[nodiscard]] bool bodyFits(Vec2 p) const;
  /// The point kAxisDistance in front of `station` (along its heading) when it is free on `g` and
  /// the straight leg to it is clear of walls and standing robots; the way in and out.
  [[nodiscard]] std::optional<Vec2> axisPoint(const Pose2& station, const planning::OccupancyGrid& g) const;
  /// `p` lies on the station's straight leg already (no approach point needed).
  [[nodiscard]] bool onAxis(Vec2 p, const Pose2& station) const;
  Pose2 standsAt_;  // the station (or parking place) the robot last stopped on
  /// The goal's pose (facing in), still to be driven to straight from its axis point once the
  /// path there is done; empty when the path leads onto the goal itself.
  std::optional<Pose2> approach_;
  std::optional<Vec2> backoffFrom_;  // what blocked the robot when it started backing off
  std::optional<Vec2> blockPoint_;   // where the nearest obstacle ahead is (map frame)
  double v_ = 0.0;
  double w_ = 0.0;
  double battery_ = 1.0;
  bool docking_ = false;  // on the final approach to a goal (see clearSpeed)
  /// The pose law's curve onto this goal was blocked by a wall: turn to face it and drive straight.
  bool straightDock_ = false;
  std::int64_t idleSinceNs_ = -1;
  std::int64_t homeRetryNs_ = -1;  // after a failed trip home, not before this time
  /// On the way to a station that another robot stands on, this far off: that robot (else null).
  [[nodiscard]] const Other* stationOccupant() const;
  std::int64_t holdSinceNs_ = -1;  // queueing for an occupied station since
  bool makingRoom_ = false;        // queueing further back: the occupant wants out
  /// Where the robot left a station or its parking place from: the follower drives the first
  /// kUndockDistance, as it docks the last metre. A sampling planner behind a rotation shim turned
  /// in place towards the path first, which from a row of parked robots is towards a neighbour,
  /// and stood there held by the stop rule.
  std::optional<Vec2> undockFrom_;
  /// Whether the robot gets anywhere, and the planner's recoveries (see conduct().plannerRecoveries).
  ProgressWatch progress_;
  /// Acts on the progress watch: a task that comes no closer to its goal fails (whatever held it:
  /// a planner that outputs nothing, a return that cannot finish); a stalled driver recovers.
  void watchProgress(std::int64_t nowNs);
  /// A stalled driver: the planner hands over to the follower (inside the watch); a stalled return
  /// ends; a stalled follower on the way to a goal plans anew from where the robot is.
  void onStall(std::int64_t nowNs);
  /// Who drove this cycle and whether something held the robot (reset at the start of a cycle).
  struct Drove {
    Driver driver = Driver::kNone;
    bool held = false;
    bool waiting = false;  // reserved traffic: on a robot the plan knows about, or on a person
  } drove_;
  std::vector<Vec2> trail_;  // where the robot drove, a point every kTrailStep (newest last)
  StandoffArbiter arbiter_;  // what to do about a hold: wait, yield, detour, fail
  Conduct conduct_;
  RoutePlanner route_;  // global paths: the planner chosen once, cost layers, the fallback chain

  // Reserved traffic.
  bool reserved_ = false;
  ReleaseTracker releases_;                  // what may be driven, the last node reached
  std::uint64_t followedRevision_ = 0;       // the release the follower's path was built from
  std::vector<Vec2> basePath_;               // ... that path (from where the robot was then)
  std::optional<std::int32_t> turnsBackAt_;  // ... which stops at this node, where the base turns back
  bool rejoining_ = false;  // ... which leads back onto the node it last reached (off it, stuck)
  bool rejoined_ = false;   // ... and it is there: the base from there
  std::vector<Vec2>
      gateRoute_;            // the base ahead, for the gate's stop rule (empty: reactive, straight corridor)
  bool baseAhead_ = false;   // driving along the base this cycle (progress watch)
  bool dockingLeg_ = false;  // on the base's last leg onto the goal
  bool aligning_ = false;    // turning on the spot to face the next base node
  std::optional<Vec2> alignedTo_;  // ... done for this next node (once per node: see kMisaligned)
  std::optional<Vec2> cornerAt_;   // the corner node it drove onto last (where it aligns)
  std::int64_t heldSinceNs_ = -1;  // the gate has held the robot since (a person, ...)
  Vec2 heldAt_;                    // ... here
  bool blocked_ = false;           // ... for more than a second
  Standing standing_;
  Vec2 standAt_;                         // where the robot began standing
  std::string standWhy_;                 // this cycle's reason for a zero command (reserved traffic)
  bool standByObstacle_ = false;         // ... a static obstacle held it
  bool standByPerson_ = false;           // ... a person held it
  bool rejoinForPerson_ = false;         // the rejoin under way (or just done) gives way to a person
  std::int64_t givingWayUntilNs_ = -1;   // back on its node for a person: stands there until then
  std::uint64_t givingWayRevision_ = 0;  // ... or a new release comes
  [[nodiscard]] bool givingWay() const { return rejoinForPerson_ || givingWayUntilNs_ >= 0; }
  std::optional<msg::TrafficProgress> lastProgress_;  // the last report sent
};

/// The planning grid from a scenario's occupancy cells, inflated by `radius`.
std::shared_ptr<const planning::OccupancyGrid> inflate(const planning::OccupancyGrid& raw, double radius);

}  // namespace fleet::agent
