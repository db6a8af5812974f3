#include "fleet/avoidance/safety_layer.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include "fleet/avoidance/clearance.hpp"

#include "fleet/control/diff_drive_kinematics.hpp"

namespace fleet::avoidance {

namespace {

double approach(double from, double to, double max_step) {
  return from + std::clamp(to - from, -max_step, max_step);
}

// Surface clearance of the robot at p to everything (or the discs only), discs advanced to time tau.
double clearanceAt(const LocalView& view, Vec2 p, double tau, bool withScan = true) {
  double best = std::numeric_limits<double>::infinity();
  const double r = view.robot.radius;
  if (withScan) {
    for (const Vec2& q : view.scan)
      best = std::min(best, (p - q).squaredNorm());
  }
  best = std::sqrt(best) - r;
  for (const MovingDisc& d : view.discs) {
    best = std::min(best, fastDistance(p, d.position + d.velocity * tau) - r - d.radius);
  }
  return best;
}

}  // namespace

Expected<void> SafetyParams::validate() const {
  if (!(stopMargin >= 0.0) || !(slowMargin >= stopMargin) || !(slowTime >= 0.0) ||
      !(slowRatio > 0.0 && slowRatio <= 1.0) || !(sampleStep > 0.0)) {
    return fleet::unexpected("invalid_safety_params",
                             "need 0 <= stop_margin <= slow_margin, slow_time >= 0, 0 < slow_ratio <= 1, "
                             "sample_step > 0");
  }
  return {};
}

bool SafetyLayer::profileSafe(const LocalView& view, Twist cmd) const {
  const auto& lim = view.limits;
  const double h = params_.sampleStep;
  Pose2 pose = view.robot.pose;
  Twist tw = view.robot.twist;
  double prev = clearanceAt(view, pose.position(), 0.0);
  double t = 0.0;
  // One cycle towards cmd, then brake to a stop at accelMax while keeping the turn rate.
  const double brake_time = (std::abs(tw.v) + lim.accelMax * view.dt) / std::max(lim.accelMax, 1e-9);
  const double total = view.dt + brake_time + h;
  while (t < total) {
    const bool first_cycle = t < view.dt - 1e-12;
    const Twist target = first_cycle ? cmd : Twist{0.0, cmd.omega};
    tw.v = approach(tw.v, target.v, lim.accelMax * h);
    tw.omega = approach(tw.omega, target.omega, lim.alphaMax * h);
    pose = control::DiffDriveKinematics::integrateExact(pose, tw, h);
    t += h;
    const double c = clearanceAt(view, pose.position(), t);
    if (c < params_.stopMargin && c < prev - 1e-9)
      return false;
    prev = c;
    if (!first_cycle && tw.v == 0.0 && view.discs.empty())
      break;
  }
  return true;
}

double SafetyLayer::timeToCollision(const LocalView& view, Twist cmd, double horizon) const {
  const double h = params_.sampleStep;
  for (double t = h; t <= horizon + 1e-12; t += h) {
    const Pose2 p = control::DiffDriveKinematics::integrateExact(view.robot.pose, cmd, t);
    if (clearanceAt(view, p.position(), t) <= 0.0)
      return t;
  }
  return std::numeric_limits<double>::infinity();
}

SafetyResult SafetyLayer::filter(const LocalView& view, Twist request) const {
  SafetyResult out;
  const auto& lim = view.limits;
  if (!request.isFinite()) {
    out.overruled = true;
    out.blocked = true;
    return out;
  }
  Twist req{std::clamp(request.v, lim.vMin, lim.vMax),
            std::clamp(request.omega, -lim.omegaMax, lim.omegaMax)};
  out.timeToCollision = timeToCollision(view, req, params_.slowTime);
  static constexpr std::array<double, 5> kScales{1.0, 0.75, 0.5, 0.25, 0.0};
  bool found = false;
  for (const double s : kScales) {
    const Twist cand{req.v * s, req.omega};
    if (profileSafe(view, cand)) {
      out.twist = cand;
      found = true;
      break;
    }
  }
  if (!found) {
    out.twist = {};
    out.blocked = true;
  }
  // Slow-down zone: something within slowMargin of where the (possibly scaled) command goes.
  if (found && out.twist.v != 0.0) {
    const double cap = params_.slowRatio * std::max(lim.vMax, -lim.vMin);
    if (std::abs(out.twist.v) > cap) {
      double min_c = std::numeric_limits<double>::infinity();
      for (double t = params_.sampleStep; t <= params_.slowTime + 1e-12; t += params_.sampleStep) {
        const Pose2 p = control::DiffDriveKinematics::integrateExact(view.robot.pose, out.twist, t);
        min_c = std::min(min_c, clearanceAt(view, p.position(), t, params_.slowForStatic));
      }
      if (min_c < params_.slowMargin) {
        out.twist.v = std::copysign(cap, out.twist.v);
        out.slowed = true;
      }
    }
  }
  out.overruled = out.twist != req || req != request;
  return out;
}

Command SafePlanner::plan(const LocalView& view) {
  Command c = inner_->plan(view);
  last_ = safety_.filter(view, c.twist);
  c.overruled = last_.overruled;
  c.twist = last_.twist;
  if (last_.blocked && c.status == PlanStatus::kMoving)
    c.status = PlanStatus::kBlocked;
  return c;
}

}  // namespace fleet::avoidance
