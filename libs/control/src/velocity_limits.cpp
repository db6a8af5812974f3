#include "fleet/control/velocity_limits.hpp"

#include <algorithm>
#include <cmath>

namespace fleet::control {

Expected<void> VelocityLimits::validate() const {
  const bool finite = std::isfinite(v_max) && std::isfinite(v_min) && std::isfinite(omega_max) &&
                      std::isfinite(accel_max) && std::isfinite(alpha_max);
  if (!finite) {
    return fleet::unexpected("invalid_limits", "velocity limits must be finite");
  }
  if (v_max < 0.0 || v_min > 0.0) {
    return fleet::unexpected("invalid_limits", "need v_min <= 0 <= v_max");
  }
  if (omega_max < 0.0 || accel_max <= 0.0 || alpha_max <= 0.0) {
    return fleet::unexpected("invalid_limits", "need omega_max >= 0, accel_max > 0, alpha_max > 0");
  }
  return {};
}

namespace {

Twist clampSpeed(const VelocityLimits& l, Twist t, bool& saturated) {
  double scale = 1.0;
  if (t.v > l.v_max) {
    scale = std::min(scale, l.v_max / t.v);
  } else if (t.v < l.v_min) {
    scale = std::min(scale, l.v_min / t.v);
  }
  if (std::abs(t.omega) > l.omega_max) {
    scale = std::min(scale, l.omega_max / std::abs(t.omega));
  }
  if (scale < 1.0) {
    saturated = true;
    return {t.v * scale, t.omega * scale};
  }
  return t;
}

double rateLimit(double from, double to, double max_step, bool& saturated) {
  const double step = to - from;
  if (step > max_step) {
    saturated = true;
    return from + max_step;
  }
  if (step < -max_step) {
    saturated = true;
    return from - max_step;
  }
  return to;
}

}  // namespace

LimitedTwist applyLimits(const VelocityLimits& limits, Twist desired, Twist previous, double dt) {
  LimitedTwist out;
  if (!desired.isFinite()) {
    out.rejected = true;
    desired = {};
  }
  if (!previous.isFinite()) {
    previous = {};
  }
  bool ignored = false;
  previous = clampSpeed(limits, previous, ignored);
  if (!std::isfinite(dt) || dt <= 0.0) {
    out.twist = previous;
    return out;
  }
  const Twist target = clampSpeed(limits, desired, out.saturated);
  out.twist.v = rateLimit(previous.v, target.v, limits.accel_max * dt, out.saturated);
  out.twist.omega = rateLimit(previous.omega, target.omega, limits.alpha_max * dt, out.saturated);
  return out;
}

}  // namespace fleet::control
