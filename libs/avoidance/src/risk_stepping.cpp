#include "fleet/avoidance/risk_stepping.hpp"

#include <algorithm>
#include <cmath>

#include "fleet/avoidance/clearance.hpp"
#include "fleet/core/angles.hpp"
#include "fleet/risk/query.hpp"

namespace fleet::avoidance {

RiskLookup riskLookup(const risk::ProbabilityGrid& grid) {
  return [&grid](Vec2 p) {
    const auto r = risk::riskAt(grid, p);
    return r ? r->risk : 0.0;
  };
}

Expected<void> RiskSteppingParams::validate() const {
  if (!(step_time > 0.0) || candidates < 1 || !(fan >= 0.0) || risk_samples < 1 || w_progress < 0.0 ||
      min_clearance < 0.0 || !(k_omega > 0.0)) {
    return fleet::unexpected("invalid_risk_stepping_params", "positive step, counts and gains");
  }
  return {};
}

SteppingChoice RiskSteppingPlanner::choose(const LocalView& view) const {
  const Vec2 p = view.robot.pose.position();
  const Vec2 goal = view.goal();
  const double dg = fastDistance(p, goal);
  const double step = std::min(view.limits.v_max * params_.step_time, dg);
  const double base = std::atan2(goal.y - p.y, goal.x - p.x);
  const double r = view.robot.radius;
  // Where the robot already is closer than min_clearance, accept any candidate that does not get
  // closer still, so it can always leave.
  const double here = arcClearance({p.x, p.y, 0.0}, {0.0, 0.0}, 0.0, view.scan, r, 1.0);
  const double threshold = std::min(params_.min_clearance, here - 1e-6);
  SteppingChoice best;
  double best_score = -1e300;
  for (int i = 0; i < params_.candidates; ++i) {
    const double frac =
        params_.candidates == 1 ? 0.5 : static_cast<double>(i) / static_cast<double>(params_.candidates - 1);
    const double a = base + params_.fan * (2.0 * frac - 1.0);
    const Vec2 c = p + Vec2{std::cos(a), std::sin(a)} * step;
    // Reachable: the straight move keeps clear of scan points and of discs advanced in time.
    const Pose2 seg_start{p.x, p.y, a};
    double clr = arcClearance(seg_start, {step, 0.0}, 1.0, view.scan, r, 1.0);
    const double t_move = step / std::max(view.limits.v_max, 1e-9);
    for (int k = 0; k <= 4; ++k) {
      const double s = static_cast<double>(k) / 4.0;
      const Vec2 at = p + (c - p) * s;
      for (const MovingDisc& d : view.discs) {
        clr = std::min(clr, fastDistance(at, d.position + d.velocity * (s * t_move)) - r - d.radius);
      }
    }
    if (clr < threshold || clr <= 0.0)
      continue;
    double pmax = 0.0;
    for (int k = 1; k <= params_.risk_samples; ++k) {
      pmax = std::max(pmax, view.riskAt(p + (c - p) * (static_cast<double>(k) /
                                                       static_cast<double>(params_.risk_samples))));
    }
    const double safety = 1.0 - pmax;
    const double progress = (dg - fastDistance(c, goal)) / std::max(step, 1e-9);  // in [−1, 1]
    const double score = safety + params_.w_progress * progress;
    if (score > best_score) {
      best_score = score;
      best = {c, safety, true};
    }
  }
  return best;
}

Command RiskSteppingPlanner::plan(const LocalView& view) {
  const Vec2 p = view.robot.pose.position();
  if (fastDistance(p, view.goal()) <= view.goal_tolerance)
    return {{}, PlanStatus::kGoalReached, false};
  const SteppingChoice c = choose(view);
  if (!c.found)
    return {{}, PlanStatus::kBlocked, false};
  const double err = angleDiff(std::atan2(c.point.y - p.y, c.point.x - p.x), view.robot.pose.theta);
  const double dist = fastDistance(p, c.point);
  const double v = std::min(view.limits.v_max, dist / params_.step_time) * std::max(0.0, std::cos(err));
  const double w = std::clamp(params_.k_omega * err, -view.limits.omega_max, view.limits.omega_max);
  return {{v, w}, PlanStatus::kMoving, false};
}

}  // namespace fleet::avoidance
