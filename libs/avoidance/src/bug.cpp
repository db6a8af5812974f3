#include "fleet/avoidance/bug.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "fleet/avoidance/clearance.hpp"
#include "fleet/core/angles.hpp"

namespace fleet::avoidance {

namespace {

double distanceToLine(Vec2 a, Vec2 b, Vec2 p) {
  const Vec2 ab = b - a;
  const double n = std::sqrt(ab.squaredNorm());
  return n > 0.0 ? std::abs(ab.cross(p - a)) / n : fastDistance(a, p);
}

// Bug is an algorithm for a static world: a boundary it follows must stay put. Moving discs (people
// walking by, robots driving) are left to the safety layer, which holds the robot until they pass;
// a disc standing still (a parked robot) is a boundary like a shelf.
constexpr double kStandingSpeed = 0.05;  // m/s
bool standing(const MovingDisc& d) {
  return d.velocity.squaredNorm() <= kStandingSpeed * kStandingSpeed;
}

// Nearest static obstacle point (scan or standing disc surface) and its distance from the robot centre.
std::pair<Vec2, double> nearestObstacle(const LocalView& view) {
  const Vec2 p = view.robot.pose.position();
  Vec2 best_pt = p;
  double best = std::numeric_limits<double>::infinity();
  for (const Vec2& q : view.scan) {
    const double d = fastDistance(p, q);
    if (d < best) {
      best = d;
      best_pt = q;
    }
  }
  for (const MovingDisc& d : view.discs) {
    if (!standing(d))
      continue;
    const double dc = fastDistance(p, d.position) - d.radius;
    if (dc < best) {
      best = dc;
      best_pt = d.position + (p - d.position).normalized() * d.radius;
    }
  }
  return {best_pt, best};
}

}  // namespace

Expected<void> BugParams::validate() const {
  if (!(followGap > 0.0) || !(hitGap >= followGap) || !(mlineTolerance > 0.0) || !(loopTolerance > 0.0) ||
      !(cruise > 0.0) || !(kHeading > 0.0) || !(kGap >= 0.0) || leaveMargin < 0.0) {
    return fleet::unexpected("invalid_bug_params",
                             "gaps, tolerances, gains and cruise speed must be positive");
  }
  return {};
}

void BugPlanner::reset() {
  mode_ = BugMode::kGoToGoal;
  initialised_ = false;
  hits_ = 0;
}

Twist BugPlanner::steerTowards(const LocalView& view, Vec2 direction) const {
  const double err = angleDiff(std::atan2(direction.y, direction.x), view.robot.pose.theta);
  const double v = params_.cruise * std::max(0.0, std::cos(err));
  const double w = std::clamp(params_.kHeading * err, -view.limits.omegaMax, view.limits.omegaMax);
  return {std::min(v, view.limits.vMax), w};
}

bool BugPlanner::blockedTowards(const LocalView& view, Vec2 direction) const {
  // Anything inside a corridor one body wide reaching hitGap beyond the body, in that direction?
  const Vec2 p = view.robot.pose.position();
  const Vec2 u = direction.normalized();
  const double r = view.robot.radius;
  const double reach = r + params_.hitGap;
  auto inCorridor = [&](Vec2 q, double qr) {
    const Vec2 d = q - p;
    const double along = d.dot(u);
    return along > 0.0 && along < reach + qr && std::abs(d.cross(u)) < r + qr;
  };
  for (const Vec2& q : view.scan) {
    if (inCorridor(q, 0.0))
      return true;
  }
  for (const MovingDisc& d : view.discs) {
    if (standing(d) && inCorridor(d.position, d.radius))
      return true;
  }
  return false;
}

Twist BugPlanner::followBoundary(const LocalView& view) const {
  const auto [q, d] = nearestObstacle(view);
  const Vec2 p = view.robot.pose.position();
  if (!std::isfinite(d))
    return steerTowards(view, goal_ - p);
  const Vec2 n = (p - q).normalized();  // away from the obstacle
  const Vec2 tangent{n.y, -n.x};        // obstacle on the right
  const double gap_err = (d - view.robot.radius) - params_.followGap;
  const Vec2 dir = tangent + (-n) * std::clamp(params_.kGap * gap_err, -1.0, 1.0);
  return steerTowards(view, dir);
}

Command BugPlanner::plan(const LocalView& view) {
  const Vec2 p = view.robot.pose.position();
  const Vec2 goal = view.goal();
  if (!initialised_ || !(goal == goal_)) {
    initialised_ = true;
    goal_ = goal;
    start_ = p;
    mode_ = BugMode::kGoToGoal;
    last_position_ = p;
  }
  const double step = fastDistance(p, last_position_);
  last_position_ = p;
  const double dg = fastDistance(p, goal_);
  if (dg <= view.goalTolerance) {
    mode_ = BugMode::kDone;
    return {{}, PlanStatus::kGoalReached, false};
  }
  if (mode_ == BugMode::kDone)
    return {{}, PlanStatus::kUnreachable, false};

  if (mode_ == BugMode::kGoToGoal) {
    if (!blockedTowards(view, goal_ - p))
      return {steerTowards(view, goal_ - p), PlanStatus::kMoving, false};
    mode_ = BugMode::kFollow;
    hit_ = p;
    ++hits_;
    leave_ = p;
    leave_goal_distance_ = dg;
    travelled_since_hit_ = 0.0;
    left_hit_area_ = false;
    toured_ = false;
  }

  travelled_since_hit_ += step;
  if (fastDistance(p, hit_) > 2.0 * params_.loopTolerance)
    left_hit_area_ = true;
  const bool back_at_hit = left_hit_area_ && fastDistance(p, hit_) < params_.loopTolerance;

  if (mode_ == BugMode::kFollow) {
    if (variant_ == BugVariant::kBug2) {
      // Leave rule: on the m-line, strictly closer to the goal than H, and free towards the goal.
      const bool on_mline = distanceToLine(start_, goal_, p) < params_.mlineTolerance;
      if (on_mline && dg < fastDistance(hit_, goal_) - params_.leaveMargin &&
          !blockedTowards(view, goal_ - p)) {
        mode_ = BugMode::kGoToGoal;
        return {steerTowards(view, goal_ - p), PlanStatus::kMoving, false};
      }
      if (back_at_hit) {
        mode_ = BugMode::kDone;  // a full tour found no leave point: the goal is enclosed
        return {{}, PlanStatus::kUnreachable, false};
      }
    } else {
      if (dg < leave_goal_distance_) {
        leave_goal_distance_ = dg;
        leave_ = p;
      }
      if (back_at_hit) {
        toured_ = true;
        mode_ = BugMode::kToLeavePoint;
      }
    }
    return {followBoundary(view), PlanStatus::kMoving, false};
  }

  // Bug1, second lap: follow on to L, then leave, unless the obstacle still blocks the goal there.
  if (fastDistance(p, leave_) < params_.loopTolerance) {
    if (blockedTowards(view, goal_ - p) && fastDistance(leave_, hit_) < params_.loopTolerance) {
      mode_ = BugMode::kDone;
      return {{}, PlanStatus::kUnreachable, false};
    }
    if (!blockedTowards(view, goal_ - p)) {
      mode_ = BugMode::kGoToGoal;
      return {steerTowards(view, goal_ - p), PlanStatus::kMoving, false};
    }
    // Blocked at L although L is not H: the goal is inside (L is the closest the boundary gets).
    mode_ = BugMode::kDone;
    return {{}, PlanStatus::kUnreachable, false};
  }
  return {followBoundary(view), PlanStatus::kMoving, false};
}

}  // namespace fleet::avoidance
