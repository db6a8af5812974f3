// The progress watch alone: fed samples, it fails a task that comes no closer to its goal, and
// with one notion of "wants to progress and cannot" for every driver (the follower, a sampling
// planner, reserved traffic's base following) says when the robot has stalled; a stalled planner
// hands over to the follower.

#include "progress_watch.hpp"

#include <gtest/gtest.h>

#include <cstdint>
#include <random>

using namespace fleet;
using agent::Driver;
using agent::ProgressParams;
using agent::ProgressSample;
using agent::ProgressVerdict;
using agent::ProgressWatch;

namespace {

constexpr std::int64_t kSecond = 1'000'000'000;

ProgressSample driving(double t, Vec2 here, Vec2 goal = {20.0, 0.0}, Driver driver = Driver::kNone) {
  ProgressSample s;
  s.nowNs = static_cast<std::int64_t>(t * 1e9);
  s.here = here;
  s.travelling = true;
  s.goal = goal;
  s.hasOrder = true;
  s.driver = driver;
  return s;
}

/// The first cycle (0.1 s each) at which standing on one spot gives kStalled, or -1 within `n`.
int stalledAt(ProgressWatch& watch, Driver driver, int n = 1000) {
  for (int k = 0; k <= n; ++k) {
    if (watch.check(driving(0.1 * k, {1.0, 1.0}, {20.0, 0.0}, driver)) == ProgressVerdict::kStalled) {
      return k;
    }
  }
  return -1;
}

}  // namespace

TEST(ProgressWatch, FailsATaskThatComesNoCloserForFailS) {
  ProgressWatch watch({});
  watch.newOrder();
  EXPECT_EQ(watch.failAfterS(), 180);
  // Back and forth across 1 m for ever: it moves, but never gets 0.25 m closer than at the start.
  ProgressVerdict last = ProgressVerdict::kNone;
  double failedAt = -1.0;
  for (int k = 0; k <= 2000 && failedAt < 0.0; ++k) {
    const double t = 0.1 * k;
    last = watch.check(driving(t, {(k / 10) % 2 == 0 ? 0.0 : -1.0, 0.0}, {20.0, 0.0}, Driver::kPlanner));
    if (last == ProgressVerdict::kFailTask) {
      failedAt = t;
    }
  }
  EXPECT_EQ(last, ProgressVerdict::kFailTask);
  EXPECT_NEAR(failedAt, 180.1, 1e-6) << "the first cycle more than 180 s after the order started";
}

TEST(ProgressWatch, TheFailureLimitComesFromTheParameters) {
  ProgressParams p;
  p.failS = 30.0;
  ProgressWatch watch(p);
  watch.newOrder();
  EXPECT_EQ(watch.failAfterS(), 30);
  EXPECT_EQ(watch.check(driving(0.0, {0.0, 0.0})), ProgressVerdict::kNone);
  EXPECT_EQ(watch.check(driving(29.9, {0.0, 0.0})), ProgressVerdict::kNone);
  EXPECT_EQ(watch.check(driving(30.1, {0.0, 0.0})), ProgressVerdict::kFailTask);
}

TEST(ProgressWatch, CreepingCloserKeepsTheTaskAlive) {
  ProgressWatch watch({});
  watch.newOrder();
  // 0.3 m closer every 100 s: slow, but progress.
  for (int k = 0; k <= 4000; ++k) {
    const double t = 0.1 * k;
    ASSERT_NE(watch.check(driving(t, {0.3 * static_cast<double>(k / 1000), 0.0})), ProgressVerdict::kFailTask)
        << "at " << t << " s";
  }
}

// Property: whoever drives, at whatever speed and from wherever, a robot that moves towards its goal
// is never stalled and its task never fails.
TEST(ProgressWatch, ARobotThatMovesTowardsItsGoalNeverStallsNorFails) {
  std::mt19937 rng(17);
  std::uniform_real_distribution<double> speed(0.05, 1.2);
  std::uniform_real_distribution<double> coord(-30.0, 30.0);
  for (int trial = 0; trial < 200; ++trial) {
    ProgressWatch watch({});
    watch.newOrder();
    const Driver driver = trial % 2 == 0 ? Driver::kPlanner : Driver::kFollower;
    const Vec2 goal{coord(rng), coord(rng)};
    Vec2 here{coord(rng), coord(rng)};
    const double v = speed(rng);
    for (int k = 0; k < 20000 && distance(here, goal) > 0.2; ++k) {
      const auto verdict = watch.check(driving(0.1 * k, here, goal, driver));
      ASSERT_EQ(verdict, ProgressVerdict::kNone)
          << "trial " << trial << " at " << 0.1 * k << " s, " << distance(here, goal) << " m from the goal";
      here = here + (goal - here) * (std::min(v * 0.1, distance(here, goal)) / distance(here, goal));
    }
  }
}

