#pragma once

// One robot's stack without DDS: EKF localization (odometry, compass, laser lines, landmark
// bearings), the traffic manager's releases as its route, its local planner along them behind the
// motion gate (stop rule, cross traffic, speed zones) and the safety layer, and task execution
// (goals with dwell times). The robot drives only what was released, stops at the end of it,
// reports each node it reaches (AgentOutput::traffic), and stands and reports itself blocked when a
// person or something off the map is in the way: robots that follow their releases are kept apart
// by the traffic manager's plan, the gate stays for people and the unexpected.
//
// The agent wires parts, each in its own file with its own tests: the Localizer (pose estimate,
// what the sensors see, sensor loss), the TaskRunner (the order, its phases and the task states
// reported), the ReleaseFollower (driving the released base; the ReleaseTracker keeps count of
// it), the MotionGate and the ProgressWatch.

#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <unordered_map>
#include <vector>

#include "fleet/avoidance/dynamic_window.hpp"
#include "fleet/avoidance/local_planner.hpp"
#include "fleet/avoidance/risk_stepping.hpp"
#include "fleet/avoidance/safety_layer.hpp"
#include "fleet/control/cruise.hpp"
#include "fleet/messages/messages.hpp"
#include "fleet/planning/occupancy_grid.hpp"
#include "fleet/risk/risk_lookup.hpp"
#include "localizer.hpp"
#include "motion_gate.hpp"
#include "other_robot.hpp"
#include "pose_watch.hpp"
#include "progress_watch.hpp"
#include "release_follower.hpp"
#include "release_tracker.hpp"
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
  /// Where the robot was when its process last saw it (the pose file, pose_store.hpp): the
  /// localization starts there, less certain, instead of at `start` (which stays its parking place).
  std::optional<Pose2> resumeAt;
  /// The driver's wheel totals kept with `resumeAt`: the roll since is known, the start is certain.
  std::optional<WheelTotals> resumeWheels;
  double radius = 0.3;
  double wheelBase = 0.4;
  double vMax = 0.8;                                  // m/s cruise
  double wMax = 1.5;                                  // rad/s
  double stopGap = 0.35;                              // m of free space kept ahead at standstill
  double robotStopGap = control::kAgentRobotStopGap;  // the same to another robot, in reserved traffic
  double headway = 1.0;                               // s: the stop distance grows with speed
  /// One notion of "wants to progress and cannot" for every local planner (robot_agent --config,
  /// "progress"; docs/algorithms.md, "Progress watch").
  ProgressParams progress;
  /// Idle, the robot asks the traffic manager for the way back to its start pose (its parking
  /// place), so a finished robot does not stay on a drop-off station or in a lane. A new order
  /// preempts the trip. Negative: it stays where the last task ended.
  double returnHomeS = 5.0;
  /// No SensorFrame for this long (of the agent's clock): stop, report RM_FAULT, resume on frames.
  double sensorTimeoutS = 0.5;
  double predictionHorizonS = 3.0;
  double predictionDt = 0.5;
  std::vector<std::pair<std::int32_t, Vec2>> landmarks;
  /// The site's wall faces for the localizer's laser-line updates (shared; null: none).
  std::shared_ptr<const std::vector<estimation::MapSegment>> walls;
  bool lineUpdates = true;  ///< false: the localizer fuses no laser lines (config localization.lines)
  /// Any libs/avoidance planner name ("dwa", "vo", ...): that planner drives along the released
  /// base, behind the safety layer; "follow": the Lyapunov path follower. Either way the follower
  /// docks on stations and turns at corners, and the same motion gate applies.
  std::string localPlanner = "dwa";
  avoidance::DwaParams dwa = agentDwaDefaults();  ///< when localPlanner is "dwa" (from --config)
  /// When localPlanner is "risk_stepping" (from --config); "risk_stepping_weighted" forces the weighted rule.
  avoidance::RiskSteppingParams riskStepping;
  avoidance::SafetyParams safety;  ///< the safety layer behind every libs/avoidance planner
  control::VelocityLimits limits{0.8, -0.3, 1.5, 1.0, 3.0};
  /// The site's speed limit at a map point [m/s] (+inf or empty: none), which the motion gate enforces.
  std::function<double(Vec2)> speedLimit;
};

