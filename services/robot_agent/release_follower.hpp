#pragma once

// Driving what the traffic manager released: the robot follows the released base with its local
// stack behind the motion gate, stops at the base's end unless a newer release extends it, docks
// when the base ends on its goal, turns on the spot at corners, and says why it stands. The
// ReleaseTracker keeps count of what was released and which node was reached; this drives it.
// The traffic manager's plan keeps robots that follow it apart, so what the gate still stops for is
// people and the unexpected, and that is reported (blocked) for the traffic manager to plan around.
//
// It asks the robot's stack (DriveStack, the Agent) for the local planner's twist and the motion
// gate's verdict, and tells the agent when the robot stands on its goal (the task runner's arrive).

#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "fleet/control/path_follower.hpp"
#include "fleet/control/twist.hpp"
#include "fleet/control/velocity_limits.hpp"
#include "fleet/core/pose2.hpp"
#include "fleet/core/robot_activity.hpp"
#include "fleet/messages/messages.hpp"
#include "fleet/planning/occupancy_grid.hpp"
#include "motion_gate.hpp"
#include "progress_watch.hpp"
#include "release_tracker.hpp"
#include "task_runner.hpp"

namespace fleet::agent {

/// What the follower asks of the robot's stack each cycle (the Agent implements it).
class DriveStack {
 public:
  virtual ~DriveStack() = default;
  /// A local planner drives along the base (false: the path follower alone, "follow").
  [[nodiscard]] virtual bool hasPlanner() const = 0;
  /// One cycle of the local planner along `window` (the base ahead); `blocked`: no admissible move.
  virtual control::Twist planLocal(const std::vector<Vec2>& window, bool& blocked) = 0;
  /// The motion gate on (v, w), keeping its gap along `route` (the base ahead; see GateView),
  /// `docking` on the final approach: true when held, `blocker` names what holds it.
  virtual bool heldUp(const std::vector<Vec2>& route, bool docking, double& v, double& w,
                      Blocker& blocker) = 0;
  /// The stop rule's largest forward speed up to `v` (see MotionGate::clearSpeed).
  virtual double clearSpeed(const std::vector<Vec2>& route, bool docking, double v, Blocker& blocker) = 0;
  /// `id` is a robot the agent hears of: the traffic manager plans it too.
  [[nodiscard]] virtual bool knowsRobot(const std::string& id) const = 0;
};

struct FollowerParams {
  double radius = 0.3;
  double vMax = 0.8;
  double wMax = 1.5;
  control::VelocityLimits limits{0.8, -0.3, 1.5, 1.0, 3.0};
};

/// One cycle's input.
struct FollowCycle {
  std::int64_t nowNs = 0;
  double dt = 0.1;
  Pose2 pose;
  double lastV = 0.0;            ///< the previous cycle's forward command
  std::optional<TaskGoal> goal;  ///< where the robot goes: its task's goal, or home when idle
  bool busy = false;             ///< with a task
};

/// One cycle's command and what it says of the robot.
struct FollowCommand {
  double v = 0.0;
  double w = 0.0;
  msg::RobotMode mode = msg::RobotMode::Idle;
  bool onGoal = false;  ///< it stands on its goal's pose (at the end of a base that ends there)
  Driver driver = Driver::kNone;
  bool held = false;     ///< the gate cut a command that wanted to move
  bool waiting = false;  ///< ... on a robot the plan knows about, or on a person
  /// For the robot-time ledger: driving, turning and docking, waiting on a robot (one it knows, or
  /// the traffic manager holding it at the end of its base), held by a person or by its own safety
  /// layer (an obstacle, a robot it cannot name).
  RobotActivity doing = RobotActivity::WaitingOnRobot;
};

/// Why the robot stands with a task (what last stopped it), and since when [ns] it has not got
/// movedM further; sinceNs < 0: it has nothing to do. For the operator's log: a robot that stands
/// for minutes without reporting itself blocked has the traffic manager waiting on it, and only the
/// robot knows why.
struct Standing {
  std::string why;
  std::int64_t sinceNs = -1;
  std::optional<Vec2> next;  ///< the next base node, if one is released
  bool byObstacle = false;   ///< last held by a static obstacle (what a rejoin is for)
  bool homing = false;       ///< on its way home with no task
};

class ReleaseFollower {
 public:
  /// `raw`: the map itself (tight corners); `progress`: the agent's progress watch, shared.
  ReleaseFollower(FollowerParams params, std::shared_ptr<const planning::OccupancyGrid> raw,
                  ProgressWatch& progress);

