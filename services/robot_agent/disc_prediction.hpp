#pragma once

// The robot's predicted discs for the risk map: the current command held over the horizon, each disc
// with the position covariance of the prediction (docs/algorithms.md, "Anisotropic uncertainty").

#include <Eigen/Core>

#include <vector>

#include "fleet/core/pose2.hpp"
#include "fleet/messages/messages.hpp"

namespace fleet::agent {

struct DiscPredictionParams {
  double radius = 0.3;    // m
  double dt = 0.5;        // s between discs
  double horizonS = 3.0;  // s
  /// Growth in every direction, m/s of standard deviation: what holding the command cannot promise
  /// (the command changes, the robot turns). The isotropic model's former growth rate.
  double isotropicRate = 0.1;
  /// Growth along the heading, standard deviation per metre the held command predicts: the robot
  /// slows for the stop rule and for others, so it covers ~70–100 % of v·t over a few seconds (±2σ).
  double alongTrackFraction = 0.15;
};

/// Discs at t = k·dt, k = 0..⌊horizon/dt⌋, along the arc of (v, w) from `pose`. Covariance of disc k:
/// F P Fᵀ (the EKF's 3×3 (x, y, θ) covariance carried through the arc, whose position moves by
/// perp(p_k − p_0) per radian of initial heading) + (isotropicRate·t)² I + (alongTrackFraction·|v|·t)²
/// u_k u_kᵀ (u_k the heading at step k). sigma is the square root of its largest eigenvalue.
std::vector<msg::Disc> predictDiscs(const Pose2& pose, const Eigen::Matrix3d& P, double v, double w,
                                    const DiscPredictionParams& params);

}  // namespace fleet::agent