struct AgentOutput {
  msg::VelocityCommand command;
  msg::RobotState state;
  msg::PredictedDiscs discs;
  std::optional<msg::TaskStatus> status;  // on every task state change
  /// On every node reached, on a change of goal, holding or blocked, and at least once a second.
  std::optional<msg::TrafficProgress> traffic;
  /// The people the robot sees, a few times a second (AgentNode, PeopleReport); never set by Agent.
  std::optional<msg::PeopleSeen> people;
};

class Agent : private DriveStack {
 public:
  /// `raw`: the map (with the site's no-go zones blocked) the robot keeps clear of.
  Agent(AgentParams params, std::shared_ptr<const planning::OccupancyGrid> raw);

  void onFrame(const msg::SensorFrame& f);
  /// Other robots' states: what the local planner and the gate keep clear of, and whom the robot
  /// waits on (a robot the traffic manager plans too).
  void onOtherRobot(const msg::RobotState& s);
  /// The same state converted once for every agent of a process (otherOf: nullopt for a pose that
  /// is not finite) and found by `slot`, the process's number for its robot id (AgentNode): at 300
  /// robots every state reaches 150 agents each cycle. An agent is fed through one of the two.
  void onOtherRobot(std::size_t slot, const OtherRobot& o);
  [[nodiscard]] static std::optional<OtherRobot> otherOf(const msg::RobotState& s);
  /// Every other robot heard of, as last heard.
  [[nodiscard]] const std::vector<OtherRobot>& others() const { return others_; }
  /// A new revision replaces the current order (an empty task id cancels).
  void onAssignment(const msg::TaskAssignment& a);
  /// An order for this robot that cannot be carried out (refused at the edge, or without goals):
  /// reports that task failed with `why`.
  void refuseAssignment(const msg::TaskAssignment& a, const std::string& why);
  /// The traffic manager's release for this robot (others, stale ones and ones that do not start at
  /// the node it last reported are ignored and counted).
  void onRelease(const msg::TrafficRelease& r);
  /// The latest risk map (shared by every agent of the process): the local planner's risk term.
  /// Null: no risk information.
  void onRiskMap(std::shared_ptr<const risk::RiskLookup> risk) { risk_ = std::move(risk); }
  AgentOutput step(std::int64_t nowNs, double dt);
  /// True while the sensor stream is considered lost (as of the last step).
  [[nodiscard]] bool sensorLost() const { return localizer_.lost(); }
  /// True while its laser lines say its pose estimate is wrong (PoseWatch): it stands, faulted.
  [[nodiscard]] bool poseDoubted() const { return poseWatch_.doubted(); }
  [[nodiscard]] const PoseWatch& poseWatch() const { return poseWatch_; }

  [[nodiscard]] Pose2 pose() const { return localizer_.pose(); }
  [[nodiscard]] const Eigen::Matrix3d& covariance() const { return localizer_.covariance(); }
  /// The driver's wheel totals the pose is as of (kept with it in the pose file).
  [[nodiscard]] std::optional<WheelTotals> wheelTotals() const { return localizer_.wheelTotals(); }
  [[nodiscard]] bool resumeTotalsRefused() const { return localizer_.resumeTotalsRefused(); }
  [[nodiscard]] std::uint64_t driverRestarts() const { return localizer_.driverRestarts(); }
  [[nodiscard]] const std::string& id() const { return p_.id; }
  /// Where it goes when idle (its start pose, its parking place).
  [[nodiscard]] const Pose2& home() const { return p_.start; }
  [[nodiscard]] bool busy() const { return tasks_.busy(); }
  /// The current order is paused by the operator: the robot stands still with it.
  [[nodiscard]] bool paused() const { return tasks_.paused(); }
  [[nodiscard]] std::uint64_t framesRejected() const { return localizer_.rejected(); }
  [[nodiscard]] const LineStats& lineStats() const { return localizer_.lineStats(); }
  /// What the sensors saw as of the last reading (pose, scan, detections, people).
  [[nodiscard]] const Perception& perception() const { return localizer_.perception(); }
  /// Releases taken and ignored (cumulative).
  [[nodiscard]] const ReleaseCounts& releases() const { return follow_.releases().counts(); }
  /// The last roadmap node reached (-1 before any release).
  [[nodiscard]] std::int32_t trafficNode() const { return follow_.releases().node(); }
  /// Why the robot stands with a task, and since when (see Standing).
  [[nodiscard]] const Standing& standingStill() const { return follow_.standing(); }