  /// Takes a release for this robot or says why not (ReleaseTracker::offer).
  ReleaseVerdict offer(const Release& r, Vec2 here) { return releases_.offer(r, here); }
  /// A release for another robot reached this one (counted only).
  void noteForeign() { releases_.noteForeign(); }

  /// The cycle's twist along the base.
  FollowCommand drive(const FollowCycle& c, DriveStack& stack);
  /// After drive(): whether and why the robot stands (see standing()).
  void noteStanding(const FollowCycle& c, const FollowCommand& cmd);
  /// Dwelling at a goal: at work, neither standing nor held.
  void atWork();
  /// Held still by the operator or by a sensor loss: not held by anything on its way.
  void holdStill();
  /// A leg begins from where the robot stands (a station, its parking place): the follower drives
  /// the first kLeaveDistance, as it docks.
  void leaving(Vec2 from) { undockFrom_ = from; }

  [[nodiscard]] const ReleaseTracker& releases() const { return releases_; }
  /// Reported blocked to the traffic manager (held by what the plan does not know of).
  [[nodiscard]] bool blocked() const { return blocked_; }
  /// On the base's last leg onto its goal (the traffic manager counts it as holding).
  [[nodiscard]] bool dockingLeg() const { return dockingLeg_; }
  /// Driving along the base this cycle (the progress watch's "travelling").
  [[nodiscard]] bool baseAhead() const { return baseAhead_; }
  [[nodiscard]] const Standing& standing() const { return standing_; }
  /// Times it drove back onto its node, stuck off it, before going on.
  [[nodiscard]] std::uint64_t rejoins() const { return rejoins_; }

 private:
  [[nodiscard]] bool givingWay() const { return rejoinForPerson_ || givingWayUntilNs_ >= 0; }
  /// The base ends on the current goal (its last leg is the docking).
  [[nodiscard]] bool baseEndsAtGoal(const std::optional<TaskGoal>& goal) const;
  /// The follower's command, scaled to cruise and limited.
  void followerTwist(const control::PathFollowerOutput& r, const Pose2& pose, double& v, double& w) const;

  FollowerParams p_;
  std::shared_ptr<const planning::OccupancyGrid> raw_;
  ProgressWatch& progress_;
  ReleaseTracker releases_;  // what may be driven, the last node reached
  control::PathFollower follower_;
  std::uint64_t followedRevision_ = 0;       // the release the follower's path was built from
  std::vector<Vec2> basePath_;               // ... that path (from where the robot was then)
  std::optional<std::int32_t> turnsBackAt_;  // ... which stops at this node, where the base turns back
  bool rejoining_ = false;          // ... which leads back onto the node it last reached (off it, stuck)
  bool rejoined_ = false;           // ... and it is there: the base from there
  std::optional<Vec2> undockFrom_;  // where it left a station or its parking place from
  bool baseAhead_ = false;          // driving along the base this cycle (progress watch)
  bool dockingLeg_ = false;         // on the base's last leg onto the goal
  bool aligning_ = false;           // turning on the spot to face the next base node
  std::optional<Vec2> alignedTo_;   // ... done for this next node (once per node: see kMisaligned)
  std::optional<Vec2> cornerAt_;    // the corner node it drove onto last (where it aligns)
  std::int64_t heldSinceNs_ = -1;   // the gate has held the robot since (a person, ...)
  Vec2 heldAt_;                     // ... here
  bool blocked_ = false;            // ... for more than kBlockedAfterS
  Standing standing_;
  Vec2 standAt_;                         // where the robot began standing
  std::string standWhy_;                 // this cycle's reason for a zero command
  bool standByObstacle_ = false;         // ... a static obstacle held it
  bool standByPerson_ = false;           // ... a person held it
  bool rejoinForPerson_ = false;         // the rejoin under way (or just done) gives way to a person
  std::int64_t givingWayUntilNs_ = -1;   // back on its node for a person: stands there until then
  std::uint64_t givingWayRevision_ = 0;  // ... or a new release comes
  std::uint64_t rejoins_ = 0;
};

}  // namespace fleet::agent
