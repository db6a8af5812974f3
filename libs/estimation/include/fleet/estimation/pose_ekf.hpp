#pragma once

#include <cstddef>
#include <span>

#include <Eigen/Core>

#include "fleet/core/expected.hpp"
#include "fleet/core/pose2.hpp"
#include "fleet/core/vec2.hpp"
#include "fleet/estimation/measurement_models.hpp"

namespace fleet::estimation {

/// Filter constants. Defaults are the seed-003 identified values where the seed has one.
struct EkfParams {
  double wheelBase = 0.6;             ///< L [m]; not in the seed (docs/algorithms.md)
  double delta = 0.0003;              ///< wheel noise variance per metre rolled (eq. 3.9)
  double compassVariance = 2.79e-4;   ///< recalibrated CMPS03 [rad²]
  double compassOffset = 0.0;         ///< compass reading of map heading 0 [rad], stored at start-up
  double bearingVariance = 2.992e-4;  ///< omni-camera bearing [rad²]
  double gate1dof = 10.83;            ///< χ²(1) 99.9 % Mahalanobis gate
  double gate2dof = 13.82;            ///< χ²(2) 99.9 % gate (one line = (r, ψ))
  double minLineDistance = 0.05;      ///< reject a line closer than this: its ψ is undefined on the line
  /// A wheel increment larger than this (m, either wheel, one prediction) is no motion a robot makes
  /// between two readings: refused (kRejectedImplausible), since it would swing the estimate and
  /// blow the covariance up by its square.
  double maxWheelIncrement = 10.0;
  /// Ceilings of the covariance's diagonal: beyond them the filter knows nothing anyway, and a
  /// covariance growing without bound (a stream of predictions without corrections, widened gaps)
  /// ends in overflow. A diagonal entry over its ceiling is scaled down with its row and column
  /// (P ← D P D, which keeps P positive semi-definite and the correlations as they were).
  double maxPositionVariance = 1e4;  ///< m² (σ = 100 m)
  double maxHeadingVariance = 10.0;  ///< rad² (σ ≈ π: the heading is unknown)

  [[nodiscard]] Expected<void> validate() const;
};

enum class UpdateStatus {
  kAccepted,
  kRejectedNonFinite,    ///< NaN/inf reading or variance, or a variance <= 0
  kRejectedGate,         ///< Mahalanobis distance over the χ² gate (outlier)
  kRejectedGeometry,     ///< the model is singular here (landmark on the robot, robot on the line)
  kRejectedImplausible,  ///< a reading no robot produces (a wheel increment over maxWheelIncrement)
};

struct SensorStats {
  std::size_t accepted = 0;
  std::size_t rejectedNonFinite = 0;
  std::size_t rejectedGate = 0;
  std::size_t rejectedGeometry = 0;
  std::size_t rejectedImplausible = 0;
  [[nodiscard]] std::size_t rejected() const {
    return rejectedNonFinite + rejectedGate + rejectedGeometry + rejectedImplausible;
  }
};

struct EkfStats {
  SensorStats odometry;
  SensorStats compass;
  SensorStats bearing;
  SensorStats line;
  std::size_t linesUnmatched = 0;  ///< observed lines with no map line inside the gate
};

/// A laser line feature in the robot frame (x_R cos ψ + y_R sin ψ = r) with its variances.
struct LineObservation {
  double r = 0.0;
  double psi = 0.0;
  double varR = 1e-4;
  double varPsi = 1e-3;
  /// Correlation of r and ψ from the fit (not in the thesis's diagonal R, eq. 3.23); |cov|² < varR·varPsi.
  double covRPsi = 0.0;
};

struct LineBatchResult {
  std::size_t accepted = 0;
  std::size_t unmatched = 0;
  std::size_t rejectedNonFinite = 0;
};

/// EKF over the planar pose (x, y, θ) of seed 003 ch. 3: odometry prediction and independent compass,
/// landmark-bearing and laser-line corrections, each applied whenever its sensor delivers (no fixed
/// schedule). Every correction is gated and uses the Joseph form followed by symmetrisation, so the
/// covariance stays symmetric positive-definite; a rejected reading leaves state and covariance
/// untouched and is counted in stats(). After every step (and reset) the covariance is kept
/// finite, symmetric, positive semi-definite (negative eigenvalues from rounding clamped to 0) and
/// under the ceilings of EkfParams, whatever the readings were.
class PoseEkf {
 public:
  static Expected<PoseEkf> create(const EkfParams& params, const Pose2& initial, const Eigen::Matrix3d& P0);

  /// Prediction with the measured wheel increments [m] since the last call.
  UpdateStatus predict(double ds_left, double ds_right);

  /// Compass heading as read (compassOffset is subtracted). Variance defaults to params.
  UpdateStatus updateCompass(double reading);
  UpdateStatus updateCompass(double reading, double variance);

  /// Bearing to a known landmark, counter-clockwise from the robot's x axis.
  UpdateStatus updateBearing(Vec2 landmark, double bearing);
  UpdateStatus updateBearing(Vec2 landmark, double bearing, double variance);

  /// One line already matched to a map line.
  UpdateStatus updateLine(const MapLine& map_line, const LineObservation& obs);

  /// Matches each observed line to the unused map line with the smallest Mahalanobis distance inside
  /// the gate (nearest neighbour against the current estimate) and applies the updates in turn.
  LineBatchResult updateLines(std::span<const MapLine> map, std::span<const LineObservation> observations);

  [[nodiscard]] Pose2 pose() const { return {x_(0), x_(1), x_(2)}; }
  [[nodiscard]] const Eigen::Vector3d& state() const { return x_; }
  [[nodiscard]] const Eigen::Matrix3d& covariance() const { return P_; }
  [[nodiscard]] const EkfStats& stats() const { return stats_; }
  [[nodiscard]] const EkfParams& params() const { return params_; }

  /// Re-initialise (e.g. after a relocalisation); stats are kept. A P0 over the ceilings is scaled
  /// down to them.
  Expected<void> reset(const Pose2& pose, const Eigen::Matrix3d& P0);

 private:
  PoseEkf(const EkfParams& params, const Pose2& initial, const Eigen::Matrix3d& P0);

  template <int M>
  UpdateStatus correct(const Eigen::Matrix<double, M, 1>& innovation, const Eigen::Matrix<double, M, 3>& H,
                       const Eigen::Matrix<double, M, M>& R, double gate, SensorStats& stats);

  // Keeps P_ finite, symmetric, positive semi-definite and under the ceilings.
  void boundCovariance();

  EkfParams params_;
  Eigen::Vector3d x_;
  Eigen::Matrix3d P_;
  EkfStats stats_;
};

/// NEES e^T P^-1 e of a pose estimate against the truth, with the heading error wrapped.
double normalizedEstimationErrorSquared(const Pose2& truth, const Pose2& estimate, const Eigen::Matrix3d& P);

}  // namespace fleet::estimation
