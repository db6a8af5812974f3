#pragma once

// Whether the robot is getting anywhere, watched once per cycle: a task that comes no closer to its
// goal for a long while fails, a return (backing out along the trail) that stands still ends, and a
// local planner that keeps the robot on one spot hands over to the path follower for a while (as
// Nav2's controller server consults its progress checker). The caller decides what to do; this
// only keeps the clocks.

#include <cstdint>
#include <optional>

#include "fleet/core/vec2.hpp"

namespace fleet::agent {

struct ProgressLimits {
  /// A task (or the trip home) that has come no 0.25 m closer to its goal for 3 x this [s] fails.
  double blockedFailS = 60.0;
  /// A return that has not moved 0.1 m for 2 x this [s] ends.
  double blockedBackoffS = 4.0;
};

/// What the robot does this cycle, as far as progress is concerned.
struct ProgressSample {
  std::int64_t nowNs = 0;
  Vec2 here;
  /// Driving, returning or backing off (any other phase restarts both clocks).
  bool travelling = false;
  bool returning = false;
  /// The current goal's position; empty when the order has none left.
  std::optional<Vec2> goal;
  /// There is an order or a trip home that could fail.
  bool hasOrder = false;
};

enum class ProgressVerdict {
  kNone,
  kFailTask,   ///< no progress towards the goal for failAfterS(): fail the task
  kEndReturn,  ///< the return has not moved for a while: plan from where the robot is
};

class ProgressWatch {
 public:
  explicit ProgressWatch(ProgressLimits limits) : limits_(limits) {}

  /// The progress watch proper; call once per cycle after the phase's work.
  ProgressVerdict check(const ProgressSample& s);
  /// The limit of kFailTask in whole seconds, as the task's failure reason names it.
  [[nodiscard]] int failAfterS() const { return static_cast<int>(3.0 * limits_.blockedFailS); }

  /// The local planner drove this cycle (`planning`: it drove and nothing held the robot). When the
  /// robot has stood on one spot too long, returns until when the follower drives instead.
  std::optional<std::int64_t> watchPlanner(std::int64_t nowNs, Vec2 here, bool planning);
  /// A recovery is under way: the follower drives, not the planner.
  [[nodiscard]] bool followerDrives(std::int64_t nowNs) const { return nowNs < followUntilNs_; }

  /// A new order: both clocks start with its first cycle.
  void newOrder() {
    movedNs_ = -1;
    closerNs_ = -1;
  }
  /// The next goal of the order (or a trip home): "closer" is measured to it from now on.
  void newGoal() { closerNs_ = -1; }
  /// The task ended (done or failed): standing still from now on is not being stuck.
  void taskEnded(std::int64_t nowNs) { movedNs_ = nowNs; }
  /// Waiting in a station's queue is not being stuck.
  void queueing(std::int64_t nowNs) {
    movedNs_ = nowNs;
    closerNs_ = nowNs;
  }
  /// The sensors were lost for `outageNs`: that time does not count.
  void afterSensorOutage(std::int64_t outageNs) {
    // (The moved clock is shifted even before the order's first cycle, unlike after a pause.)
    movedNs_ += outageNs;
    if (closerNs_ >= 0) {
      closerNs_ += outageNs;
    }
  }
  /// The operator held the order for `heldNs`: that time does not count.
  void afterPause(std::int64_t heldNs) {
    if (movedNs_ >= 0) {
      movedNs_ += heldNs;
    }
    // Until 2026-11-25 only the moved clock was shifted, so a pause longer than 3 x blockedFailS
    // failed the task with "no progress" on the first cycle after resuming.
    if (closerNs_ >= 0) {
      closerNs_ += heldNs;
    }
  }

 private:
  ProgressLimits limits_;
  // The two watches of check() differ: progress is 0.25 m closer to the goal within 3 x blockedFailS
  // (180 s), a return's is 0.1 m moved within 2 x blockedBackoffS (8 s); the planner watch below is
  // 0.1 m moved within 6 s. Merging them is a later, measured change.
  Vec2 movedFrom_;              // where the robot last moved 0.1 m from
  std::int64_t movedNs_ = 0;    // ... and when
  double bestToGoal_ = 0.0;     // the closest it has come to the current goal [m]
  std::int64_t closerNs_ = -1;  // ... when that last improved by 0.25 m (-1: new goal)

  Vec2 stallFrom_;                   // where the local planner last moved the robot 0.1 m from
  std::int64_t stallNs_ = -1;        // ... and when (-1: not driving with it)
  std::int64_t followUntilNs_ = -1;  // the follower drives instead of the planner until then
};

}  // namespace fleet::agent
