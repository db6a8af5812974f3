#include "fleet/avoidance/elastic_strips.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "fleet/avoidance/clearance.hpp"
#include "fleet/avoidance/dynamic_window.hpp"
#include "fleet/core/angles.hpp"
#include "fleet/geometry/bvh.hpp"

namespace fleet::avoidance {

Vec2 elasticInternalForce(Vec2 prev, Vec2 cur, Vec2 next, double k_c) {
  const double d_minus = fastDistance(cur, prev);
  const double d_plus = fastDistance(next, cur);
  const double sum = d_minus + d_plus;
  const double ratio = sum > 0.0 ? d_minus / sum : 0.5;
  return ((next - prev) * ratio - (cur - prev)) * k_c;
}

Vec2 elasticExternalForce(Vec2 robot, Vec2 obstacle, double d_obs_min, double threshold, double k_r) {
  if (!(d_obs_min < threshold))
    return {};
  return (robot - obstacle).normalized() * (k_r * (threshold - d_obs_min));
}

LeftRightMinimum leftRightMinimum(std::span<const double> ranges, double d_safe) {
  LeftRightMinimum out;
  out.min_left = d_safe;
  out.min_right = d_safe;
  const std::size_t half = ranges.size() / 2;
  for (std::size_t i = 0; i < ranges.size(); ++i) {
    const double a = ranges[i];
    if (!(a < d_safe))
      continue;
    if (i < half && a < out.min_left) {
      out.min_left = a;
      out.left_index = static_cast<int>(i);
    }
    if (i >= half && a < out.min_right) {
      out.min_right = a;
      out.right_index = static_cast<int>(i);
    }
  }
  out.found = out.left_index >= 0 || out.right_index >= 0;
  return out;
}

Expected<void> ElasticStripsParams::validate() const {
  if (!(k_c >= 0.0) || !(k_r >= 0.0) || !(d_safe > 0.0) || !(spacing > 0.0) || !(k_omega > 0.0) ||
      beams < 2) {
    return fleet::unexpected("invalid_elastic_strips_params",
                             "non-negative gains, positive distances, beams >= 2");
  }
  return {};
}

Vec2 ElasticStripsPlanner::externalForce(const LocalView& view, Vec2 at) const {
  const double r = view.robot.radius;
  if (variant_ == ElasticVariant::kOriginal) {
    // Single nearest reading, threshold d_o = d_safe + d_r on the centre distance (eq. 2.20).
    double best = std::numeric_limits<double>::infinity();
    Vec2 obs;
    for (const Vec2& q : view.scan) {
      const double d = fastDistance(at, q);
      if (d < best) {
        best = d;
        obs = q;
      }
    }
    for (const MovingDisc& d : view.discs) {
      const double dd = fastDistance(at, d.position) - d.radius;
      if (dd < best) {
        best = dd;
        obs = d.position;
      }
    }
    return elasticExternalForce(at, obs, best, params_.d_safe + r, params_.k_r);
  }
  // Two-sided variant: a BVH over the readings answers "what lies within d_safe of the body", the
  // hits are binned into a scan (left half = bearings 0..π, right half = π..2π relative to the
  // heading), and the nearest left and right readings each push with threshold d_safe on the
  // surface distance (eq. 2.27, 2.28).
  std::vector<geometry::Primitive> prims;
  prims.reserve(view.scan.size() + view.discs.size());
  for (const Vec2& q : view.scan)
    prims.push_back(geometry::Primitive::makeDisc(q, 0.0));
  for (const MovingDisc& d : view.discs)
    prims.push_back(geometry::Primitive::makeDisc(d.position, d.radius));
  if (prims.empty())
    return {};
  const geometry::Bvh2 bvh(prims);
  const double theta = view.robot.pose.theta;
  const int beams = params_.beams;
  std::vector<double> ranges(static_cast<std::size_t>(beams), std::numeric_limits<double>::infinity());
  std::vector<Vec2> pts(static_cast<std::size_t>(beams));
  for (const int idx : bvh.overlappingDisc(at, params_.d_safe + r)) {
    const auto& pr = prims[static_cast<std::size_t>(idx)];
    const Vec2 rel = pr.center - at;
    const double dist = std::sqrt(rel.squaredNorm()) - pr.radius - r;
    double bearing = angleDiff(std::atan2(rel.y, rel.x), theta);
    if (bearing < 0.0)
      bearing += 2.0 * kPi;
    const int b = std::min(beams - 1, static_cast<int>(bearing / (2.0 * kPi) * static_cast<double>(beams)));
    if (dist < ranges[static_cast<std::size_t>(b)]) {
      ranges[static_cast<std::size_t>(b)] = dist;
      pts[static_cast<std::size_t>(b)] = pr.center;
    }
  }
  const LeftRightMinimum m = leftRightMinimum(ranges, params_.d_safe);
  if (!m.found)
    return {};
  Vec2 f;
  if (m.left_index >= 0) {
    f += elasticExternalForce(at, pts[static_cast<std::size_t>(m.left_index)], m.min_left, params_.d_safe,
                              params_.k_r);
  }
  if (m.right_index >= 0) {
    f += elasticExternalForce(at, pts[static_cast<std::size_t>(m.right_index)], m.min_right, params_.d_safe,
                              params_.k_r);
  }
  return f;
}

Command ElasticStripsPlanner::plan(const LocalView& view) {
  const Vec2 p = view.robot.pose.position();
  if (fastDistance(p, view.goal()) <= view.goal_tolerance)
    return {{}, PlanStatus::kGoalReached, false};
  // Strip control points: P^{j−1} = where the robot was last cycle, P^j = the robot, P^{j+1} = the
  // next strip point along the path, `spacing` ahead.
  Vec2 next;
  if (view.path.size() < 2) {
    const Vec2 g = view.goal();
    const double dg = fastDistance(p, g);
    next = dg <= params_.spacing ? g : p + (g - p) * (params_.spacing / dg);
  } else {
    next = carrotOnPath(view.path, p, params_.spacing);
  }
  const Vec2 prev = have_prev_ && fastDistance(prev_, p) > 1e-6 ? prev_ : p - (next - p);
  prev_ = p;
  have_prev_ = true;
  const Vec2 f_int = elasticInternalForce(prev, p, next, params_.k_c);
  // No external force on the strip's end point: the goal is the strip's fixed end (a wall just
  // behind a goal would otherwise push the last point back and the robot would stop short of it).
  const bool end_point = fastDistance(next, view.goal()) < 1e-9;
  const Vec2 f_ext = end_point ? Vec2{} : externalForce(view, next);
  force_ = f_int + f_ext;
  target_ = next + force_;
  const Vec2 d = target_ - p;
  const double err = angleDiff(std::atan2(d.y, d.x), view.robot.pose.theta);
  const double dist = std::sqrt(d.squaredNorm());
  const double v =
      std::min(view.limits.v_max, dist / std::max(view.dt * 5.0, 1e-3)) * std::max(0.0, std::cos(err));
  const double w = std::clamp(params_.k_omega * err, -view.limits.omega_max, view.limits.omega_max);
  return {{v, w}, PlanStatus::kMoving, false};
}

}  // namespace fleet::avoidance
