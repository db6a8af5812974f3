#include "fleet/control/lyapunov_pose_controller.hpp"

#include <cmath>

namespace fleet::control {

PolarError polarError(const Pose2& pose, const Pose2& goal) {
  const double dx = goal.x - pose.x;
  const double dy = goal.y - pose.y;
  const double bearing = std::atan2(dy, dx);
  return {std::hypot(dx, dy), wrapAngle(bearing - pose.theta), wrapAngle(bearing - goal.theta)};
}

double lyapunovGlobal(const PolarError& e, double h) {
  return 0.5 * e.rho * e.rho + 0.5 * (e.alpha * e.alpha + h * e.phi * e.phi);
}

Twist globalLaw(const PolarError& e, const LyapunovGains& g) {
  const double ca = std::cos(e.alpha);
  // sin α/α → 1; the series keeps the law smooth through α = 0.
  const double sinc = std::abs(e.alpha) < 1e-6 ? 1.0 - e.alpha * e.alpha / 6.0 : std::sin(e.alpha) / e.alpha;
  return {g.kV * e.rho * ca, g.kAlpha * e.alpha + g.kV * ca * sinc * (e.alpha + g.h * e.phi)};
}

Expected<void> LyapunovParams::validate() const {
  const bool positive = gains.kV > 0.0 && gains.kAlpha > 0.0 && gains.kTheta > 0.0 && gains.h > 0.0;
  if (!positive || !std::isfinite(gains.kV) || !std::isfinite(gains.kAlpha) || !std::isfinite(gains.kTheta) ||
      !std::isfinite(gains.h)) {
    return fleet::unexpected("invalid_gains", "k_v, k_alpha, k_theta and h must be finite and > 0");
  }
  if (!(epsRho >= 0.0) || !(epsTheta >= 0.0) || !std::isfinite(epsRho) || !std::isfinite(epsTheta)) {
    return fleet::unexpected("invalid_region", "eps_rho and eps_theta must be finite and >= 0");
  }
  if (!(localExitFactor >= 1.0) || !std::isfinite(localExitFactor)) {
    return fleet::unexpected("invalid_region", "local_exit_factor must be finite and >= 1");
  }
  if (!(reverseHysteresis >= 0.0) || reverseHysteresis >= 0.5 * kPi) {
    return fleet::unexpected("invalid_hysteresis", "reverse_hysteresis must be in [0, pi/2)");
  }
  return {};
}

LyapunovPoseController::LyapunovPoseController(LyapunovParams params) : params_(params) {}

Expected<PoseControlOutput> LyapunovPoseController::step(const Pose2& estimate, const Pose2& goal) {
  if (!estimate.isFinite() || !goal.isFinite()) {
    return fleet::unexpected("non_finite_pose", "pose estimate or goal is NaN/inf");
  }
  PoseControlOutput out;
  out.error = polarError(estimate, goal);
  const LyapunovGains& g = params_.gains;
  const double theta_e = angleDiff(estimate.theta, goal.theta);

  if (in_local_ && !(goal == local_goal_)) {
    in_local_ = false;
  }
  const double grow = in_local_ ? params_.localExitFactor : 1.0;
  in_local_ = params_.law == PoseLaw::kTwoRegion && out.error.rho < grow * params_.epsRho &&
              std::abs(theta_e) < grow * params_.epsTheta;
  if (in_local_) {
    local_goal_ = goal;
    // Ω_L: φ and α are meaningless this close (they follow the feedback noise), so only the heading error
    // is driven to zero; ρ·cos α is the signed projection of the goal offset on the heading, so the
    // same v law also backs up when the goal is behind.
    out.region = ControlRegion::kLocal;
    out.cmd = {g.kV * out.error.rho * std::cos(out.error.alpha), -g.kTheta * theta_e};
    out.lyapunov = 0.5 * out.error.rho * out.error.rho + 0.5 * theta_e * theta_e;
    return out;
  }

  if (!have_direction_ || !(goal == direction_goal_)) {
    reverse_ = params_.allowReverse && std::abs(out.error.alpha) > 0.5 * kPi;
    have_direction_ = true;
    direction_goal_ = goal;
  } else if (params_.allowReverse) {
    const double a = std::abs(out.error.alpha);
    if (!reverse_ && a > 0.5 * kPi + params_.reverseHysteresis) {
      reverse_ = true;
    } else if (reverse_ && a < 0.5 * kPi - params_.reverseHysteresis) {
      reverse_ = false;
    }
  }

  PolarError e = out.error;
  if (reverse_) {
    // A robot driving backwards is a forward robot with heading θ + π that must reach θ_goal + π, so
    // α and φ both shift by π and the law's v changes sign.
    e.alpha = wrapAngle(e.alpha + kPi);
    e.phi = wrapAngle(e.phi + kPi);
  }
  const Twist t = globalLaw(e, g);
  out.cmd = reverse_ ? Twist{-t.v, t.omega} : t;
  out.reverse = reverse_;
  out.lyapunov = lyapunovGlobal(e, g.h);
  return out;
}

}  // namespace fleet::control
