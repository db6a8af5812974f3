#include "fleet/estimation/measurement_models.hpp"

#include <cmath>

#include "fleet/core/angles.hpp"

namespace fleet::estimation {

OdometryModel odometryModel(const Pose2& pose, double ds_left, double ds_right, double wheelBase) {
  const double ds = 0.5 * (ds_right + ds_left);
  const double dtheta = (ds_right - ds_left) / wheelBase;
  const double mid = pose.theta + 0.5 * dtheta;
  const double c = std::cos(mid);
  const double s = std::sin(mid);
  OdometryModel m;
  m.pose = {pose.x + ds * c, pose.y + ds * s, wrapAngle(pose.theta + dtheta)};
  m.A << 1.0, 0.0, -ds * s,  //
      0.0, 1.0, ds * c,      //
      0.0, 0.0, 1.0;
  // ∂Δs/∂εL = ∂Δs/∂εR = 1/2, ∂Δθ/∂εR = 1/L = −∂Δθ/∂εL; the midpoint heading moves by half of Δθ.
  const double k = ds / (2.0 * wheelBase);
  m.W << 0.5 * c + k * s, 0.5 * c - k * s,  //
      0.5 * s - k * c, 0.5 * s + k * c,     //
      -1.0 / wheelBase, 1.0 / wheelBase;
  return m;
}

Eigen::Matrix2d odometryNoise(double ds_left, double ds_right, double delta) {
  Eigen::Matrix2d q = Eigen::Matrix2d::Zero();
  q(0, 0) = delta * std::abs(ds_left);
  q(1, 1) = delta * std::abs(ds_right);
  return q;
}

LinePrediction predictLine(const Pose2& pose, const MapLine& line) {
  const double cb = std::cos(line.beta);
  const double sb = std::sin(line.beta);
  LinePrediction p;
  p.signedDistance = line.rho - pose.x * cb - pose.y * sb;
  // With the robot on the far side of the line (C < 0) the normal toward the line flips by π.
  const double sign = p.signedDistance >= 0.0 ? 1.0 : -1.0;
  p.r = std::abs(p.signedDistance);
  p.psi = wrapAngle(line.beta - pose.theta + (sign > 0.0 ? 0.0 : kPi));
  p.H << -sign * cb, -sign * sb, 0.0,  //
      0.0, 0.0, -1.0;
  return p;
}

BearingPrediction predictBearing(const Pose2& pose, Vec2 landmark) {
  const double dx = landmark.x - pose.x;
  const double dy = landmark.y - pose.y;
  const double d2 = dx * dx + dy * dy;
  BearingPrediction b;
  b.range = std::sqrt(d2);
  b.gamma = wrapAngle(std::atan2(dy, dx) - pose.theta);
  b.H << dy / d2, -dx / d2, -1.0;
  return b;
}

}  // namespace fleet::estimation
