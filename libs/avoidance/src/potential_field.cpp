#include "fleet/avoidance/potential_field.hpp"

#include <algorithm>
#include <cmath>

#include "fleet/avoidance/clearance.hpp"
#include "fleet/core/angles.hpp"

namespace fleet::avoidance {

Vec2 attractiveForce(Vec2 q, Vec2 goal, double kAtt) {
  return (q - goal) * (-kAtt);
}

Vec2 repulsiveForce(Vec2 q, Vec2 q_obs, double rho, double kRep, double rho0) {
  if (!(rho <= rho0))
    return {};
  rho = std::max(rho, 1e-3);  // inside the body: saturate rather than divide by zero
  const Vec2 dir = (q - q_obs).normalized();
  return dir * (kRep * (1.0 / rho - 1.0 / rho0) / (rho * rho));
}

Expected<void> PotentialFieldParams::validate() const {
  if (!(kAtt > 0.0) || !(kRep >= 0.0) || !(rho0 > 0.0) || !(attractCap > 0.0) || !(kV > 0.0) ||
      !(kOmega > 0.0) || stuckCycles < 1) {
    return fleet::unexpected("invalid_potential_field_params", "gains, rho0 and caps must be positive");
  }
  return {};
}

Vec2 totalForce(const LocalView& view, const PotentialFieldParams& params) {
  const Vec2 q = view.robot.pose.position();
  Vec2 f = attractiveForce(q, view.goal(), params.kAtt);
  const double n = std::sqrt(f.squaredNorm());
  if (n > params.attractCap)
    f *= params.attractCap / n;
  const double r = view.robot.radius;
  for (const Vec2& p : view.scan)
    f += repulsiveForce(q, p, fastDistance(q, p) - r, params.kRep, params.rho0);
  for (const MovingDisc& d : view.discs) {
    const double dc = fastDistance(q, d.position);
    f += repulsiveForce(q, d.position, dc - d.radius - r, params.kRep, params.rho0);
  }
  return f;
}

PotentialFieldPlanner::PotentialFieldPlanner(PotentialFieldParams params)
    : params_(params), escape_(BugVariant::kBug2) {}

void PotentialFieldPlanner::reset() {
  escape_.reset();
  escaping_ = false;
  no_progress_ = 0;
  have_best_ = false;
}

Command PotentialFieldPlanner::plan(const LocalView& view) {
  const Vec2 q = view.robot.pose.position();
  const double dg = fastDistance(q, view.goal());
  if (dg <= view.goalTolerance)
    return {{}, PlanStatus::kGoalReached, false};

  if (escaping_) {
    Command c = escape_.plan(view);
    // Bug2 is back in go-to-goal mode: it has left the boundary on the m-line closer to the goal,
    // past the trap, so the field takes over again.
    if (escape_.mode() == BugMode::kGoToGoal && escape_.hits() > 0) {
      escaping_ = false;
      have_best_ = false;
    } else {
      return c;
    }
  }

  const Vec2 f = totalForce(view, params_);
  const double fn = std::sqrt(f.squaredNorm());
  if (!have_best_ || dg < best_goal_distance_ - params_.stuckProgress) {
    have_best_ = true;
    best_goal_distance_ = dg;
    no_progress_ = 0;
  } else {
    ++no_progress_;
  }
  if (fn < params_.stuckForce || no_progress_ > params_.stuckCycles) {
    ++stuck_detections_;
    no_progress_ = 0;
    have_best_ = false;
    if (params_.escapeWithBug2) {
      escaping_ = true;
      escape_.reset();
      // Bug2 starts in go-to-goal, sees the blocking boundary and starts following it.
      return {escape_.plan(view).twist, PlanStatus::kStuck, false};
    }
    return {{}, PlanStatus::kStuck, false};
  }
  const double err = angleDiff(std::atan2(f.y, f.x), view.robot.pose.theta);
  const double v = std::min(view.limits.vMax, params_.kV * fn) * std::max(0.0, std::cos(err));
  const double w = std::clamp(params_.kOmega * err, -view.limits.omegaMax, view.limits.omegaMax);
  return {{v, w}, PlanStatus::kMoving, false};
}

}  // namespace fleet::avoidance
