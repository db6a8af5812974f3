#include "fleet/control/diff_drive_kinematics.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "fleet/control/diff_drive_base.hpp"
#include "fleet/core/angles.hpp"

using namespace fleet;
using namespace fleet::control;

namespace {
DiffDriveKinematics kin(double L = 0.6) {
  return DiffDriveKinematics::create(L).value();
}
}  // namespace

TEST(DiffDriveKinematics, RejectsBadWheelBase) {
  EXPECT_FALSE(DiffDriveKinematics::create(0.0).has_value());
  EXPECT_FALSE(DiffDriveKinematics::create(-0.5).has_value());
  EXPECT_FALSE(DiffDriveKinematics::create(std::nan("")).has_value());
  EXPECT_EQ(DiffDriveKinematics::create(0.0).error().code, "invalid_wheel_base");
}

TEST(DiffDriveKinematics, EqualWheelsDriveStraight) {
  // Seed 003 behaviour 1: ΔsR = ΔsL = d advances d along θ, θ unchanged.
  const Pose2 p{1.0, 2.0, 0.7};
  const Pose2 q = kin().applyOdometry(p, 0.25, 0.25);
  EXPECT_NEAR(q.x, 1.0 + 0.25 * std::cos(0.7), 1e-12);
  EXPECT_NEAR(q.y, 2.0 + 0.25 * std::sin(0.7), 1e-12);
  EXPECT_NEAR(q.theta, 0.7, 1e-12);
}

TEST(DiffDriveKinematics, OppositeWheelsSpinInPlace) {
  // ΔsR = −ΔsL = d → Δθ = 2d/L and (x, y) unchanged.
  const Pose2 p{1.0, 2.0, 0.7};
  const Pose2 q = kin(0.5).applyOdometry(p, -0.1, 0.1);
  EXPECT_NEAR(q.x, 1.0, 1e-12);
  EXPECT_NEAR(q.y, 2.0, 1e-12);
  EXPECT_NEAR(q.theta, 0.7 + 2 * 0.1 / 0.5, 1e-12);
  const OdometryDelta d = kin(0.5).odometryDelta(-0.1, 0.1);
  EXPECT_NEAR(d.ds, 0.0, 1e-15);
  EXPECT_NEAR(d.dtheta, 0.4, 1e-15);
}

TEST(DiffDriveKinematics, UsesMidpointHeading) {
  // Δs = 0.2, Δθ = 0.5: the displacement is along θ + Δθ/2, not θ.
  const Pose2 q = kin(0.6).applyOdometry(Pose2{}, 0.2 - 0.15, 0.2 + 0.15);
  EXPECT_NEAR(q.x, 0.2 * std::cos(0.25), 1e-12);
  EXPECT_NEAR(q.y, 0.2 * std::sin(0.25), 1e-12);
  EXPECT_NEAR(q.theta, 0.5, 1e-12);
}

TEST(DiffDriveKinematics, WheelSpeedsRoundTrip) {
  const auto k = kin(0.6);
  std::mt19937 rng(1);
  std::uniform_real_distribution<double> u(-2.0, 2.0);
  for (int i = 0; i < 1000; ++i) {
    const Twist t{u(rng), u(rng)};
    const WheelSpeeds w = k.toWheelSpeeds(t);
    EXPECT_NEAR(w.right - w.left, t.omega * 0.6, 1e-12);
    const Twist back = k.toTwist(w);
    EXPECT_NEAR(back.v, t.v, 1e-12);
    EXPECT_NEAR(back.omega, t.omega, 1e-12);
  }
}

TEST(DiffDriveKinematics, OdometryMatchesMidpointIntegration) {
  // Wheel increments produced by (v, ω) over dt give the same pose as the unicycle midpoint rule.
  const auto k = kin(0.6);
  std::mt19937 rng(2);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (int i = 0; i < 200; ++i) {
    const Pose2 p{u(rng), u(rng), wrapAngle(3 * u(rng))};
    const Twist t{u(rng), 2 * u(rng)};
    const WheelSpeeds w = k.toWheelSpeeds(t);
    const Pose2 a = k.applyOdometry(p, w.left * 0.1, w.right * 0.1);
    const Pose2 b = DiffDriveKinematics::integrateMidpoint(p, t, 0.1);
    EXPECT_NEAR(a.x, b.x, 1e-12);
    EXPECT_NEAR(a.y, b.y, 1e-12);
    EXPECT_NEAR(angleDiff(a.theta, b.theta), 0.0, 1e-12);
  }
}

