#include "disc_prediction.hpp"

#include <algorithm>
#include <cmath>

#include "fleet/core/angles.hpp"

namespace fleet::agent {

std::vector<msg::Disc> predictDiscs(const Pose2& pose, const Eigen::Matrix3d& P, double v, double w,
                                    const DiscPredictionParams& params) {
  std::vector<msg::Disc> out;
  const int steps = static_cast<int>(params.horizonS / params.dt) + 1;
  out.reserve(static_cast<std::size_t>(std::max(steps, 0)));
  Pose2 q = pose;
  for (int k = 0; k < steps; ++k) {
    const double t = k * params.dt;
    // Rotating the initial heading by δ rotates the whole displacement about the start by δ, so the
    // position's sensitivity to θ0 is the displacement turned by 90°.
    Eigen::Matrix<double, 2, 3> F;
    F << 1.0, 0.0, -(q.y - pose.y), 0.0, 1.0, q.x - pose.x;
    Eigen::Matrix2d S = F * P * F.transpose();
    const double iso = params.isotropicRate * t;
    S(0, 0) += iso * iso;
    S(1, 1) += iso * iso;
    const double along = params.alongTrackFraction * std::abs(v) * t;
    const double ux = std::cos(q.theta);
    const double uy = std::sin(q.theta);
    S(0, 0) += along * along * ux * ux;
    S(0, 1) += along * along * ux * uy;
    S(1, 0) += along * along * ux * uy;
    S(1, 1) += along * along * uy * uy;
    const double xy = 0.5 * (S(0, 1) + S(1, 0));  // symmetric to the last bit on the wire
    const double half = 0.5 * (S(0, 0) - S(1, 1));
    const double lmax = 0.5 * (S(0, 0) + S(1, 1)) + std::sqrt(half * half + xy * xy);
    out.push_back({static_cast<float>(q.x), static_cast<float>(q.y), static_cast<float>(params.radius),
                   static_cast<float>(std::sqrt(std::max(lmax, 0.0))), static_cast<float>(S(0, 0)),
                   static_cast<float>(xy), static_cast<float>(S(1, 1))});
    q = {q.x + v * std::cos(q.theta) * params.dt, q.y + v * std::sin(q.theta) * params.dt,
         wrapAngle(q.theta + w * params.dt)};
  }
  return out;
}

}  // namespace fleet::agent
