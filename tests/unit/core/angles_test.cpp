#include <gtest/gtest.h>

#include <random>

#include "fleet/core/angles.hpp"
#include "fleet/core/clock.hpp"
#include "fleet/core/ids.hpp"
#include "fleet/core/pose2.hpp"

using namespace fleet;

TEST(Angles, WrapIsInHalfOpenInterval) {
  EXPECT_DOUBLE_EQ(wrapAngle(kPi), kPi);
  EXPECT_DOUBLE_EQ(wrapAngle(-kPi), kPi);
  EXPECT_NEAR(wrapAngle(3 * kPi), kPi, 1e-12);
  EXPECT_NEAR(wrapAngle(2 * kPi + 0.5), 0.5, 1e-12);
  EXPECT_NEAR(wrapAngle(-2 * kPi - 0.5), -0.5, 1e-12);
  std::mt19937 rng(1);
  std::uniform_real_distribution<double> u(-1000, 1000);
  for (int i = 0; i < 10000; ++i) {
    const double a = u(rng);
    const double w = wrapAngle(a);
    EXPECT_GT(w, -kPi);
    EXPECT_LE(w, kPi);
    EXPECT_NEAR(std::cos(w), std::cos(a), 1e-9);
    EXPECT_NEAR(std::sin(w), std::sin(a), 1e-9);
  }
}

TEST(Angles, DiffIsShortestWay) {
  EXPECT_NEAR(angleDiff(deg2rad(170), deg2rad(-170)), deg2rad(-20), 1e-12);
  EXPECT_NEAR(angleDiff(deg2rad(-170), deg2rad(170)), deg2rad(20), 1e-12);
}

TEST(Pose2, ComposeWithInverseIsIdentity) {
  std::mt19937 rng(2);
  std::uniform_real_distribution<double> u(-10, 10);
  for (int i = 0; i < 1000; ++i) {
    const Pose2 p{u(rng), u(rng), wrapAngle(u(rng))};
    const Pose2 id = p.compose(p.inverse());
    EXPECT_NEAR(id.x, 0, 1e-9);
    EXPECT_NEAR(id.y, 0, 1e-9);
    EXPECT_NEAR(id.theta, 0, 1e-9);
  }
}

TEST(Pose2, TransformRotatesThenTranslates) {
  const Pose2 p{1, 2, kPi / 2};
  const Vec2 q = p.transform({1, 0});
  EXPECT_NEAR(q.x, 1, 1e-12);
  EXPECT_NEAR(q.y, 3, 1e-12);
}

TEST(Ids, ValidAndInvalid) {
  EXPECT_TRUE(isValidId("robot-01"));
  EXPECT_TRUE(isValidId("task:2026.11.22_7"));
  EXPECT_FALSE(isValidId(""));
  EXPECT_FALSE(isValidId("has space"));
  EXPECT_FALSE(isValidId("quote\""));
  EXPECT_FALSE(isValidId(std::string(64, 'a')));
  EXPECT_TRUE(isValidId(std::string(63, 'a')));
}

TEST(Clock, SimClockNeverGoesBack) {
  SimClock c(100);
  EXPECT_TRUE(c.set(200));
  EXPECT_FALSE(c.set(150));
  EXPECT_EQ(c.nowNs(), 200);
  c.advance(50);
  EXPECT_EQ(c.nowNs(), 250);
  WallClock w;
  EXPECT_GT(w.nowNs(), secToNs(1.7e9));  // after 2023
}
