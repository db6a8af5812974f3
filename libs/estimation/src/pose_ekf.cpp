#include "fleet/estimation/pose_ekf.hpp"

#include <cmath>
#include <limits>
#include <vector>

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <Eigen/LU>

#include "fleet/core/angles.hpp"

namespace fleet::estimation {

namespace {

bool isPositiveDefinite(const Eigen::Matrix3d& P) {
  if (!P.allFinite() || !P.isApprox(P.transpose(), 1e-9)) {
    return false;
  }
  return Eigen::LLT<Eigen::Matrix3d>(P).info() == Eigen::Success;
}

bool positiveFinite(double v) {
  return std::isfinite(v) && v > 0.0;
}

bool validLineObservation(const LineObservation& o) {
  return std::isfinite(o.r) && std::isfinite(o.psi) && positiveFinite(o.varR) && positiveFinite(o.varPsi) &&
         std::isfinite(o.covRPsi) && o.covRPsi * o.covRPsi < o.varR * o.varPsi;
}

}  // namespace

Expected<void> EkfParams::validate() const {
  if (!positiveFinite(wheelBase) || !std::isfinite(delta) || delta < 0.0) {
    return fleet::unexpected("invalid_ekf_params", "wheel_base must be > 0 and delta >= 0");
  }
  if (!positiveFinite(compassVariance) || !positiveFinite(bearingVariance) || !std::isfinite(compassOffset)) {
    return fleet::unexpected("invalid_ekf_params", "sensor variances must be finite and > 0");
  }
  if (!positiveFinite(gate1dof) || !positiveFinite(gate2dof) || !std::isfinite(minLineDistance) ||
      minLineDistance < 0.0) {
    return fleet::unexpected("invalid_ekf_params", "gates must be > 0 and min_line_distance >= 0");
  }
  if (!positiveFinite(maxWheelIncrement) || !positiveFinite(maxPositionVariance) ||
      !positiveFinite(maxHeadingVariance)) {
    return fleet::unexpected("invalid_ekf_params",
                             "max_wheel_increment and the covariance ceilings must be finite and > 0");
  }
  return {};
}

PoseEkf::PoseEkf(const EkfParams& params, const Pose2& initial, const Eigen::Matrix3d& P0)
    : params_(params), x_(initial.x, initial.y, wrapAngle(initial.theta)), P_(P0) {
  boundCovariance();
}

void PoseEkf::boundCovariance() {
  const Eigen::Vector3d ceiling(params_.maxPositionVariance, params_.maxPositionVariance,
                                params_.maxHeadingVariance);
  if (!P_.allFinite()) {
    P_ = ceiling.asDiagonal();  // nothing is known any more
    return;
  }
  P_ = (0.5 * (P_ + P_.transpose())).eval();  // eval: transpose aliases P_
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(P_);
  if (eig.info() != Eigen::Success) {
    P_ = ceiling.asDiagonal();
    return;
  }
  if (eig.eigenvalues().minCoeff() < 0.0) {
    const Eigen::Vector3d clamped = eig.eigenvalues().cwiseMax(0.0);
    P_ = eig.eigenvectors() * clamped.asDiagonal() * eig.eigenvectors().transpose();
    P_ = (0.5 * (P_ + P_.transpose())).eval();
  }
  for (int i = 0; i < 3; ++i) {
    const double v = P_(i, i);
    if (v > ceiling(i)) {
      const double s = std::sqrt(ceiling(i) / v);
      P_.row(i) *= s;
      P_.col(i) *= s;
      P_(i, i) = ceiling(i);  // exactly, not within rounding
    } else if (v < 0.0) {
      P_(i, i) = 0.0;  // rounding after the clamp above
    }
  }
}

Expected<PoseEkf> PoseEkf::create(const EkfParams& params, const Pose2& initial, const Eigen::Matrix3d& P0) {
  if (auto ok = params.validate(); !ok) {
    return fleet::unexpected(ok.error());
  }
  if (!initial.isFinite()) {
    return fleet::unexpected("non_finite_pose", "initial pose is NaN/inf");
  }
  if (!isPositiveDefinite(P0)) {
    return fleet::unexpected("invalid_covariance", "P0 must be finite, symmetric and positive-definite");
  }
  return PoseEkf(params, initial, P0);
}

Expected<void> PoseEkf::reset(const Pose2& pose, const Eigen::Matrix3d& P0) {
  if (!pose.isFinite()) {
    return fleet::unexpected("non_finite_pose", "pose is NaN/inf");
  }
  if (!isPositiveDefinite(P0)) {
    return fleet::unexpected("invalid_covariance", "P0 must be finite, symmetric and positive-definite");
  }
  x_ = Eigen::Vector3d(pose.x, pose.y, wrapAngle(pose.theta));
  P_ = P0;
  boundCovariance();
  return {};
}

UpdateStatus PoseEkf::predict(double ds_left, double ds_right) {
  if (!std::isfinite(ds_left) || !std::isfinite(ds_right)) {
    ++stats_.odometry.rejectedNonFinite;
    return UpdateStatus::kRejectedNonFinite;
  }
  if (std::abs(ds_left) > params_.maxWheelIncrement || std::abs(ds_right) > params_.maxWheelIncrement) {
    ++stats_.odometry.rejectedImplausible;
    return UpdateStatus::kRejectedImplausible;
  }
  const OdometryModel m = odometryModel(pose(), ds_left, ds_right, params_.wheelBase);
  const Eigen::Matrix2d Q = odometryNoise(ds_left, ds_right, params_.delta);
  if (!m.pose.isFinite()) {  // a pose already at the edge of the doubles
    ++stats_.odometry.rejectedNonFinite;
    return UpdateStatus::kRejectedNonFinite;
  }
  x_ << m.pose.x, m.pose.y, m.pose.theta;
  P_ = m.A * P_ * m.A.transpose() + m.W * Q * m.W.transpose();
  boundCovariance();
  ++stats_.odometry.accepted;
  return UpdateStatus::kAccepted;
}

template <int M>
UpdateStatus PoseEkf::correct(const Eigen::Matrix<double, M, 1>& innovation,
                              const Eigen::Matrix<double, M, 3>& H, const Eigen::Matrix<double, M, M>& R,
                              double gate, SensorStats& stats) {
  using MatM = Eigen::Matrix<double, M, M>;
  const MatM S = H * P_ * H.transpose() + R;
  const Eigen::LLT<MatM> llt(S);
  if (llt.info() != Eigen::Success) {
    ++stats.rejectedGeometry;
    return UpdateStatus::kRejectedGeometry;
  }
  const double d2 = innovation.dot(llt.solve(innovation));
  if (!(d2 <= gate)) {
    ++stats.rejectedGate;
    return UpdateStatus::kRejectedGate;
  }
  // K = P Hᵀ S⁻¹, solved through the Cholesky factor rather than an explicit inverse.
  const Eigen::Matrix<double, 3, M> K = llt.solve(H * P_).transpose();
  const Eigen::Matrix3d IKH = Eigen::Matrix3d::Identity() - K * H;
  // Joseph form stays positive semi-definite under rounding, unlike (I − KH)P.
  const Eigen::Matrix3d P = IKH * P_ * IKH.transpose() + K * R * K.transpose();
  const Eigen::Vector3d x = x_ + K * innovation;
  if (!P.allFinite() || !x.allFinite()) {  // overflow in extreme readings: keep what we had
    ++stats.rejectedNonFinite;
    return UpdateStatus::kRejectedNonFinite;
  }
  P_ = P;
  boundCovariance();
  x_ = x;
  x_(2) = wrapAngle(x_(2));
  ++stats.accepted;
  return UpdateStatus::kAccepted;
}

UpdateStatus PoseEkf::updateCompass(double reading) {
  return updateCompass(reading, params_.compassVariance);
}

UpdateStatus PoseEkf::updateCompass(double reading, double variance) {
  if (!std::isfinite(reading) || !positiveFinite(variance)) {
    ++stats_.compass.rejectedNonFinite;
    return UpdateStatus::kRejectedNonFinite;
  }
  Eigen::Matrix<double, 1, 1> innov;
  innov(0) = angleDiff(reading - params_.compassOffset, x_(2));
  const Eigen::Matrix<double, 1, 3> H(0.0, 0.0, 1.0);
  const Eigen::Matrix<double, 1, 1> R = Eigen::Matrix<double, 1, 1>::Constant(variance);
  return correct<1>(innov, H, R, params_.gate1dof, stats_.compass);
}

UpdateStatus PoseEkf::updateBearing(Vec2 landmark, double bearing) {
  return updateBearing(landmark, bearing, params_.bearingVariance);
}

UpdateStatus PoseEkf::updateBearing(Vec2 landmark, double bearing, double variance) {
  if (!landmark.isFinite() || !std::isfinite(bearing) || !positiveFinite(variance)) {
    ++stats_.bearing.rejectedNonFinite;
    return UpdateStatus::kRejectedNonFinite;
  }
  const BearingPrediction b = predictBearing(pose(), landmark);
  if (b.range < 1e-6) {
    ++stats_.bearing.rejectedGeometry;
    return UpdateStatus::kRejectedGeometry;
  }
  Eigen::Matrix<double, 1, 1> innov;
  innov(0) = angleDiff(bearing, b.gamma);
  const Eigen::Matrix<double, 1, 1> R = Eigen::Matrix<double, 1, 1>::Constant(variance);
  return correct<1>(innov, Eigen::Matrix<double, 1, 3>(b.H), R, params_.gate1dof, stats_.bearing);
}

UpdateStatus PoseEkf::updateLine(const MapLine& map_line, const LineObservation& obs) {
  if (!std::isfinite(map_line.rho) || !std::isfinite(map_line.beta) || !std::isfinite(obs.r) ||
      !validLineObservation(obs)) {
    ++stats_.line.rejectedNonFinite;
    return UpdateStatus::kRejectedNonFinite;
  }
  const LinePrediction p = predictLine(pose(), map_line);
  if (p.r < params_.minLineDistance) {
    ++stats_.line.rejectedGeometry;
    return UpdateStatus::kRejectedGeometry;
  }
  const Eigen::Vector2d innov(obs.r - p.r, angleDiff(obs.psi, p.psi));
  Eigen::Matrix2d R = Eigen::Matrix2d::Zero();
  R(0, 0) = obs.varR;
  R(1, 1) = obs.varPsi;
  R(0, 1) = R(1, 0) = obs.covRPsi;
  return correct<2>(innov, p.H, R, params_.gate2dof, stats_.line);
}

LineBatchResult PoseEkf::updateLines(std::span<const MapLine> map,
                                     std::span<const LineObservation> observations) {
  LineBatchResult result;
  std::vector<bool> used(map.size(), false);
  for (const LineObservation& obs : observations) {
    if (!validLineObservation(obs)) {
      ++stats_.line.rejectedNonFinite;
      ++result.rejectedNonFinite;
      continue;
    }
    Eigen::Matrix2d R = Eigen::Matrix2d::Zero();
    R(0, 0) = obs.varR;
    R(1, 1) = obs.varPsi;
    R(0, 1) = R(1, 0) = obs.covRPsi;
    double best = params_.gate2dof;
    std::size_t best_j = map.size();
    for (std::size_t j = 0; j < map.size(); ++j) {
      if (used[j]) {
        continue;
      }
      const LinePrediction p = predictLine(pose(), map[j]);
      if (p.r < params_.minLineDistance) {
        continue;
      }
      const Eigen::Vector2d innov(obs.r - p.r, angleDiff(obs.psi, p.psi));
      // Closed-form 2×2 Mahalanobis distance: this loop runs for every (observation, map line) pair.
      const Eigen::Matrix2d S = p.H * P_ * p.H.transpose() + R;
      const double det = S(0, 0) * S(1, 1) - S(0, 1) * S(1, 0);
      if (!(det > 0.0)) {
        continue;
      }
      const double d2 = (S(1, 1) * innov(0) * innov(0) - 2.0 * S(0, 1) * innov(0) * innov(1) +
                         S(0, 0) * innov(1) * innov(1)) /
                        det;
      if (d2 <= best) {
        best = d2;
        best_j = j;
      }
    }
    if (best_j == map.size()) {
      ++stats_.linesUnmatched;
      ++result.unmatched;
      continue;
    }
    used[best_j] = true;
    if (updateLine(map[best_j], obs) == UpdateStatus::kAccepted) {
      ++result.accepted;
    }
  }
  return result;
}

double normalizedEstimationErrorSquared(const Pose2& truth, const Pose2& estimate, const Eigen::Matrix3d& P) {
  const Eigen::Vector3d e(estimate.x - truth.x, estimate.y - truth.y, angleDiff(estimate.theta, truth.theta));
  return e.dot(P.ldlt().solve(e));
}

}  // namespace fleet::estimation
