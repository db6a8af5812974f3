#include "progress_watch.hpp"

#include "fleet/core/clock.hpp"

namespace fleet::agent {

ProgressVerdict ProgressWatch::check(const ProgressSample& s) {
  // Progress is getting closer to the goal, not moving: two robots yielding to each other by turns,
  // or a robot backing out and trying again at an aisle mouth, move for ever and get nowhere (a
  // 20-robot run once held two tasks en route for 600 s that way, each move resetting a "moved
  // 0.1 m" watch).
  if (s.goal) {
    const double toGoal = distance(s.here, *s.goal);
    if (!s.travelling || s.waiting || closerNs_ < 0 || toGoal < bestToGoal_ - p_.closerM) {
      bestToGoal_ = toGoal;
      closerNs_ = s.nowNs;
    }
  }
  const ProgressVerdict stalled = stall(s);
  // A last resort behind the standoff rules (whose timer restarts whenever the robot inches on):
  // three times their limit, so a robot in a long queue is not failed for queueing.
  if (closerNs_ >= 0 && nsToSec(s.nowNs - closerNs_) > p_.failS && s.hasOrder) {
    return ProgressVerdict::kFailTask;
  }
  return stalled;
}

ProgressVerdict ProgressWatch::stall(const ProgressSample& s) {
  // Standing with a way to drive and nothing holding it: a sampling planner in a local minimum
  // (turning in place at an aisle corner, never held by the stop rule: a 1.25 m passage turning
  // into a corridor did that for minutes), or the follower on its way back stuck where the stop
  // rule does not see why. What holds the robot is the standoff rules' or the traffic manager's
  // business, so a hold stops the clock; so does a change of driver.
  if (s.driver == Driver::kNone || s.held || s.waiting) {
    stallNs_ = -1;
    return ProgressVerdict::kNone;
  }
  if (stallNs_ < 0 || s.driver != stallDriver_ || distance(s.here, stallFrom_) > p_.movedM) {
    stallDriver_ = s.driver;
    stallFrom_ = s.here;
    stallNs_ = s.nowNs;
    return ProgressVerdict::kNone;
  }
  if (nsToSec(s.nowNs - stallNs_) <= p_.stallS) {
    return ProgressVerdict::kNone;
  }
  stallNs_ = -1;
  if (s.driver == Driver::kPlanner) {
    // The follower, which tracks the path itself, drives for a while (Nav2 would run a recovery
    // behaviour here).
    followUntilNs_ = s.nowNs + static_cast<std::int64_t>(p_.recoverS * 1e9);
  }
  return ProgressVerdict::kStalled;
}

}  // namespace fleet::agent
