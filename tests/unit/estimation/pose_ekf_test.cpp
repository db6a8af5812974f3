#include "fleet/estimation/pose_ekf.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>
#include <vector>

#include <Eigen/Eigenvalues>

#include "fleet/core/angles.hpp"

using namespace fleet;
using namespace fleet::estimation;

namespace {

const double kNan = std::numeric_limits<double>::quiet_NaN();
const double kInf = std::numeric_limits<double>::infinity();

PoseEkf makeEkf(const Pose2& p = {}, const Eigen::Matrix3d& P0 = Eigen::Matrix3d::Identity() * 1e-4) {
  return PoseEkf::create(EkfParams{}, p, P0).value();
}

bool symmetricPositiveDefinite(const Eigen::Matrix3d& P) {
  if (P != P.transpose()) {
    return false;
  }
  return Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(P).eigenvalues().minCoeff() > 0.0;
}

}  // namespace

TEST(PoseEkf, CreateValidates) {
  EXPECT_TRUE(PoseEkf::create(EkfParams{}, Pose2{}, Eigen::Matrix3d::Identity()).has_value());
  EXPECT_EQ(PoseEkf::create(EkfParams{}, Pose2{kNan, 0, 0}, Eigen::Matrix3d::Identity()).error().code,
            "non_finite_pose");
  Eigen::Matrix3d bad = Eigen::Matrix3d::Identity();
  bad(0, 0) = -1.0;
  EXPECT_EQ(PoseEkf::create(EkfParams{}, Pose2{}, bad).error().code, "invalid_covariance");
  EkfParams p;
  p.wheelBase = 0.0;
  EXPECT_EQ(PoseEkf::create(p, Pose2{}, Eigen::Matrix3d::Identity()).error().code, "invalid_ekf_params");
}

TEST(PoseEkf, PredictionFollowsOdometryAndGrowsCovariance) {
  PoseEkf ekf = makeEkf();
  const Eigen::Matrix3d P0 = ekf.covariance();
  EXPECT_EQ(ekf.predict(0.0, 0.0), UpdateStatus::kAccepted);
  EXPECT_EQ(ekf.covariance(), P0);  // no motion, no growth (eq. 3.9)
  ekf.predict(0.1, 0.1);
  EXPECT_NEAR(ekf.pose().x, 0.1, 1e-12);
  EXPECT_GT(ekf.covariance()(0, 0), P0(0, 0));
  EXPECT_GT(ekf.covariance()(1, 1), P0(1, 1));  // through the heading uncertainty
  EXPECT_EQ(ekf.stats().odometry.accepted, 2u);
}

TEST(PoseEkf, CompassPullsHeading) {
  // Seed 003 behaviour 5: a prior with σθ ≫ 1° is pulled close to the reading; x, y only move
  // through the cross-covariance.
  Eigen::Matrix3d P0 = Eigen::Matrix3d::Identity() * 0.01;
  P0(2, 2) = 0.1;  // σθ ≈ 18°
  PoseEkf ekf = makeEkf(Pose2{1.0, 2.0, 0.0}, P0);
  EXPECT_EQ(ekf.updateCompass(0.3), UpdateStatus::kAccepted);
  EXPECT_NEAR(ekf.pose().theta, 0.3 * 0.1 / (0.1 + 2.79e-4), 1e-12);
  EXPECT_DOUBLE_EQ(ekf.pose().x, 1.0);  // no cross terms in this prior
  EXPECT_DOUBLE_EQ(ekf.pose().y, 2.0);
  EXPECT_NEAR(ekf.covariance()(2, 2), 0.1 * 2.79e-4 / (0.1 + 2.79e-4), 1e-12);

  // With correlation (after driving) the position moves too.
  PoseEkf moving = makeEkf(Pose2{}, P0);
  for (int i = 0; i < 10; ++i) {
    moving.predict(0.1, 0.1);
  }
  const double y_before = moving.pose().y;
  moving.updateCompass(0.2);
  EXPECT_GT(moving.pose().y - y_before, 0.01);  // heading was further left → the robot is further left
}

