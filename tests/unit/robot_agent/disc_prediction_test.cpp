#include "disc_prediction.hpp"

#include <gtest/gtest.h>

#include <cmath>

namespace fleet::agent {
namespace {

struct Eig {
  double lmax, lmin, majorAngle;
};

Eig eig(const msg::Disc& d) {
  const double xx = d.cov_xx, xy = d.cov_xy, yy = d.cov_yy;
  const double half = 0.5 * (xx - yy), split = std::sqrt(half * half + xy * xy);
  return {0.5 * (xx + yy) + split, 0.5 * (xx + yy) - split, 0.5 * std::atan2(2.0 * xy, xx - yy)};
}

TEST(DiscPrediction, StandingStillKeepsTheEkfCovarianceAndGrowsRound) {
  Eigen::Matrix3d P = Eigen::Matrix3d::Zero();
  P << 0.04, 0.01, 0.0, 0.01, 0.02, 0.0, 0.0, 0.0, 0.01;
  const auto discs = predictDiscs({1, 2, 0.3}, P, 0.0, 0.0, {});
  ASSERT_EQ(discs.size(), 7u);  // 3 s at 0.5 s, both ends
  EXPECT_FLOAT_EQ(discs[0].cov_xx, 0.04f);
  EXPECT_FLOAT_EQ(discs[0].cov_xy, 0.01f);
  EXPECT_FLOAT_EQ(discs[0].cov_yy, 0.02f);
  const double g = 0.1 * 3.0;  // isotropic growth only
  EXPECT_NEAR(discs[6].cov_xx, 0.04 + g * g, 1e-6);
  EXPECT_NEAR(discs[6].cov_xy, 0.01, 1e-6);
  EXPECT_NEAR(discs[6].cov_yy, 0.02 + g * g, 1e-6);
  EXPECT_FLOAT_EQ(discs[6].x, 1.0f);
  EXPECT_NEAR(discs[6].sigma, std::sqrt(eig(discs[6]).lmax), 1e-6);
}

TEST(DiscPrediction, MovingFastStretchesAlongTheHeadingAndHeadingErrorWidensAcross) {
  Eigen::Matrix3d P = Eigen::Matrix3d::Identity() * 1e-4;  // σ 1 cm, 0.57°
  const double th = 0.6;
  const auto discs = predictDiscs({0, 0, th}, P, 1.5, 0.0, {});
  for (std::size_t k = 1; k < discs.size(); ++k) {
    const auto e = eig(discs[k]);
    EXPECT_GE(e.lmin, 0.0);
    EXPECT_NEAR(std::remainder(e.majorAngle - th, M_PI), 0.0, 1e-3) << k;  // major axis = heading
    EXPECT_GT(e.lmax, eig(discs[k - 1]).lmax);
  }
  const double t = 3.0, along = 0.15 * 1.5 * t,
               across2 = 1e-4 + (0.1 * t) * (0.1 * t) + 1e-4 * (1.5 * t) * (1.5 * t);
  const auto e = eig(discs.back());
  EXPECT_NEAR(e.lmax, 1e-4 + (0.1 * t) * (0.1 * t) + along * along, 1e-5);
  EXPECT_NEAR(e.lmin, across2, 1e-5);
  EXPECT_NEAR(discs.back().x, 4.5 * std::cos(th), 1e-5);
}

TEST(DiscPrediction, TurningCarriesTheHeadingErrorAcrossTheArc) {
  // Only heading uncertainty: the position spread is the displacement turned by 90° times σθ.
  Eigen::Matrix3d P = Eigen::Matrix3d::Zero();
  P(2, 2) = 0.01;
  DiscPredictionParams p;
  p.isotropicRate = 0.0;
  p.alongTrackFraction = 0.0;
  const auto discs = predictDiscs({0, 0, 0}, P, 1.0, 0.5, p);
  for (const auto& d : discs) {
    const double dx = d.x, dy = d.y;
    EXPECT_NEAR(d.cov_xx, 0.01 * dy * dy, 1e-5);
    EXPECT_NEAR(d.cov_xy, -0.01 * dx * dy, 1e-5);
    EXPECT_NEAR(d.cov_yy, 0.01 * dx * dx, 1e-5);
  }
}

}  // namespace
}  // namespace fleet::agent
