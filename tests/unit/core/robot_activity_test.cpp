#include "fleet/core/robot_activity.hpp"

#include <gtest/gtest.h>

#include <limits>
#include <random>

namespace fleet {
namespace {

TEST(RobotActivity, NamesRoundTrip) {
  for (std::size_t i = 0; i < kRobotActivities; ++i) {
    const auto a = static_cast<RobotActivity>(i);
    RobotActivity back = RobotActivity::Faulted;
    ASSERT_TRUE(parseRobotActivity(toString(a), back)) << toString(a);
    EXPECT_EQ(back, a);
  }
  RobotActivity x = RobotActivity::Driving;
  EXPECT_FALSE(parseRobotActivity("flying", x));
  EXPECT_EQ(x, RobotActivity::Driving);
}

TEST(RobotActivity, DerivedFromModeWhenUnset) {
  EXPECT_EQ(activityFromMode("idle", false), RobotActivity::NoTask);
  EXPECT_EQ(activityFromMode("idle", true), RobotActivity::WaitingOnRobot);
  EXPECT_EQ(activityFromMode("moving", true), RobotActivity::Driving);
  EXPECT_EQ(activityFromMode("loading", true), RobotActivity::Dwelling);
  EXPECT_EQ(activityFromMode("charging", false), RobotActivity::Charging);
  EXPECT_EQ(activityFromMode("fault", true), RobotActivity::Faulted);
  EXPECT_EQ(activityFromMode("waiting", true), RobotActivity::WaitingOnRobot);
  EXPECT_EQ(activityFromMode("blocked", true), RobotActivity::WaitingOnRobot);
  EXPECT_EQ(activityFromMode("", false), RobotActivity::NoTask);
}

// Property: whatever is filed, the shares of the nine categories add up to 1 and Unset never
// holds time.
TEST(ActivityLedger, SharesAddUpToOneForAnyFiling) {
  std::mt19937 rng(7);
  for (int trial = 0; trial < 200; ++trial) {
    ActivityLedger l;
    const int n = 1 + static_cast<int>(rng() % 50);
    for (int i = 0; i < n; ++i) {
      l.add(static_cast<RobotActivity>(rng() % kRobotActivities),
            std::uniform_real_distribution<double>(0.0, 3.0)(rng));
    }
    double sum = 0.0;
    for (const auto a : kLedgerActivities) {
      sum += l.share(a);
    }
    EXPECT_NEAR(sum, 1.0, 1e-12);
    EXPECT_EQ(l.seconds(RobotActivity::Unset), 0.0);
  }
}

TEST(ActivityLedger, IgnoresNegativeAndNonFiniteTime) {
  ActivityLedger l;
  l.add(RobotActivity::Driving, -1.0);
  l.add(RobotActivity::Driving, std::numeric_limits<double>::quiet_NaN());
  EXPECT_EQ(l.total(), 0.0);
  EXPECT_EQ(l.share(RobotActivity::Driving), 0.0);
  l.add(RobotActivity::Driving, 2.0);
  ActivityLedger m;
  m.add(RobotActivity::Dwelling, 2.0);
  m.add(l);
  EXPECT_DOUBLE_EQ(m.share(RobotActivity::Driving), 0.5);
}

}  // namespace
}  // namespace fleet