// Property: standing while it wants to move, with nothing holding it, is a stall after stallS
// whoever drives: one threshold for the follower and every sampling planner.
TEST(ProgressWatch, StandingWhileWantingToMoveStallsAfterTheSameTimeForEveryDriver) {
  for (const Driver driver : {Driver::kFollower, Driver::kPlanner}) {
    ProgressWatch watch({});
    EXPECT_EQ(stalledAt(watch, driver), 61) << "the first cycle more than 6 s on one spot";
  }
  ProgressParams p;
  p.stallS = 2.0;
  for (const Driver driver : {Driver::kFollower, Driver::kPlanner}) {
    ProgressWatch watch(p);
    EXPECT_EQ(stalledAt(watch, driver), 21) << "stall_s from the parameters";
  }
}

TEST(ProgressWatch, OneWantSpeedForEveryDriver) {
  ProgressWatch watch({});
  EXPECT_TRUE(watch.wantsToMove(0.03)) << "a sampling planner's first step from standstill";
  EXPECT_TRUE(watch.wantsToMove(0.8)) << "the follower's cruise";
  EXPECT_FALSE(watch.wantsToMove(0.02));
  EXPECT_FALSE(watch.wantsToMove(-0.2));
}

TEST(ProgressWatch, AStalledPlannerHandsOverToTheFollowerForRecoverS) {
  ProgressWatch watch({});
  EXPECT_FALSE(watch.followerDrives(0));
  ASSERT_EQ(stalledAt(watch, Driver::kPlanner), 61);
  const std::int64_t until = 61 * kSecond / 10 + 8 * kSecond;
  EXPECT_TRUE(watch.followerDrives(until - 1));
  EXPECT_FALSE(watch.followerDrives(until));
}

TEST(ProgressWatch, AStalledFollowerHandsNothingOver) {
  ProgressWatch watch({});
  ASSERT_EQ(stalledAt(watch, Driver::kFollower), 61);
  EXPECT_FALSE(watch.followerDrives(62 * kSecond / 10)) << "the caller decides what a stalled follower does";
}

TEST(ProgressWatch, AHeldOrTurningRobotIsNoStallWhileItMoves) {
  ProgressWatch watch({});
  for (int k = 0; k <= 200; ++k) {
    // Held every 5 s (which restarts the watch), else turning on the spot.
    auto s = driving(0.1 * k, {1.0, 1.0}, {20.0, 0.0}, Driver::kPlanner);
    s.held = k % 50 == 0;
    ASSERT_NE(watch.check(s), ProgressVerdict::kStalled) << k;
  }
  for (int k = 0; k <= 200; ++k) {
    ASSERT_NE(watch.check(driving(20.0 + 0.1 * k, {1.0 + 0.02 * k, 1.0}, {20.0, 0.0}, Driver::kFollower)),
              ProgressVerdict::kStalled)
        << k;
  }
}

TEST(ProgressWatch, HeldByTheStopRuleIsNoStall) {
  ProgressWatch watch({});
  watch.newOrder();
  for (int k = 0; k <= 1000; ++k) {
    auto s = driving(0.1 * k, {1.0, 1.0}, {20.0, 0.0}, Driver::kFollower);
    s.held = true;  // the standoff rules' business
    ASSERT_EQ(watch.check(s), ProgressVerdict::kNone) << k;
  }
}

TEST(ProgressWatch, AChangeOfDriverRestartsTheStallClock) {
  ProgressWatch watch({});
  for (int k = 0; k <= 50; ++k) {
    ASSERT_EQ(watch.check(driving(0.1 * k, {1.0, 1.0}, {20.0, 0.0}, Driver::kPlanner)),
              ProgressVerdict::kNone);
  }
  for (int k = 51; k <= 111; ++k) {
    ASSERT_EQ(watch.check(driving(0.1 * k, {1.0, 1.0}, {20.0, 0.0}, Driver::kFollower)),
              ProgressVerdict::kNone)
        << k;
  }
  EXPECT_EQ(watch.check(driving(11.2, {1.0, 1.0}, {20.0, 0.0}, Driver::kFollower)),
            ProgressVerdict::kStalled);
}

