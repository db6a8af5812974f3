#include "fleet/control/velocity_limits.hpp"

#include <algorithm>
#include <cmath>

namespace fleet::control {

Expected<void> VelocityLimits::validate() const {
  const bool finite = std::isfinite(vMax) && std::isfinite(vMin) && std::isfinite(omegaMax) &&
                      std::isfinite(accelMax) && std::isfinite(alphaMax);
  if (!finite) {
    return fleet::unexpected("invalid_limits", "velocity limits must be finite");
  }
  if (vMax < 0.0 || vMin > 0.0) {
    return fleet::unexpected("invalid_limits", "need v_min <= 0 <= v_max");
  }
  if (omegaMax < 0.0 || accelMax <= 0.0 || alphaMax <= 0.0) {
    return fleet::unexpected("invalid_limits", "need omega_max >= 0, accel_max > 0, alpha_max > 0");
  }
  return {};
}

namespace {

Twist clampSpeed(const VelocityLimits& l, Twist t, bool& saturated) {
  double scale = 1.0;
  if (t.v > l.vMax) {
    scale = std::min(scale, l.vMax / t.v);
  } else if (t.v < l.vMin) {
    scale = std::min(scale, l.vMin / t.v);
  }
  if (std::abs(t.omega) > l.omegaMax) {
    scale = std::min(scale, l.omegaMax / std::abs(t.omega));
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
  out.twist.v = rateLimit(previous.v, target.v, limits.accelMax * dt, out.saturated);
  out.twist.omega = rateLimit(previous.omega, target.omega, limits.alphaMax * dt, out.saturated);
  return out;
}

}  // namespace fleet::control
