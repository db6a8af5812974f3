#include "fleet/avoidance/elastic_strips.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>

#include "fleet/avoidance/clearance.hpp"
#include "fleet/avoidance/dynamic_window.hpp"
#include "fleet/core/angles.hpp"
#include "fleet/geometry/bvh.hpp"

namespace fleet::avoidance {

Vec2 elasticInternalForce(Vec2 prev, Vec2 cur, Vec2 next, double kC) {
  const double d_minus = fastDistance(cur, prev);
  const double d_plus = fastDistance(next, cur);
  const double sum = d_minus + d_plus;
  const double ratio = sum > 0.0 ? d_minus / sum : 0.5;
  return ((next - prev) * ratio - (cur - prev)) * kC;
}

Vec2 elasticExternalForce(Vec2 robot, Vec2 obstacle, double d_obs_min, double threshold, double kR) {
  if (!(d_obs_min < threshold))
    return {};
  return (robot - obstacle).normalized() * (kR * (threshold - d_obs_min));
}

LeftRightMinimum leftRightMinimum(std::span<const double> ranges, double dSafe) {
  LeftRightMinimum out;
  out.minLeft = dSafe;
  out.minRight = dSafe;
  const std::size_t half = ranges.size() / 2;
  for (std::size_t i = 0; i < ranges.size(); ++i) {
    const double a = ranges[i];
    if (!(a < dSafe))
      continue;
    if (i < half && a < out.minLeft) {
      out.minLeft = a;
      out.leftIndex = static_cast<int>(i);
    }
    if (i >= half && a < out.minRight) {
      out.minRight = a;
      out.rightIndex = static_cast<int>(i);
    }
  }
  out.found = out.leftIndex >= 0 || out.rightIndex >= 0;
  return out;
}

geometry::Obb2 obstacleBox(Vec2 left, Vec2 right, Vec2 heading, double dSafe) {
  // Axes: along L→R and across it; the box holds the four corners L, R, L + d·h, R + d·h (a
  // rectangle when h is square to L→R, else the rectangle around that parallelogram).
  Vec2 u = right - left;
  const double len = std::sqrt(u.squaredNorm());
  u = len > 1e-9 ? u * (1.0 / len) : heading.perp();
  const Vec2 w = u.perp();
  const Vec2 corners[4] = {left, right, left + heading * dSafe, right + heading * dSafe};
  double lo_u = std::numeric_limits<double>::infinity(), hi_u = -lo_u, lo_w = lo_u, hi_w = -lo_u;
  for (const Vec2& c : corners) {
    lo_u = std::min(lo_u, c.dot(u));
    hi_u = std::max(hi_u, c.dot(u));
    lo_w = std::min(lo_w, c.dot(w));
    hi_w = std::max(hi_w, c.dot(w));
  }
  geometry::Obb2 box;
  box.center = u * (0.5 * (lo_u + hi_u)) + w * (0.5 * (lo_w + hi_w));
  box.angle = std::atan2(u.y, u.x);
  box.half = {0.5 * (hi_u - lo_u), 0.5 * (hi_w - lo_w)};
  return box;
}

geometry::Obb2 robotBox(Vec2 robot, Vec2 next, Vec2 heading, double radius) {
  const double ahead = std::max(0.0, (next - robot).dot(heading));
  geometry::Obb2 box;
  box.center = robot + heading * (0.5 * ahead);
  box.angle = std::atan2(heading.y, heading.x);
  box.half = {0.5 * ahead + radius, radius};
  return box;
}

Expected<void> ElasticStripsParams::validate() const {
  if (!(kC >= 0.0) || !(kR >= 0.0) || !(dSafe > 0.0) || !(spacing > 0.0) || !(kOmega > 0.0) || beams < 2) {
    return fleet::unexpected("invalid_elastic_strips_params",
                             "non-negative gains, positive distances, beams >= 2");
  }
  return {};
}

Vec2 ElasticStripsPlanner::externalForce(const LocalView& view, Vec2 at) {
  const double r = view.robot.radius;
  if (variant_ == ElasticVariant::kOriginal) {
    // Single nearest reading, threshold d_o = dSafe + d_r on the centre distance (eq. 2.20).
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
    return elasticExternalForce(at, obs, best, params_.dSafe + r, params_.kR);
  }
  // Two-sided variant: a BVH over the readings answers "what lies within dSafe of the body", the
  // hits are binned into a scan (left half = bearings 0..π, right half = π..2π relative to the
  // heading), and the nearest left and right readings each push with threshold dSafe on the
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
  std::vector<std::uint8_t> moving(static_cast<std::size_t>(beams), 0);  // the reading is a disc
  for (const int idx : bvh.overlappingDisc(at, params_.dSafe + r)) {
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
      moving[static_cast<std::size_t>(b)] = static_cast<std::size_t>(idx) >= view.scan.size() ? 1 : 0;
    }
  }
  const LeftRightMinimum m = leftRightMinimum(ranges, params_.dSafe);
  if (!m.found) {
    contact_ = Contact::kNone;
    return {};
  }
  if (m.leftIndex < 0 || m.rightIndex < 0) {
    // One collision point: no boxes, the original Elastic Strips (thesis §2.3.1): the nearest
    // reading, threshold d_o = dSafe + d_r on the centre distance.
    contact_ = Contact::kOnePoint;
    const Vec2 q = pts[static_cast<std::size_t>(m.leftIndex >= 0 ? m.leftIndex : m.rightIndex)];
    return elasticExternalForce(at, q, fastDistance(at, q), params_.dSafe + r, params_.kR);
  }
  // Two collision points: OBB-O from them, OBB-R from the robot's size and direction of motion; the
  // two forces act only when the boxes meet (the obstacles lie in this step's way).
  const Vec2 L = pts[static_cast<std::size_t>(m.leftIndex)];
  const Vec2 R = pts[static_cast<std::size_t>(m.rightIndex)];
  const Vec2 h{std::cos(theta), std::sin(theta)};
  const Vec2 robot = view.robot.pose.position();
  if (!geometry::overlaps(robotBox(robot, at, h, r), obstacleBox(L, R, h, params_.dSafe))) {
    contact_ = Contact::kBoxesApart;
    return {};
  }
  contact_ = Contact::kBoxesMeet;
  const Vec2 f_left = elasticExternalForce(at, L, m.minLeft, params_.dSafe, params_.kR);
  const Vec2 f_right = elasticExternalForce(at, R, m.minRight, params_.dSafe, params_.kR);
  const bool discs = moving[static_cast<std::size_t>(m.leftIndex)] != 0 ||
                     moving[static_cast<std::size_t>(m.rightIndex)] != 0;
  if (discs || fastDistance(L, R) >= 2.0 * r)
    return f_left + f_right;  // a gap the robot fits through, or robots/people: both push (2.28)
  // Static readings too close together to pass between: one obstacle to go around. Their symmetric
  // pushes would cancel sideways and hold the robot in front of it (the seed's open question 6), so
  // only the nearer reading pushes, towards the side where the obstacle recedes; a tie passes right.
  return m.minLeft <= m.minRight ? f_left : f_right;
}

