#include "fleet/control/diff_drive_kinematics.hpp"

#include <cmath>

namespace fleet::control {

Expected<DiffDriveKinematics> DiffDriveKinematics::create(double wheelBase) {
  if (!std::isfinite(wheelBase) || wheelBase <= 0.0) {
    return fleet::unexpected("invalid_wheel_base", "wheel_base must be finite and > 0 (metres)");
  }
  return DiffDriveKinematics(wheelBase);
}

WheelSpeeds DiffDriveKinematics::toWheelSpeeds(Twist t) const {
  const double half = 0.5 * wheel_base_ * t.omega;
  return {t.v - half, t.v + half};
}

Twist DiffDriveKinematics::toTwist(WheelSpeeds w) const {
  return {0.5 * (w.right + w.left), (w.right - w.left) / wheel_base_};
}

OdometryDelta DiffDriveKinematics::odometryDelta(double ds_left, double ds_right) const {
  return {0.5 * (ds_right + ds_left), (ds_right - ds_left) / wheel_base_};
}

Pose2 DiffDriveKinematics::applyOdometry(const Pose2& pose, double ds_left, double ds_right) const {
  const OdometryDelta d = odometryDelta(ds_left, ds_right);
  const double mid = pose.theta + 0.5 * d.dtheta;
  return {pose.x + d.ds * std::cos(mid), pose.y + d.ds * std::sin(mid), wrapAngle(pose.theta + d.dtheta)};
}

Pose2 DiffDriveKinematics::integrateExact(const Pose2& pose, Twist t, double dt) {
  const double dtheta = t.omega * dt;
  const double ds = t.v * dt;
  // The chord of an arc of length ds turning by dθ is ds·sin(dθ/2)/(dθ/2), along the midpoint heading;
  // written this way the straight-line limit needs no special case beyond the sinc guard.
  const double half = 0.5 * dtheta;
  const double sinc = std::abs(half) < 1e-9 ? 1.0 - half * half / 6.0 : std::sin(half) / half;
  const double chord = ds * sinc;
  const double mid = pose.theta + half;
  return {pose.x + chord * std::cos(mid), pose.y + chord * std::sin(mid), wrapAngle(pose.theta + dtheta)};
}

Pose2 DiffDriveKinematics::integrateMidpoint(const Pose2& pose, Twist t, double dt) {
  const double ds = t.v * dt;
  const double dtheta = t.omega * dt;
  const double mid = pose.theta + 0.5 * dtheta;
  return {pose.x + ds * std::cos(mid), pose.y + ds * std::sin(mid), wrapAngle(pose.theta + dtheta)};
}

}  // namespace fleet::control
