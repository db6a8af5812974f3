#include "fleet/avoidance/rotation_shim.hpp"

#include <algorithm>
#include <cmath>

#include "fleet/avoidance/clearance.hpp"
#include "fleet/avoidance/dynamic_window.hpp"
#include "fleet/core/angles.hpp"

namespace fleet::avoidance {

Expected<void> RotationShimParams::validate() const {
  if (!(startAngle > 0.0 && startAngle < kPi) || !(stopAngle > 0.0 && stopAngle <= startAngle) ||
      !(lookahead > 0.0) || !(omega > 0.0)) {
    return fleet::unexpected("invalid_rotation_shim_params",
                             "0 < stop_angle <= start_angle < pi, lookahead > 0, omega > 0");
  }
  return {};
}

Command RotationShim::plan(const LocalView& view) {
  const Vec2 p = view.robot.pose.position();
  // Close to the goal the goal pose is the wrapped planner's business (it may approach it sideways).
  if (view.path.empty() || fastDistance(p, view.goal()) <= params_.lookahead) {
    rotating_ = false;
    return inner_->plan(view);
  }
  const Vec2 target = carrotOnPath(view.path, p, params_.lookahead);
  const double err = angleDiff(std::atan2(target.y - p.y, target.x - p.x), view.robot.pose.theta);
  rotating_ = std::abs(err) > (rotating_ ? params_.stopAngle : params_.startAngle);
  if (!rotating_)
    return inner_->plan(view);
  const double w = std::min(params_.omega, view.limits.omegaMax);
  return {{0.0, err > 0.0 ? w : -w}, PlanStatus::kMoving, false};
}

}  // namespace fleet::avoidance
