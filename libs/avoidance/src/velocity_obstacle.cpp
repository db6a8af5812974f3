#include "fleet/avoidance/velocity_obstacle.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "fleet/avoidance/clearance.hpp"
#include "fleet/avoidance/dynamic_window.hpp"
#include "fleet/core/angles.hpp"

namespace fleet::avoidance {

double discTimeToCollision(Vec2 rel, Vec2 vel, double R) {
  const double c = rel.squaredNorm() - R * R;
  if (c <= 0.0)
    return 0.0;
  const double a = vel.squaredNorm();
  const double b = rel.dot(vel);  // closing when > 0
  if (a <= 0.0 || b <= 0.0)
    return std::numeric_limits<double>::infinity();
  const double disc = b * b - a * c;
  if (disc < 0.0)
    return std::numeric_limits<double>::infinity();
  return (b - std::sqrt(disc)) / a;
}

Expected<void> VelocityObstacleParams::validate() const {
  if (headings < 1 || speeds < 1 || wTtc < 0.0 || !(horizon > 0.0) || margin < 0.0 || !(kOmega > 0.0)) {
    return fleet::unexpected("invalid_vo_params", "counts >= 1, horizon > 0, non-negative weights");
  }
  return {};
}

Command VelocityObstaclePlanner::plan(const LocalView& view) {
  const Pose2& pose = view.robot.pose;
  const Vec2 p = pose.position();
  const Vec2 goal = view.goal();
  const double dg = fastDistance(p, goal);
  if (dg <= view.goalTolerance)
    return {{}, PlanStatus::kGoalReached, false};
  const double vmax = view.limits.vMax;
  const Vec2 carrot = carrotOnPath(view.path, p, 1.5);
  // Slow down on the last stretch so the goal tolerance is not overshot.
  const Vec2 v_pref = (carrot - p).normalized() * std::min(vmax, dg / 1.0);
  const double r = view.robot.radius + params_.margin;

  // Is anything on a collision course with the preferred velocity?
  bool conflict = false;
  for (const MovingDisc& d : view.discs) {
    if (discTimeToCollision(d.position - p, v_pref - d.velocity, r + d.radius) < params_.horizon)
      conflict = true;
  }
  Vec2 best_v;
  double best_cost = std::numeric_limits<double>::infinity();
  auto evaluate = [&](Vec2 cand) {
    double ttc = std::numeric_limits<double>::infinity();
    for (const MovingDisc& d : view.discs) {
      ttc = std::min(ttc, discTimeToCollision(d.position - p, cand - d.velocity, r + d.radius));
    }
    for (const Vec2& q : view.scan)
      ttc = std::min(ttc, discTimeToCollision(q - p, cand, r));
    const double pen = ttc < params_.horizon ? params_.wTtc / std::max(ttc, 1e-3) : 0.0;
    double cost = pen + std::sqrt((cand - v_pref).squaredNorm());
    if (params_.rightBias > 0.0 && conflict) {
      cost += params_.rightBias * std::max(0.0, v_pref.normalized().cross(cand));
    }
    if (cost < best_cost) {
      best_cost = cost;
      best_v = cand;
    }
  };
  evaluate(v_pref);
  evaluate({});
  for (int i = 0; i < params_.headings; ++i) {
    const double a = pose.theta + 2.0 * kPi * static_cast<double>(i) / static_cast<double>(params_.headings);
    for (int k = 1; k <= params_.speeds; ++k) {
      evaluate(Vec2{std::cos(a), std::sin(a)} *
               (vmax * static_cast<double>(k) / static_cast<double>(params_.speeds)));
    }
  }
  const double speed = std::sqrt(best_v.squaredNorm());
  if (speed < 1e-9)
    return {{}, PlanStatus::kMoving, false};
  const double err = angleDiff(std::atan2(best_v.y, best_v.x), pose.theta);
  const double v = speed * std::max(0.0, std::cos(err));
  const double w = std::clamp(params_.kOmega * err, -view.limits.omegaMax, view.limits.omegaMax);
  return {{v, w}, PlanStatus::kMoving, false};
}

}  // namespace fleet::avoidance
