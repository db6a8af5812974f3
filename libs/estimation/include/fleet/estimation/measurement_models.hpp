#pragma once

#include <Eigen/Core>

#include "fleet/core/pose2.hpp"
#include "fleet/core/vec2.hpp"

namespace fleet::estimation {

/// Odometry motion model of seed 003 (eqs. 3.1a, 3.9–3.11): midpoint update from the wheel increments,
/// with the Jacobians A = ∂f/∂x and W = ∂f/∂(εL, εR).
struct OdometryModel {
  Pose2 pose;
  Eigen::Matrix3d A;
  Eigen::Matrix<double, 3, 2> W;  ///< columns: left wheel, right wheel
};
OdometryModel odometryModel(const Pose2& pose, double ds_left, double ds_right, double wheelBase);

/// Q = diag(δ|ΔsL|, δ|ΔsR|) (eq. 3.9): wheel variance proportional to the distance it rolled.
Eigen::Matrix2d odometryNoise(double ds_left, double ds_right, double delta);

/// A map line x·cos β + y·sin β = ρ in the map frame (ρ >= 0: β is the direction of the foot of the
/// normal from the origin).
struct MapLine {
  double rho = 0.0;
  double beta = 0.0;
};

/// The same line seen from a pose, in the robot frame: x_R cos ψ + y_R sin ψ = r, r >= 0
/// (eqs. 3.19–3.21).
struct LinePrediction {
  double r = 0.0;
  double psi = 0.0;
  double signedDistance = 0.0;  ///< C = ρ − x cos β − y sin β; |C| tiny means the robot is on the line
  Eigen::Matrix<double, 2, 3> H;
};
LinePrediction predictLine(const Pose2& pose, const MapLine& line);

/// Bearing of a point landmark from the robot, counter-clockwise from the robot's x axis (eq. 3.34).
struct BearingPrediction {
  double gamma = 0.0;
  double range = 0.0;
  Eigen::RowVector3d H;
};
BearingPrediction predictBearing(const Pose2& pose, Vec2 landmark);

}  // namespace fleet::estimation