Command ElasticStripsPlanner::plan(const LocalView& view) {
  const Vec2 p = view.robot.pose.position();
  if (fastDistance(p, view.goal()) <= view.goalTolerance)
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
  const Vec2 f_int = elasticInternalForce(prev, p, next, params_.kC);
  // No external force on the strip's end point: the goal is the strip's fixed end (a wall just
  // behind a goal would otherwise push the last point back and the robot would stop short of it).
  const bool end_point = fastDistance(next, view.goal()) < 1e-9;
  contact_ = Contact::kNone;  // stays so for the original variant and at the strip's end
  const Vec2 f_ext = end_point ? Vec2{} : externalForce(view, next);
  force_ = f_int + f_ext;
  target_ = next + force_;
  const Vec2 d = target_ - p;
  const double err = angleDiff(std::atan2(d.y, d.x), view.robot.pose.theta);
  const double dist = std::sqrt(d.squaredNorm());
  const double v =
      std::min(view.limits.vMax, dist / std::max(view.dt * 5.0, 1e-3)) * std::max(0.0, std::cos(err));
  const double w = std::clamp(params_.kOmega * err, -view.limits.omegaMax, view.limits.omegaMax);
  return {{v, w}, PlanStatus::kMoving, false};
}

}  // namespace fleet::avoidance