TEST(PoseEkf, CompassOffsetAndWrapping) {
  EkfParams params;
  params.compassOffset = 0.5;
  Eigen::Matrix3d P0 = Eigen::Matrix3d::Identity() * 0.01;
  PoseEkf ekf = PoseEkf::create(params, Pose2{0, 0, 3.1}, P0).value();
  // Map heading −3.1 is 0.083 rad from 3.1 across ±π; the estimate must move the short way.
  ekf.updateCompass(wrapAngle(-3.1 + 0.5));
  EXPECT_GT(std::abs(ekf.pose().theta), 3.1);
  EXPECT_GT(ekf.pose().theta, -kPi);
  EXPECT_LE(ekf.pose().theta, kPi);
}

TEST(PoseEkf, BearingUpdateCorrectsLateralPosition) {
  Eigen::Matrix3d P0 = Eigen::Matrix3d::Identity() * 0.04;
  P0(2, 2) = 1e-6;  // heading known
  PoseEkf ekf = makeEkf(Pose2{0.0, 0.2, 0.0}, P0);
  // True robot at the origin; landmark straight ahead at (5, 0).
  for (int i = 0; i < 5; ++i) {
    ekf.updateBearing(Vec2{5, 0}, 0.0);
  }
  EXPECT_LT(std::abs(ekf.pose().y), 0.05);
  EXPECT_LT(std::abs(ekf.pose().x), 0.01);  // bearing carries almost no range information here
}

TEST(PoseEkf, LineUpdateCorrectsDistanceToWall) {
  PoseEkf ekf = makeEkf(Pose2{0.3, 0.0, 0.0}, Eigen::Matrix3d::Identity() * 0.04);
  // True robot at the origin; wall x = 2 seen at r = 2, ψ = 0.
  EXPECT_EQ(ekf.updateLine(MapLine{2.0, 0.0}, LineObservation{2.0, 0.0, 1e-4, 1e-3}),
            UpdateStatus::kAccepted);
  EXPECT_LT(std::abs(ekf.pose().x), 0.01);
  EXPECT_NEAR(ekf.pose().y, 0.0, 1e-12);
}

TEST(PoseEkf, LineBatchMatchesToTheRightWalls) {
  const std::vector<MapLine> map{{2.0, 0.0}, {1.0, kPi / 2}, {3.0, kPi}, {1.5, -kPi / 2}};
  PoseEkf ekf = makeEkf(Pose2{0.1, -0.1, 0.02}, Eigen::Matrix3d::Identity() * 0.02);
  // Truth at the origin facing +x: walls x = 2 (ahead), y = 1 (left), y = −1.5 (right); a spurious line.
  const std::vector<LineObservation> obs{{2.0, 0.0, 1e-4, 1e-3},
                                         {1.0, kPi / 2, 1e-4, 1e-3},
                                         {1.5, -kPi / 2, 1e-4, 1e-3},
                                         {0.7, 2.5, 1e-4, 1e-3},
                                         {kNan, 0.0, 1e-4, 1e-3}};
  const LineBatchResult r = ekf.updateLines(map, obs);
  EXPECT_EQ(r.accepted, 3u);
  EXPECT_EQ(r.unmatched, 1u);
  EXPECT_EQ(r.rejectedNonFinite, 1u);
  EXPECT_EQ(ekf.stats().linesUnmatched, 1u);
  EXPECT_LT(std::hypot(ekf.pose().x, ekf.pose().y), 0.01);
  EXPECT_LT(std::abs(ekf.pose().theta), 0.02);
}

