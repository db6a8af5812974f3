#pragma once

// Whether the robot is getting anywhere, watched once per cycle, with one notion of "wants to
// progress and cannot" for every local planner: the path follower, DWA, the sampling planners and
// reserved traffic's base following. A robot stalls when it has a way to drive, nothing holds it
// (the stop rule, a station's queue, a dependency, a person) and it has not moved `movedM` for
// `stallS`; a task that comes no `closerM` closer to its goal for `failS` fails. The caller
// decides what a stall means for whoever drove (Nav2's controller server consults its progress
// checker the same way); this only keeps the clocks.

#include <cstdint>
#include <optional>

#include "fleet/core/vec2.hpp"

namespace fleet::agent {

/// The one set of progress parameters (robot_agent --config, "progress").
struct ProgressParams {
  /// A forward command above this [m/s] wants the robot to move: cut by the stop rule, the robot is
  /// held. (A sampling planner accelerates from standstill in steps of a·dt = 0.1 m/s, so its first
  /// wish is no more than that; the follower asks for cruise.)
  double wantSpeed = 0.02;
  /// Moving less than this [m] is standing.
  double movedM = 0.1;
  /// Standing this long [s] with a way to drive and nothing holding it: stalled.
  double stallS = 6.0;
  /// A stalled sampling planner hands over to the follower for this long [s].
  double recoverS = 8.0;
  /// Progress on a task is coming this much [m] closer to its goal than ever before ...
  double closerM = 0.25;
  /// ... and a task (or the trip home) without it for this long [s] fails.
  double failS = 180.0;
};

/// Who drives the robot this cycle.
enum class Driver {
  kNone,      ///< nobody: standing at a station, dwelling, backing off, waiting to start
  kFollower,  ///< the path follower (or its pose law, docking)
  kPlanner,   ///< a sampling local planner (DWA, VO, risk stepping, ...)
};

/// What the robot does this cycle, as far as progress is concerned.
struct ProgressSample {
  std::int64_t nowNs = 0;
  Vec2 here;
  /// Driving, returning or backing off (any other phase restarts the progress clock).
  bool travelling = false;
  /// The current goal's position; empty when the order has none left.
  std::optional<Vec2> goal;
  /// There is an order or a trip home that could fail.
  bool hasOrder = false;
  /// Who drove this cycle, and whether something held the robot (the stop rule cut a command that
  /// wanted to move, or the planner found no admissible move).
  Driver driver = Driver::kNone;
  bool held = false;
  /// Waiting on another robot the plan knows about (a dependency) or on a person: neither the
  /// progress clock nor the stall clock runs (reserved traffic, where the traffic manager re-plans).
  bool waiting = false;
};

enum class ProgressVerdict {
  kNone,
  kFailTask,  ///< no progress towards the goal for failS: fail the task
  kStalled,   ///< the driver has stood for stallS with nothing holding it
};

class ProgressWatch {
 public:
  explicit ProgressWatch(ProgressParams params) : p_(params) {}

  [[nodiscard]] const ProgressParams& params() const { return p_; }
  /// The forward command `v` [m/s] wants the robot to move (whoever drives).
  [[nodiscard]] bool wantsToMove(double v) const { return v > p_.wantSpeed; }

  /// The progress watch proper; call once per cycle after the phase's work. A kStalled of the
  /// planner also hands the drive to the follower for recoverS (see followerDrives).
  ProgressVerdict check(const ProgressSample& s);
  /// The limit of kFailTask in whole seconds, as the task's failure reason names it.
  [[nodiscard]] int failAfterS() const { return static_cast<int>(p_.failS); }
  /// A recovery is under way: the follower drives, not the planner.
  [[nodiscard]] bool followerDrives(std::int64_t nowNs) const { return nowNs < followUntilNs_; }

  /// A new order: the progress clock starts with its first cycle.
  void newOrder() { closerNs_ = -1; }
  /// The next goal of the order (or a trip home): "closer" is measured to it from now on.
  void newGoal() { closerNs_ = -1; }
  /// The task ended (done or failed): standing still from now on is not being stuck.
  void taskEnded() { stallNs_ = -1; }
  /// Waiting in a station's queue is not being stuck.
  void queueing(std::int64_t nowNs) {
    stallNs_ = -1;
    closerNs_ = nowNs;
  }
  /// The sensors were lost for `outageNs`, or the operator held the order for `outageNs`: that
  /// time does not count. (Until 2026-11-25 a pause shifted only one clock, so a pause longer than
  /// the failure limit failed the task with "no progress" on the first cycle after resuming.)
  void afterOutage(std::int64_t outageNs) {
    if (stallNs_ >= 0) {
      stallNs_ += outageNs;
    }
    if (closerNs_ >= 0) {
      closerNs_ += outageNs;
    }
  }

 private:
  ProgressVerdict stall(const ProgressSample& s);

  ProgressParams p_;
  double bestToGoal_ = 0.0;     // the closest it has come to the current goal [m]
  std::int64_t closerNs_ = -1;  // ... when that last improved by closerM (-1: new goal)

  Driver stallDriver_ = Driver::kNone;  // who drove while the stall clock ran
  Vec2 stallFrom_;                      // where the robot last moved movedM from
  std::int64_t stallNs_ = -1;           // ... and when (-1: the clock is off)
  std::int64_t followUntilNs_ = -1;     // the follower drives instead of the planner until then
};

}  // namespace fleet::agent