TEST(ProgressWatch, NobodyDrivingIsNoStall) {
  ProgressWatch watch({});
  for (int k = 0; k <= 1000; ++k) {
    ASSERT_EQ(watch.check(driving(0.1 * k, {1.0, 1.0}, {20.0, 0.0}, Driver::kNone)), ProgressVerdict::kNone);
  }
}

// Property (reserved traffic): waiting on a dependency (a robot the plan knows) or on a person runs
// neither the stall clock nor the failure clock, however long; the clocks start when it ends.
TEST(ProgressWatch, WaitingOnADependencyOrAPersonRunsNoFailureTimer) {
  for (const Driver driver : {Driver::kFollower, Driver::kPlanner}) {
    ProgressWatch watch({});
    watch.newOrder();
    for (int k = 0; k <= 6000; ++k) {  // 600 s
      auto s = driving(0.1 * k, {1.0, 1.0}, {20.0, 0.0}, driver);
      s.held = true;
      s.waiting = true;
      ASSERT_EQ(watch.check(s), ProgressVerdict::kNone) << k;
    }
    EXPECT_EQ(watch.check(driving(700.0, {1.0, 1.0}, {20.0, 0.0})), ProgressVerdict::kNone)
        << "standing 100 s after the wait";
    EXPECT_EQ(watch.check(driving(780.1, {1.0, 1.0}, {20.0, 0.0})), ProgressVerdict::kFailTask)
        << "180 s after the wait ended";
  }
}

TEST(ProgressWatch, StandingStillOutsideTheTravellingPhasesIsNoFailure) {
  ProgressWatch watch({});
  watch.newOrder();
  for (int k = 0; k <= 3000; ++k) {
    auto s = driving(0.1 * k, {0.0, 0.0});
    s.travelling = false;  // dwelling, waiting to start
    ASSERT_EQ(watch.check(s), ProgressVerdict::kNone);
  }
}

TEST(ProgressWatch, WithoutAnOrderNothingFails) {
  ProgressWatch watch({});
  watch.newOrder();
  for (int k = 0; k <= 3000; ++k) {
    auto s = driving(0.1 * k, {0.0, 0.0});
    s.hasOrder = false;
    ASSERT_EQ(watch.check(s), ProgressVerdict::kNone);
  }
}

TEST(ProgressWatch, ASensorOutageDoesNotCountAsTimeWithoutProgress) {
  ProgressWatch watch({});
  watch.newOrder();
  EXPECT_EQ(watch.check(driving(0.0, {0.0, 0.0})), ProgressVerdict::kNone);
  watch.afterOutage(100 * kSecond);
  EXPECT_EQ(watch.check(driving(170.0, {0.0, 0.0})), ProgressVerdict::kNone) << "70 s of it were driving";
  EXPECT_EQ(watch.check(driving(281.0, {0.0, 0.0})), ProgressVerdict::kFailTask);
}

TEST(ProgressWatch, AnOperatorsPauseDoesNotCountAsTimeWithoutProgressNorStanding) {
  ProgressWatch watch({});
  watch.newOrder();
  ASSERT_EQ(watch.check(driving(0.0, {0.0, 0.0}, {20.0, 0.0}, Driver::kPlanner)), ProgressVerdict::kNone);
  // Held for five minutes, then standing a while longer: 190 s of the order's time, 10 s of it
  // unpaused, so no failure yet; the failure comes 180 s after the pause.
  watch.afterOutage(300 * kSecond);
  EXPECT_EQ(watch.check(driving(305.0, {0.0, 0.0}, {20.0, 0.0}, Driver::kPlanner)), ProgressVerdict::kNone)
      << "5 s standing, not 305";
  EXPECT_EQ(watch.check(driving(479.0, {0.0, 0.0})), ProgressVerdict::kNone);
  EXPECT_EQ(watch.check(driving(481.0, {0.0, 0.0})), ProgressVerdict::kFailTask);
}

TEST(ProgressWatch, QueueingForAStationRestartsTheClock) {
  ProgressWatch watch({});
  watch.newOrder();
  EXPECT_EQ(watch.check(driving(0.0, {0.0, 0.0})), ProgressVerdict::kNone);
  watch.queueing(150 * kSecond);
  EXPECT_EQ(watch.check(driving(200.0, {0.0, 0.0})), ProgressVerdict::kNone);
  EXPECT_EQ(watch.check(driving(331.0, {0.0, 0.0})), ProgressVerdict::kFailTask);
}
