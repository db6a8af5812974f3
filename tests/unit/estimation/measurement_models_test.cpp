#include "fleet/estimation/measurement_models.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <random>

#include "fleet/core/angles.hpp"

using namespace fleet;
using namespace fleet::estimation;

namespace {

constexpr double kStep = 1e-6;

Eigen::Vector3d vec(const Pose2& p) {
  return {p.x, p.y, p.theta};
}
Pose2 pose(const Eigen::Vector3d& v) {
  return {v(0), v(1), v(2)};
}

/// Central difference of a vector function; angular outputs (by index) are differenced with wrapping.
template <int M>
Eigen::Matrix<double, M, Eigen::Dynamic> numericJacobian(
    const std::function<Eigen::Matrix<double, M, 1>(const Eigen::VectorXd&)>& f, const Eigen::VectorXd& x0,
    int angular_row) {
  Eigen::Matrix<double, M, Eigen::Dynamic> J(M, x0.size());
  for (int i = 0; i < x0.size(); ++i) {
    Eigen::VectorXd a = x0;
    Eigen::VectorXd b = x0;
    a(i) += kStep;
    b(i) -= kStep;
    Eigen::Matrix<double, M, 1> d = f(a) - f(b);
    if (angular_row >= 0) {
      d(angular_row) = wrapAngle(d(angular_row));
    }
    J.col(i) = d / (2 * kStep);
  }
  return J;
}

}  // namespace

TEST(OdometryModel, JacobiansMatchFiniteDifferences) {
  std::mt19937 rng(1);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  const double L = 0.6;
  for (int trial = 0; trial < 100; ++trial) {
    const Pose2 p{3 * u(rng), 3 * u(rng), wrapAngle(4 * u(rng))};
    const double dl = 0.1 * u(rng);
    const double dr = 0.1 * u(rng);
    const OdometryModel m = odometryModel(p, dl, dr, L);
    const auto fx = [&](const Eigen::VectorXd& x) -> Eigen::Vector3d {
      return vec(odometryModel(pose(x), dl, dr, L).pose);
    };
    const auto fw = [&](const Eigen::VectorXd& w) -> Eigen::Vector3d {
      return vec(odometryModel(p, dl + w(0), dr + w(1), L).pose);
    };
    const Eigen::MatrixXd A = numericJacobian<3>(fx, vec(p), 2);
    const Eigen::MatrixXd W = numericJacobian<3>(fw, Eigen::Vector2d::Zero(), 2);
    EXPECT_LT((A - m.A).cwiseAbs().maxCoeff(), 1e-6) << trial;
    EXPECT_LT((W - m.W).cwiseAbs().maxCoeff(), 1e-6) << trial;
  }
}

TEST(OdometryModel, NoiseGrowsWithDistanceRolled) {
  const Eigen::Matrix2d q = odometryNoise(-0.2, 0.1, 0.0003);
  EXPECT_DOUBLE_EQ(q(0, 0), 0.0003 * 0.2);
  EXPECT_DOUBLE_EQ(q(1, 1), 0.0003 * 0.1);
  EXPECT_DOUBLE_EQ(q(0, 1), 0.0);
  EXPECT_TRUE(odometryNoise(0.0, 0.0, 0.0003).isZero());
}

TEST(LineModel, SeedExamples) {
  // Robot at the origin facing +x, wall x = 2 (ρ = 2, β = 0): r = 2, ψ = 0.
  LinePrediction p = predictLine(Pose2{0, 0, 0}, MapLine{2.0, 0.0});
  EXPECT_NEAR(p.r, 2.0, 1e-12);
  EXPECT_NEAR(p.psi, 0.0, 1e-12);
  // Robot at (3, 0, 0) behind the same wall: C = −1, r = 1, ψ = π.
  p = predictLine(Pose2{3, 0, 0}, MapLine{2.0, 0.0});
  EXPECT_NEAR(p.signedDistance, -1.0, 1e-12);
  EXPECT_NEAR(p.r, 1.0, 1e-12);
  EXPECT_NEAR(p.psi, kPi, 1e-12);
  // Heading π/2 turns the wall's normal to −π/2 in the robot frame.
  p = predictLine(Pose2{0, 0, kPi / 2}, MapLine{2.0, 0.0});
  EXPECT_NEAR(p.psi, -kPi / 2, 1e-12);
}

TEST(LineModel, PredictionIsTheLineInTheRobotFrame) {
  // Cross-check: two points of the map line, moved into the robot frame, satisfy x cos ψ + y sin ψ = r.
  std::mt19937 rng(2);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (int i = 0; i < 500; ++i) {
    const MapLine line{2.0 + 2 * u(rng), wrapAngle(4 * u(rng))};
    const Pose2 p{3 * u(rng), 3 * u(rng), wrapAngle(4 * u(rng))};
    const LinePrediction pred = predictLine(p, line);
    const Vec2 n{std::cos(line.beta), std::sin(line.beta)};
    for (const double t : {-5.0, 7.0}) {
      const Vec2 q = n * line.rho + n.perp() * t;
      const Vec2 local = p.inverse().transform(q);
      EXPECT_NEAR(local.x * std::cos(pred.psi) + local.y * std::sin(pred.psi), pred.r, 1e-9);
    }
    EXPECT_GE(pred.r, 0.0);
  }
}

TEST(LineModel, JacobianMatchesFiniteDifferences) {
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (int trial = 0; trial < 200; ++trial) {
    const MapLine line{2.0 + u(rng), wrapAngle(4 * u(rng))};
    const Pose2 p{u(rng), u(rng), wrapAngle(4 * u(rng))};
    const LinePrediction pred = predictLine(p, line);
    if (pred.r < 1e-3) {
      continue;
    }
    const auto f = [&](const Eigen::VectorXd& x) -> Eigen::Vector2d {
      const LinePrediction q = predictLine(pose(x), line);
      return {q.r, q.psi};
    };
    const Eigen::MatrixXd H = numericJacobian<2>(f, vec(p), 1);
    EXPECT_LT((H - pred.H).cwiseAbs().maxCoeff(), 1e-6) << trial;
    EXPECT_DOUBLE_EQ(pred.H(1, 2), -1.0);
  }
}

TEST(BearingModel, SeedExamplesAndJacobian) {
  EXPECT_NEAR(predictBearing(Pose2{0, 0, 0}, Vec2{2, 0}).gamma, 0.0, 1e-12);
  EXPECT_NEAR(predictBearing(Pose2{0, 0, kPi / 2}, Vec2{2, 0}).gamma, -kPi / 2, 1e-12);
  EXPECT_NEAR(predictBearing(Pose2{0, 0, 0}, Vec2{-2, 0}).gamma, kPi, 1e-12);  // (−π, π]
  std::mt19937 rng(4);
  std::uniform_real_distribution<double> u(-3.0, 3.0);
  for (int trial = 0; trial < 200; ++trial) {
    const Pose2 p{u(rng), u(rng), wrapAngle(u(rng))};
    const Vec2 lm{u(rng), u(rng)};
    const BearingPrediction b = predictBearing(p, lm);
    if (b.range < 0.1) {
      continue;
    }
    const auto f = [&](const Eigen::VectorXd& x) -> Eigen::Matrix<double, 1, 1> {
      return Eigen::Matrix<double, 1, 1>::Constant(predictBearing(pose(x), lm).gamma);
    };
    const Eigen::MatrixXd H = numericJacobian<1>(f, vec(p), 0);
    EXPECT_LT((H - b.H).cwiseAbs().maxCoeff(), 1e-5) << trial;
    EXPECT_DOUBLE_EQ(b.H(2), -1.0);
  }
}