TEST(DiffDriveKinematics, ExactArcClosesCircle) {
  // Driving a full circle of radius 1 in 100 exact steps returns to the start.
  const Twist t{1.0, 1.0};
  const double period = 2 * kPi;
  Pose2 exact{};
  for (int i = 0; i < 100; ++i) {
    exact = DiffDriveKinematics::integrateExact(exact, t, period / 100);
  }
  EXPECT_NEAR(exact.x, 0.0, 1e-9);
  EXPECT_NEAR(exact.y, 0.0, 1e-9);
  // Quarter circle: exact arc ends at (1, 1); one midpoint step's error is ds·(1 − sinc(Δθ/2)) = O(Δθ³),
  // so halving the step cuts it about 8×.
  const Pose2 q = DiffDriveKinematics::integrateExact(Pose2{}, t, kPi / 2);
  EXPECT_NEAR(q.x, 1.0, 1e-12);
  EXPECT_NEAR(q.y, 1.0, 1e-12);
  auto step_error = [&](double dt) {
    const Pose2 a = DiffDriveKinematics::integrateExact(Pose2{}, t, dt);
    const Pose2 b = DiffDriveKinematics::integrateMidpoint(Pose2{}, t, dt);
    return std::hypot(a.x - b.x, a.y - b.y);
  };
  EXPECT_GT(step_error(0.2), 1e-5);
  EXPECT_NEAR(step_error(0.2) / step_error(0.1), 8.0, 0.1);
  // Straight-line limit of the exact arc.
  const Pose2 s = DiffDriveKinematics::integrateExact(Pose2{0, 0, 0.3}, Twist{2.0, 0.0}, 0.5);
  EXPECT_NEAR(s.x, std::cos(0.3), 1e-12);
  EXPECT_NEAR(s.y, std::sin(0.3), 1e-12);
}

TEST(DiffDriveBase, LimitsCommandsAndReportsWheelIncrements) {
  const VelocityLimits limits;  // 0.45 m/s, 0.5 m/s²
  auto base = DiffDriveBase::create(0.6, limits, Pose2{});
  ASSERT_TRUE(base.has_value());
  EXPECT_FALSE(DiffDriveBase::create(0.6, limits, Pose2{std::nan(""), 0, 0}).has_value());
  EXPECT_FALSE(DiffDriveBase::create(-1.0, limits, Pose2{}).has_value());
  // Full-speed request: ramps at 0.05 m/s per 0.1 s step, then holds 0.45 m/s.
  double travelled = 0.0;
  Pose2 odo{};
  for (int k = 0; k < 30; ++k) {
    const auto r = base->step(Twist{2.0, 0.0}, 0.1);
    travelled += 0.5 * (r.ds_left + r.ds_right);
    odo = base->kinematics().applyOdometry(odo, r.ds_left, r.ds_right);
  }
  EXPECT_NEAR(base->twist().v, 0.45, 1e-12);
  EXPECT_NEAR(base->pose().x, travelled, 1e-12);
  // 9 ramp steps (0.05 … 0.45) then 21 at 0.45.
  EXPECT_NEAR(travelled, 0.1 * (0.05 * 45.0 + 0.45 * 21.0), 1e-9);
  // Turning: the encoders' odometry agrees with the exact pose to the midpoint rule's accuracy.
  for (int k = 0; k < 50; ++k) {
    const auto r = base->step(Twist{0.3, 0.8}, 0.1);
    odo = base->kinematics().applyOdometry(odo, r.ds_left, r.ds_right);
  }
  EXPECT_LT(distance(odo, base->pose()), 1e-3);
  EXPECT_NEAR(angleDiff(odo.theta, base->pose().theta), 0.0, 1e-9);
  // A NaN request brings the base to a controlled stop and is flagged.
  int rejected = 0;
  for (int k = 0; k < 20; ++k) {
    rejected += base->step(Twist{std::nan(""), 0.0}, 0.1).applied.rejected ? 1 : 0;
  }
  EXPECT_EQ(rejected, 20);
  EXPECT_EQ(base->twist(), (Twist{0.0, 0.0}));
  EXPECT_TRUE(base->pose().isFinite());
}