TEST(PoseEkf, RejectsNonFiniteAndOutliersWithoutTouchingState) {
  PoseEkf ekf = makeEkf(Pose2{1.0, 1.0, 0.5}, Eigen::Matrix3d::Identity() * 1e-3);
  const Eigen::Vector3d x0 = ekf.state();
  const Eigen::Matrix3d P0 = ekf.covariance();
  EXPECT_EQ(ekf.predict(kNan, 0.1), UpdateStatus::kRejectedNonFinite);
  EXPECT_EQ(ekf.predict(0.1, kInf), UpdateStatus::kRejectedNonFinite);
  EXPECT_EQ(ekf.updateCompass(kNan), UpdateStatus::kRejectedNonFinite);
  EXPECT_EQ(ekf.updateCompass(0.5, -1.0), UpdateStatus::kRejectedNonFinite);
  EXPECT_EQ(ekf.updateCompass(0.5, kNan), UpdateStatus::kRejectedNonFinite);
  EXPECT_EQ(ekf.updateBearing(Vec2{kInf, 0}, 0.1), UpdateStatus::kRejectedNonFinite);
  EXPECT_EQ(ekf.updateBearing(Vec2{3, 1}, kNan), UpdateStatus::kRejectedNonFinite);
  EXPECT_EQ(ekf.updateBearing(Vec2{1, 1}, 0.0), UpdateStatus::kRejectedGeometry);  // on the robot
  EXPECT_EQ(ekf.updateLine(MapLine{2, 0}, LineObservation{kNan, 0, 1e-4, 1e-3}),
            UpdateStatus::kRejectedNonFinite);
  EXPECT_EQ(ekf.updateLine(MapLine{2, 0}, LineObservation{1.0, 0, 0.0, 1e-3}),
            UpdateStatus::kRejectedNonFinite);
  // Outliers: a compass 90° off (magnetic disturbance), a landmark bearing 45° off, a wall 0.5 m off.
  EXPECT_EQ(ekf.updateCompass(0.5 + kPi / 2), UpdateStatus::kRejectedGate);
  const double true_bearing = predictBearing(ekf.pose(), Vec2{4, 2}).gamma;
  EXPECT_EQ(ekf.updateBearing(Vec2{4, 2}, true_bearing + kPi / 4), UpdateStatus::kRejectedGate);
  const LinePrediction wall = predictLine(ekf.pose(), MapLine{3.0, 0.0});
  EXPECT_EQ(ekf.updateLine(MapLine{3.0, 0.0}, LineObservation{wall.r + 0.5, wall.psi, 1e-4, 1e-3}),
            UpdateStatus::kRejectedGate);
  EXPECT_EQ(ekf.state(), x0);
  EXPECT_EQ(ekf.covariance(), P0);
  const EkfStats& s = ekf.stats();
  EXPECT_EQ(s.odometry.rejectedNonFinite, 2u);
  EXPECT_EQ(s.compass.rejectedNonFinite, 3u);
  EXPECT_EQ(s.compass.rejectedGate, 1u);
  EXPECT_EQ(s.bearing.rejectedNonFinite, 2u);
  EXPECT_EQ(s.bearing.rejectedGeometry, 1u);
  EXPECT_EQ(s.bearing.rejectedGate, 1u);
  EXPECT_EQ(s.line.rejectedNonFinite, 2u);
  EXPECT_EQ(s.line.rejectedGate, 1u);
  EXPECT_EQ(s.compass.accepted + s.bearing.accepted + s.line.accepted + s.odometry.accepted, 0u);
  // The filter still works afterwards.
  EXPECT_EQ(ekf.updateCompass(0.51), UpdateStatus::kAccepted);
}

TEST(PoseEkf, CovarianceStaysSymmetricPositiveDefinite) {
  // Many very precise updates (the regime where the simple (I − KH)P form loses definiteness).
  PoseEkf ekf = makeEkf(Pose2{}, Eigen::Matrix3d::Identity() * 10.0);
  std::mt19937 rng(9);
  std::normal_distribution<double> n(0.0, 1.0);
  const std::vector<MapLine> map{{3.0, 0.0}, {2.0, kPi / 2}, {3.0, kPi}, {2.0, -kPi / 2}};
  for (int k = 0; k < 5000; ++k) {
    ekf.predict(0.01 + 0.001 * n(rng), 0.012 + 0.001 * n(rng));
    const Pose2 p = ekf.pose();
    ekf.updateCompass(p.theta, 1e-12);
    const LinePrediction l = predictLine(p, map[static_cast<std::size_t>(k) % 4]);
    ekf.updateLine(map[static_cast<std::size_t>(k) % 4], LineObservation{l.r, l.psi, 1e-12, 1e-12});
    ekf.updateBearing(Vec2{10, 10}, predictBearing(p, Vec2{10, 10}).gamma, 1e-12);
    ASSERT_TRUE(symmetricPositiveDefinite(ekf.covariance())) << k;
  }
}