  /// What the robot did about being held up (cumulative), for tests and the service's counters.
  struct Conduct {
    /// Whoever drove kept the robot on one spot while nothing held it (the progress watch's stall)
    /// and it recovered: after a sampling planner's local minimum (turning in place at a corner)
    /// the path follower drove for a while.
    std::uint64_t plannerRecoveries = 0;
    /// Stuck off its node, it drove back onto it before going on.
    std::uint64_t rejoins = 0;
  };
  [[nodiscard]] Conduct conduct() const { return {plannerRecoveries_, follow_.rejoins()}; }

 private:
  /// The task stack for one cycle (the body of step() while sensors are live).
  AgentOutput drive(std::int64_t nowNs, double dt);
  /// The localizer's stream watch; on loss and on recovery queues a TaskStatus with the reason and
  /// shifts the task's timers so the outage does not count as being stuck.
  bool sensorStreamLost(std::int64_t nowNs);
  bool poseDoubtful(std::int64_t nowNs);
  /// Command, state and predicted discs for the chosen twist and mode.
  void report(AgentOutput& out, std::int64_t nowNs, double v, double w, msg::RobotMode mode);
  /// The task ends (failed: `reason` says why).
  void endTask(TaskState final, const std::string& reason, std::int64_t nowNs);
  /// The cycle along the releases: the task runner's tick, then the release follower's twist.
  void followRelease(std::int64_t nowNs, double dt, double& v, double& w, msg::RobotMode& mode);
  /// Where the robot is going (the task's goal; idle, its home), if anywhere.
  [[nodiscard]] std::optional<TaskGoal> trafficGoal() const;
  /// What the robot-time ledger files this cycle under (RobotState.activity).
  [[nodiscard]] RobotActivity activity(msg::RobotMode mode) const;
  /// The progress report for this cycle, if one is due.
  std::optional<msg::TrafficProgress> trafficProgress(std::int64_t nowNs);
  /// Acts on the progress watch: a task that comes no closer to its next node fails; a stalled
  /// planner hands the drive to the follower for a while.
  void watchProgress(std::int64_t nowNs);

  // DriveStack: the local planner and the motion gate, for the release follower.
  [[nodiscard]] bool hasPlanner() const override { return planner_ != nullptr; }
  control::Twist planLocal(const std::vector<Vec2>& window, bool& blocked) override;
  bool heldUp(const std::vector<Vec2>& route, bool docking, double& v, double& w, Blocker& blocker) override;
  double clearSpeed(const std::vector<Vec2>& route, bool docking, double v, Blocker& blocker) override;
  [[nodiscard]] bool knowsRobot(const std::string& id) const override;
  /// What the motion gate looks at this cycle.
  [[nodiscard]] GateView gateView(const std::vector<Vec2>& route, bool docking) const;

  AgentParams p_;
  std::shared_ptr<const planning::OccupancyGrid> raw_;
  Localizer localizer_;                               // pose, scan, detections, people, sensor loss
  Pose2 lastPlausiblePose_;                           // reported while the estimate is implausible (a fault)
  std::unique_ptr<avoidance::LocalPlanner> planner_;  // null: "follow"
  std::shared_ptr<const risk::RiskLookup> risk_;
  TaskRunner tasks_;                 // the order, its goals, the phase and the task states reported
  std::int64_t pausedSinceNs_ = -1;  // holding since (its length is added to the task's timers)
  MotionGate gate_;                  // stop rule, cross traffic, speed zones
  std::vector<OtherRobot> others_;
  std::unordered_map<std::string, std::size_t> slotOf_;  // robot id -> slot, fed by RobotState
  std::vector<std::int32_t> entryOf_;                    // slot -> its entry in others_, -1: none
  double v_ = 0.0;
  double w_ = 0.0;
  double battery_ = 1.0;
  /// Whether the robot gets anywhere, and the planner's recoveries.
  ProgressWatch progress_;
  PoseWatch poseWatch_;
  std::int64_t doubtedSinceNs_ = -1;
  std::uint64_t plannerRecoveries_ = 0;
  ReleaseFollower follow_;                            // drives the released base
  FollowCommand drove_;                               // this cycle's (reset at the start of a cycle)
  std::optional<msg::TrafficProgress> lastProgress_;  // the last report sent
};

}  // namespace fleet::agent
