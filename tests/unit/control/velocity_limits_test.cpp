#include "fleet/control/velocity_limits.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>

using namespace fleet::control;

TEST(VelocityLimits, Validation) {
  EXPECT_TRUE(VelocityLimits{}.validate().has_value());
  VelocityLimits l;
  l.vMin = 0.1;
  EXPECT_FALSE(l.validate().has_value());
  l = {};
  l.accelMax = 0.0;
  EXPECT_FALSE(l.validate().has_value());
  l = {};
  l.omegaMax = std::numeric_limits<double>::infinity();
  EXPECT_FALSE(l.validate().has_value());
}

TEST(VelocityLimits, SaturationKeepsCurvature) {
  VelocityLimits l;
  l.accelMax = 100.0;
  l.alphaMax = 100.0;
  const LimitedTwist r = applyLimits(l, Twist{0.9, 0.6}, Twist{0.45, 0.3}, 0.1);
  EXPECT_TRUE(r.saturated);
  EXPECT_NEAR(r.twist.v, 0.45, 1e-12);
  EXPECT_NEAR(r.twist.omega / r.twist.v, 0.6 / 0.9, 1e-12);
  const LimitedTwist spin = applyLimits(l, Twist{0.1, -3.0}, Twist{}, 0.1);
  EXPECT_NEAR(spin.twist.omega, -1.5, 1e-12);
  EXPECT_NEAR(spin.twist.v, 0.05, 1e-12);
  const LimitedTwist back = applyLimits(l, Twist{-1.0, 0.0}, Twist{}, 0.1);
  EXPECT_NEAR(back.twist.v, -0.45, 1e-12);
}

TEST(VelocityLimits, AccelerationIsRateLimited) {
  const VelocityLimits l;  // 0.5 m/s², 2 rad/s²
  const LimitedTwist r = applyLimits(l, Twist{0.4, 1.0}, Twist{}, 0.1);
  EXPECT_TRUE(r.saturated);
  EXPECT_NEAR(r.twist.v, 0.05, 1e-12);
  EXPECT_NEAR(r.twist.omega, 0.2, 1e-12);
  const LimitedTwist within = applyLimits(l, Twist{0.42, 0.5}, Twist{0.4, 0.45}, 0.1);
  EXPECT_FALSE(within.saturated);
  EXPECT_EQ(within.twist, (Twist{0.42, 0.5}));
}

TEST(VelocityLimits, RandomRequestsStayWithinBounds) {
  const VelocityLimits l;
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-3.0, 3.0);
  Twist prev{};
  for (int i = 0; i < 5000; ++i) {
    const LimitedTwist r = applyLimits(l, Twist{u(rng), u(rng)}, prev, 0.1);
    EXPECT_LE(r.twist.v, l.vMax + 1e-12);
    EXPECT_GE(r.twist.v, l.vMin - 1e-12);
    EXPECT_LE(std::abs(r.twist.omega), l.omegaMax + 1e-12);
    EXPECT_LE(std::abs(r.twist.v - prev.v), l.accelMax * 0.1 + 1e-12);
    EXPECT_LE(std::abs(r.twist.omega - prev.omega), l.alphaMax * 0.1 + 1e-12);
    prev = r.twist;
  }
}

TEST(VelocityLimits, NonFiniteRequestBecomesControlledStop) {
  const VelocityLimits l;
  const double nan = std::nan("");
  Twist cmd{0.4, 0.5};
  int rejected = 0;
  for (int i = 0; i < 20; ++i) {
    const LimitedTwist r = applyLimits(l, Twist{nan, 0.1}, cmd, 0.1);
    EXPECT_TRUE(r.twist.isFinite());
    EXPECT_LE(std::abs(r.twist.v), std::abs(cmd.v));
    rejected += r.rejected ? 1 : 0;
    cmd = r.twist;
  }
  EXPECT_EQ(rejected, 20);
  EXPECT_EQ(cmd, (Twist{0.0, 0.0}));
  // A NaN previous command is treated as standing still; a bad dt holds the previous command.
  const LimitedTwist r = applyLimits(l, Twist{0.3, 0.0}, Twist{nan, nan}, 0.1);
  EXPECT_FALSE(r.rejected);
  EXPECT_NEAR(r.twist.v, 0.05, 1e-12);
  EXPECT_EQ(applyLimits(l, Twist{0.3, 0.0}, Twist{0.1, 0.0}, -1.0).twist, (Twist{0.1, 0.0}));
}
