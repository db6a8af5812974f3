#include "fleet/control/path_follower.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace fleet::control {

namespace {

LyapunovParams trackingParams(LyapunovParams p) {
  p.law = PoseLaw::kSingleLaw;
  p.allowReverse = false;
  return p;
}

}  // namespace

Expected<void> PathFollowerParams::validate() const {
  if (!std::isfinite(lookahead) || lookahead <= 0.0 || !std::isfinite(searchWindow) || searchWindow <= 0.0) {
    return fleet::unexpected("invalid_lookahead", "lookahead and search_window must be finite and > 0");
  }
  if (!(goalToleranceXy > 0.0) || !(goalToleranceTheta > 0.0)) {
    return fleet::unexpected("invalid_tolerance", "goal tolerances must be > 0");
  }
  return controller.validate();
}

PathFollower::PathFollower(PathFollowerParams params)
    : params_(params), tracker_(trackingParams(params.controller)), final_(params.controller) {}

Expected<void> PathFollower::setPath(const std::vector<Vec2>& points, double final_heading) {
  if (points.empty()) {
    return fleet::unexpected("empty_path", "a path needs at least one point");
  }
  if (!std::isfinite(final_heading) ||
      std::any_of(points.begin(), points.end(), [](Vec2 p) { return !p.isFinite(); })) {
    return fleet::unexpected("non_finite_path", "path points and final heading must be finite");
  }
  points_.clear();
  cumulative_.clear();
  for (const Vec2 p : points) {
    if (!points_.empty() && distance(points_.back(), p) < 1e-9) {
      continue;
    }
    cumulative_.push_back(points_.empty() ? 0.0 : cumulative_.back() + distance(points_.back(), p));
    points_.push_back(p);
  }
  final_heading_ = wrapAngle(final_heading);
  progress_ = 0.0;
  segment_ = 0;
  tracker_.reset();
  final_.reset();
  return {};
}

Expected<void> PathFollower::setPath(const std::vector<Pose2>& poses) {
  if (poses.empty()) {
    return fleet::unexpected("empty_path", "a path needs at least one pose");
  }
  std::vector<Vec2> pts;
  pts.reserve(poses.size());
  for (const Pose2& p : poses) {
    pts.push_back(p.position());
  }
  return setPath(pts, poses.back().theta);
}

Pose2 PathFollower::pointAt(double s) const {
  if (points_.size() == 1) {
    return {points_[0].x, points_[0].y, final_heading_};
  }
  const auto it = std::upper_bound(cumulative_.begin(), cumulative_.end(), s);
  std::size_t i = it == cumulative_.begin() ? 0 : static_cast<std::size_t>(it - cumulative_.begin()) - 1;
  i = std::min(i, points_.size() - 2);
  const Vec2 a = points_[i];
  const Vec2 b = points_[i + 1];
  const double len = cumulative_[i + 1] - cumulative_[i];
  const double t = std::clamp((s - cumulative_[i]) / len, 0.0, 1.0);
  const Vec2 p = a + (b - a) * t;
  return {p.x, p.y, std::atan2(b.y - a.y, b.x - a.x)};
}

Expected<PathFollowerOutput> PathFollower::step(const Pose2& estimate) {
  if (points_.empty()) {
    return fleet::unexpected("no_path", "step() before setPath()");
  }
  if (!estimate.isFinite()) {
    return fleet::unexpected("non_finite_pose", "pose estimate is NaN/inf");
  }
  PathFollowerOutput out;
  const Vec2 p = estimate.position();
  const double total = pathLength();

  // Project onto the segments within the search window ahead; progress is monotone so the carrot never
  // jumps back to a part of the path already driven.
  double best_d2 = std::numeric_limits<double>::infinity();
  double best_s = progress_;
  std::size_t best_seg = segment_;
  if (points_.size() == 1) {
    best_d2 = (p - points_[0]).squaredNorm();
    best_s = 0.0;
  }
  for (std::size_t i = segment_; i + 1 < points_.size(); ++i) {
    if (cumulative_[i] > progress_ + params_.searchWindow) {
      break;
    }
    const Vec2 a = points_[i];
    const Vec2 ab = points_[i + 1] - a;
    const double len2 = ab.squaredNorm();
    double t = std::clamp((p - a).dot(ab) / len2, 0.0, 1.0);
    double s = cumulative_[i] + t * std::sqrt(len2);
    if (s < progress_) {
      s = progress_;
      t = (s - cumulative_[i]) / std::sqrt(len2);
    }
    const double d2 = (p - (a + ab * t)).squaredNorm();
    if (d2 < best_d2) {
      best_d2 = d2;
      best_s = s;
      best_seg = i;
    }
  }
  progress_ = std::max(progress_, best_s);
  segment_ = best_seg;
  out.progress = progress_;
  out.crossTrack = std::sqrt(best_d2);

  const double carrot = progress_ + params_.lookahead;
  const Pose2 goal{points_.back().x, points_.back().y, final_heading_};
  if (carrot >= total) {
    out.finalApproach = true;
    out.target = goal;
    const PolarError e = polarError(estimate, goal);
    if (e.rho < params_.goalToleranceXy &&
        std::abs(angleDiff(estimate.theta, goal.theta)) < params_.goalToleranceTheta) {
      out.goalReached = true;
      return out;
    }
    auto r = final_.step(estimate, goal);
    if (!r) {
      return fleet::unexpected(r.error());
    }
    out.cmd = r->cmd;
    return out;
  }
  out.target = pointAt(carrot);
  auto r = tracker_.step(estimate, out.target);
  if (!r) {
    return fleet::unexpected(r.error());
  }
  out.cmd = r->cmd;
  return out;
}

}  // namespace fleet::control
