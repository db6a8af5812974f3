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
    if (!s.travelling || closerNs_ < 0 || toGoal < bestToGoal_ - 0.25) {
      bestToGoal_ = toGoal;
      closerNs_ = s.nowNs;
    }
  }
  if (!s.travelling || movedNs_ < 0 || distance(s.here, movedFrom_) > 0.1) {
    movedFrom_ = s.here;
    movedNs_ = s.nowNs;
  }
  // A last resort behind the standoff rules (whose timer restarts whenever the robot inches on):
  // three times their limit, so a robot in a long queue is not failed for queueing.
  if (closerNs_ >= 0 && nsToSec(s.nowNs - closerNs_) > 3.0 * limits_.blockedFailS && s.hasOrder) {
    return ProgressVerdict::kFailTask;
  }
  if (s.returning && nsToSec(s.nowNs - movedNs_) > 2.0 * limits_.blockedBackoffS) {
    return ProgressVerdict::kEndReturn;  // the way back is held up too (and not by the stop rule)
  }
  return ProgressVerdict::kNone;
}

std::optional<std::int64_t> ProgressWatch::watchPlanner(std::int64_t nowNs, Vec2 here, bool planning) {
  // A sampling planner can sit in a local minimum that nothing else notices: the robot turns in
  // place at an aisle corner, never held by the stop rule, never blocked (a 1.25 m passage turning
  // into a corridor did that for minutes). After kStallS on one spot the follower, which tracks the
  // path itself, drives for kRecoverS (Nav2 would run a recovery behaviour here).
  constexpr double kStallS = 6.0;
  constexpr double kRecoverS = 8.0;
  if (!planning) {
    stallNs_ = -1;
    return std::nullopt;
  }
  if (stallNs_ < 0 || distance(here, stallFrom_) > 0.1) {
    stallFrom_ = here;
    stallNs_ = nowNs;
  } else if (nsToSec(nowNs - stallNs_) > kStallS) {
    followUntilNs_ = nowNs + static_cast<std::int64_t>(kRecoverS * 1e9);
    stallNs_ = -1;
    return followUntilNs_;
  }
  return std::nullopt;
}

}  // namespace fleet::agent