TEST(PoseEkf, IndependentUpdatesCommuteToFirstOrder) {
  // Asynchronous sensors: the order in which two readings of the same instant are applied changes the
  // result only through the re-linearisation (second order).
  auto run = [](bool compass_first) {
    PoseEkf ekf = makeEkf(Pose2{0.05, -0.05, 0.03}, Eigen::Matrix3d::Identity() * 0.01);
    const LineObservation wall{2.0, 0.0, 1e-4, 1e-3};
    if (compass_first) {
      ekf.updateCompass(0.0);
      ekf.updateLine(MapLine{2.0, 0.0}, wall);
    } else {
      ekf.updateLine(MapLine{2.0, 0.0}, wall);
      ekf.updateCompass(0.0);
    }
    return ekf;
  };
  const PoseEkf a = run(true);
  const PoseEkf b = run(false);
  EXPECT_LT((a.state() - b.state()).cwiseAbs().maxCoeff(), 1e-3);
  EXPECT_LT((a.covariance() - b.covariance()).cwiseAbs().maxCoeff(), 1e-5);
}

TEST(PoseEkf, AnAbsurdWheelIncrementIsRefusedWithoutTouchingState) {
  PoseEkf ekf = makeEkf(Pose2{1.0, 1.0, 0.5}, Eigen::Matrix3d::Identity() * 1e-3);
  const Eigen::Matrix3d P0 = ekf.covariance();
  EXPECT_EQ(ekf.predict(1e6, 1e6), UpdateStatus::kRejectedImplausible);
  EXPECT_EQ(ekf.predict(0.1, -11.0), UpdateStatus::kRejectedImplausible);
  EXPECT_EQ(ekf.pose(), (Pose2{1.0, 1.0, 0.5}));
  EXPECT_EQ(ekf.covariance(), P0);
  EXPECT_EQ(ekf.stats().odometry.rejectedImplausible, 2u);
  EXPECT_EQ(ekf.stats().odometry.rejected(), 2u);
  EXPECT_EQ(ekf.predict(9.0, 9.0), UpdateStatus::kAccepted);  // a long gap with wheel totals
}

// Predictions without any correction: the covariance grows to its ceilings and stops there,
// symmetric and positive semi-definite, with its correlations kept.
TEST(PoseEkf, TheCovarianceStopsAtItsCeilings) {
  EkfParams params;
  params.delta = 0.5;  // noisy wheels, so the ceiling is reached in a few thousand steps
  PoseEkf ekf = PoseEkf::create(params, Pose2{}, Eigen::Matrix3d::Identity() * 1e-3).value();
  for (int k = 0; k < 20000; ++k) {
    ASSERT_EQ(ekf.predict(9.5, 9.0 + 0.001 * (k % 7)), UpdateStatus::kAccepted);
    const Eigen::Matrix3d& P = ekf.covariance();
    ASSERT_TRUE(P.allFinite()) << k;
    ASSERT_EQ(P, P.transpose()) << k;
    ASSERT_LE(P(0, 0), params.maxPositionVariance) << k;
    ASSERT_LE(P(1, 1), params.maxPositionVariance) << k;
    ASSERT_LE(P(2, 2), params.maxHeadingVariance) << k;
  }
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(ekf.covariance());
  EXPECT_GE(eig.eigenvalues().minCoeff(), -1e-9 * params.maxPositionVariance);
  // It did grow that far (the heading turns uncertainty between x and y).
  EXPECT_GT(ekf.covariance()(0, 0) + ekf.covariance()(1, 1), params.maxPositionVariance);
  EXPECT_TRUE(ekf.pose().isFinite());
  // A reset over the ceilings is scaled down to them.
  ASSERT_TRUE(ekf.reset(Pose2{}, Eigen::Matrix3d::Identity() * 1e9));
  EXPECT_DOUBLE_EQ(ekf.covariance()(1, 1), params.maxPositionVariance);
  EXPECT_DOUBLE_EQ(ekf.covariance()(2, 2), params.maxHeadingVariance);
}
