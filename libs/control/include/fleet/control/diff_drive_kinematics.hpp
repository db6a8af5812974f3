#pragma once

#include "fleet/control/twist.hpp"
#include "fleet/core/expected.hpp"
#include "fleet/core/pose2.hpp"

namespace fleet::control {

/// Linear rim speeds of the two driven wheels [m/s] (wheel angular speed times wheel radius).
struct WheelSpeeds {
  double left = 0.0;
  double right = 0.0;
};

/// Odometry increment of one sample (seed 003 eq. 3.1a): distance of the axle midpoint and heading change.
struct OdometryDelta {
  double ds = 0.0;
  double dtheta = 0.0;
};

/// Differential-drive kinematics with axle length L (distance between the wheel contact points).
class DiffDriveKinematics {
 public:
  /// Fails unless wheelBase is finite and > 0.
  static Expected<DiffDriveKinematics> create(double wheelBase);

  [[nodiscard]] double wheelBase() const { return wheel_base_; }

  /// v = (vR + vL)/2, omega = (vR - vL)/L and its inverse.
  [[nodiscard]] WheelSpeeds toWheelSpeeds(Twist t) const;
  [[nodiscard]] Twist toTwist(WheelSpeeds w) const;

  /// Δs = (ΔsR + ΔsL)/2, Δθ = (ΔsR − ΔsL)/L.
  [[nodiscard]] OdometryDelta odometryDelta(double ds_left, double ds_right) const;
  /// Dead-reckoning step with the midpoint heading θ + Δθ/2 (seed 003 eq. 3.1a).
  [[nodiscard]] Pose2 applyOdometry(const Pose2& pose, double ds_left, double ds_right) const;

  /// Unicycle motion for dt at constant (v, omega) along the exact circular arc; what a simulator uses.
  static Pose2 integrateExact(const Pose2& pose, Twist t, double dt);
  /// Same motion with the midpoint rule the odometry uses (error O(Δθ³) against the exact arc).
  static Pose2 integrateMidpoint(const Pose2& pose, Twist t, double dt);

 private:
  explicit DiffDriveKinematics(double wheelBase) : wheel_base_(wheelBase) {}
  double wheel_base_;
};

}  // namespace fleet::control
