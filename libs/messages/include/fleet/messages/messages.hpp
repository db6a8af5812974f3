#pragma once

// C++ forms of the DDS types in idl/fleet.idl. Services work with these; the transport layer copies
// them to and from the generated C structs. Field meanings and units: docs/messages.md.

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "fleet/core/pose2.hpp"
#include "fleet/core/robot_activity.hpp"
#include "fleet/core/task_state.hpp"

namespace fleet::msg {

enum class TaskKind : std::uint8_t { Transport, GoTo, Charge, Park, Multistop };
enum class StepAction : std::uint8_t { Goto, Pick, Drop, Wait, Charge };
enum class TaskControl : std::uint8_t { None, Pause, Resume, Query, HoldRobot, ReleaseRobot, Change };
/// IDL TaskState (TS_QUEUED ... TS_REJECTED), in the same order: fleet/core/task_state.hpp.
using TaskState = fleet::TaskState;
enum class RobotMode : std::uint8_t { Idle, Moving, Waiting, Loading, Charging, Blocked, Fault };
enum class SourceKind : std::uint8_t { Robot, Human };
enum class GoalAction : std::uint8_t { None, Load, Unload, Charge, Park };
/// IDL RobotActivity (RA_UNSET ... RA_FAULTED), in the same order: fleet/core/robot_activity.hpp.
using RobotActivity = fleet::RobotActivity;

struct TaskStep {
  StepAction action = StepAction::Goto;
  std::string station;
  std::string load_id;
  std::int64_t duration_ns = 0;
  bool operator==(const TaskStep&) const = default;
};

struct Task {
  std::string task_id;
  std::string request_id;
  TaskKind kind = TaskKind::Transport;
  std::string pickup;
  std::string dropoff;
  std::string station;
  std::string robot;
  std::int64_t load_ns = 0;
  std::int64_t unload_ns = 0;
  std::int32_t priority = 0;
  std::int64_t deadline_ns = 0;
  std::int64_t created_ns = 0;
  bool cancel = false;
  TaskControl control = TaskControl::None;
  bool set_priority = false;      ///< Change: `priority` is the task's new priority
  bool set_deadline = false;      ///< Change: `deadline_ns` is the task's new deadline (0 = none)
  std::vector<TaskStep> steps{};  ///< Multistop: the stops in order (at most 16)
  bool operator==(const Task&) const = default;
};

enum class AckResult : std::uint8_t { Stored, Duplicate, Conflict, Invalid, NotFound, Refused, Unavailable };

struct TaskAck {
  std::string request_id;
  std::string task_id;
  AckResult result = AckResult::Stored;
  TaskState state = TaskState::Queued;
  std::string detail;
  std::int64_t stamp_ns = 0;
  bool operator==(const TaskAck&) const = default;
};

struct TaskEvent {
  std::string task_id;
  TaskState state = TaskState::Queued;
  std::string robot_id;
  std::string reason;
  std::int64_t stamp_ns = 0;
  std::uint32_t seq = 0;
  std::string station;  ///< chosen by the manager for a charge/park task sent without one
  /// The event of a change (TaskControl::Change): priority and deadline_ns are the values now in
  /// force. On any other event they are 0 and mean nothing.
  bool changed = false;
  std::int32_t priority = 0;
  std::int64_t deadline_ns = 0;
  /// When the task is expected done, as the manager estimated it at this transition (TaskEta,
  /// UTC ns); 0: no estimate (no robot could take it, or it ended without being done).
  std::int64_t eta_ns = 0;
  /// The publishing manager's lease epoch (0: no lease); readers drop events of an older one.
  std::int64_t epoch = 0;
  /// A multi-stop task's stop the robot is at or driving to, from 1; 0: not known.
  std::uint32_t step = 0;
  bool operator==(const TaskEvent&) const = default;
};

struct Goal {
  Pose2 pose;
  std::string station;
  GoalAction action = GoalAction::None;
  double duration_s = 0;
  /// The load a pick or drop carries (on the wire TaskAssignment.goal_load_ids, as Goal is @final).
  std::string load_id{};
  bool operator==(const Goal&) const = default;
};

struct TaskAssignment {
  std::string robot_id;
  std::string task_id;
  std::uint32_t revision = 0;
  std::vector<Goal> goals;
  bool paused = false;
  std::int64_t stamp_ns = 0;
  std::int32_t priority = 0;  ///< the task's (higher first)
  /// The publishing manager's lease epoch (0: no lease); readers drop orders of an older one.
  std::int64_t epoch = 0;
  bool operator==(const TaskAssignment&) const = default;
};

struct TaskStatus {
  std::string robot_id;
  std::string task_id;
  std::uint32_t revision = 0;
  TaskState state = TaskState::Queued;
  float progress = 0;
  std::string error;
  std::int64_t stamp_ns = 0;
  /// The goal the robot is at or driving to, from 1 (the last when done); 0: not said.
  std::uint32_t step = 0;
  bool operator==(const TaskStatus&) const = default;
};

struct RobotState {
  std::string robot_id;
  std::int64_t stamp_ns = 0;
  Pose2 pose;
  std::array<double, 9> covariance{};
  double v = 0;
  double w = 0;
  RobotMode mode = RobotMode::Idle;
  float battery = 1;
  std::string task_id;
  float radius = 0;
  bool paused = false;  ///< held by the operator
  /// What it is doing (the robot-time ledger); Unset from an agent that does not say.
  RobotActivity activity = RobotActivity::Unset;
  bool operator==(const RobotState&) const = default;
};

struct Disc {
  float x = 0;
  float y = 0;
  float r = 0;
  float sigma = 0;
  // Position covariance (m²); all zero means isotropic with `sigma`.
  float cov_xx = 0;
  float cov_xy = 0;
  float cov_yy = 0;
  bool operator==(const Disc&) const = default;
};

struct PredictedDiscs {
  std::string source_id;
  SourceKind kind = SourceKind::Robot;
  std::int64_t t0_ns = 0;
  float dt = 0;
  std::vector<Disc> discs;
  bool operator==(const PredictedDiscs&) const = default;
};

struct SeenPerson {
  float x = 0;
  float y = 0;
  float vx = 0;
  float vy = 0;
  float r = 0;
  bool velocity_known = false;
  bool operator==(const SeenPerson&) const = default;
};

/// The people one robot sees (idl/fleet.idl), at most kMaxPeopleSeen.
struct PeopleSeen {
  std::string robot_id;
  std::int64_t stamp_ns = 0;
  std::vector<SeenPerson> people;
  bool operator==(const PeopleSeen&) const = default;
};
inline constexpr std::size_t kMaxPeopleSeen = 64;

struct LevelRun {
  std::uint8_t level = 0;
  std::uint32_t count = 0;
  bool operator==(const LevelRun&) const = default;
};

using Ring = std::vector<Vec2>;

struct Region {
  std::uint8_t level = 0;
  Ring outer;
  std::vector<Ring> holes;
  bool operator==(const Region&) const = default;
};

struct RiskMap {
  std::int64_t stamp_ns = 0;
  double origin_x = 0;
  double origin_y = 0;
  double resolution = 0;
  std::uint32_t width = 0;
  std::uint32_t height = 0;
  std::uint8_t levels = 0;
  float horizon_s = 0;
  float scene_index = 0;
  std::uint32_t sources = 0;
  std::vector<LevelRun> runs;
  std::vector<Region> regions;
  bool operator==(const RiskMap&) const = default;
};

struct LandmarkBearing {
  std::int32_t id = 0;
  float bearing = 0;
  bool operator==(const LandmarkBearing&) const = default;
};

struct Detection {
  SourceKind kind = SourceKind::Robot;
  float x = 0;
  float y = 0;
  float r = 0;
  bool operator==(const Detection&) const = default;
};

struct SensorFrame {
  std::string robot_id;
  std::int64_t stamp_ns = 0;
  std::uint32_t seq = 0;
  double ds_left = 0;
  double ds_right = 0;
  float angle_min = 0;
  float angle_increment = 0;
  float range_max = 0;
  std::vector<float> ranges;
  bool compass_valid = false;
  double compass = 0;
  std::vector<LandmarkBearing> landmarks;
  std::vector<Detection> detections;
  float battery = 1;
  bool charging = false;
  bool wheel_totals_valid = false;  ///< wheel_*_total are set (older drivers leave them out)
  double wheel_left_total = 0;      ///< [m] since the driver started
  double wheel_right_total = 0;
  /// The driver's run the totals count in, new and nonzero each time it starts; 0: not told.
  std::uint64_t driver_session = 0;
  bool operator==(const SensorFrame&) const = default;
};

struct VelocityCommand {
  std::string robot_id;
  double v = 0;
  double w = 0;
  std::int64_t stamp_ns = 0;
  std::uint32_t seq = 0;
  bool operator==(const VelocityCommand&) const = default;
};

struct Clock {
  std::int64_t step = 0;
  std::int64_t sim_time_ns = 0;
  std::int64_t dt_ns = 0;
  bool lockstep = false;
  bool operator==(const Clock&) const = default;
};

/// The last VelocityCommand a lockstep participant wrote for `robot_id` in a step.
struct CommandMark {
  std::string robot_id;
  std::uint32_t seq = 0;
  bool operator==(const CommandMark&) const = default;
};

/// At most this many robots' commands in one StepDone (the IDL bound).
inline constexpr std::size_t kMaxStepDoneCommands = 4096;

struct StepDone {
  static constexpr std::int64_t kRegister = -1;
  static constexpr std::int64_t kLeave = -2;
  std::string participant_id;
  std::int64_t step = 0;
  /// Step k: the robots commanded and the seq of each one's last command; the simulator waits for
  /// them before it applies the step.
  std::vector<CommandMark> commands{};
  bool operator==(const StepDone&) const = default;
};

struct Body {
  std::string id;
  SourceKind kind = SourceKind::Robot;
  Pose2 pose;
  double v = 0;
  double radius = 0;
  bool operator==(const Body&) const = default;
};

struct Contact {
  std::string a;
  std::string b;
  double depth = 0;
  bool operator==(const Contact&) const = default;
};

struct GroundTruth {
  std::int64_t step = 0;
  std::int64_t sim_time_ns = 0;
  std::vector<Body> bodies;
  std::vector<Contact> contacts;
  bool operator==(const GroundTruth&) const = default;
};

/// A roadmap node as it travels with releases (id and position).
struct RouteNode {
  std::int32_t node = -1;
  double x = 0;
  double y = 0;
  bool operator==(const RouteNode&) const = default;
};

struct RoadmapEdge {
  std::int32_t from = -1;
  std::int32_t to = -1;
  float duration_s = 0;
  bool open = true;
  bool operator==(const RoadmapEdge&) const = default;
};

struct Roadmap {
  std::string site;
  std::uint32_t epoch = 0;
  std::uint32_t revision = 0;
  std::vector<RouteNode> nodes;
  std::vector<std::uint8_t> kinds;
  std::vector<bool> open;
  std::vector<RoadmapEdge> edges;
  std::int64_t stamp_ns = 0;
  /// m: the robot disc its conflicts were computed for; a robot must fit in it (0: not stated).
  double robot_radius = 0;
  bool operator==(const Roadmap&) const = default;
};

struct NodePair {
  std::int32_t from = 0;
  std::int32_t to = 0;
  bool operator==(const NodePair&) const = default;
};

/// A part of the roadmap closed at run time (or reopened: active = false); see fleet.idl.
struct TrafficClosure {
  std::string closure_id;
  bool active = true;
  std::vector<Vec2> area;           ///< polygon, at most 256 corners; empty: none
  std::vector<std::int32_t> nodes;  ///< at most 4096
  std::vector<NodePair> lanes;      ///< directed edges, at most 4096
  std::string reason;
  std::int64_t stamp_ns = 0;
  bool operator==(const TrafficClosure&) const = default;
};

struct TrafficRelease {
  std::string robot_id;
  std::uint32_t epoch = 0;
  std::uint32_t seq = 0;
  std::vector<RouteNode> base;     ///< at most 64; base[0]: the node last reported
  std::vector<RouteNode> horizon;  ///< at most 32
  bool ends_at_goal = false;
  std::int64_t stamp_ns = 0;
  bool operator==(const TrafficRelease&) const = default;
};

struct TrafficProgress {
  std::string robot_id;
  std::uint32_t epoch = 0;
  std::int32_t node = -1;
  Pose2 pose;
  bool has_goal = false;
  Pose2 goal;
  std::string goal_station;
  std::int32_t priority = 0;
  bool holding = false;
  bool blocked = false;
  bool follows = true;
  std::int64_t stamp_ns = 0;
  bool operator==(const TrafficProgress&) const = default;
};

const char* toString(TaskState s);
const char* toString(TaskKind k);
const char* toString(RobotMode m);
/// What a state says its robot is doing: its activity, or when the agent leaves it Unset what its
/// mode and task say (fleet::activityFromMode).
RobotActivity activityOf(const RobotState& s);
/// Inverse of toString; false when the name is unknown.
bool parse(const std::string& name, TaskState& out);
bool parse(const std::string& name, TaskKind& out);

}  // namespace fleet::msg
