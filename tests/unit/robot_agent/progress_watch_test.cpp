// The progress watch alone: fed samples, it fails a task that comes no closer to its goal, ends a
// return that stands still, and hands a stalled local planner over to the follower.

#include "progress_watch.hpp"

#include <gtest/gtest.h>

#include <cstdint>

using namespace fleet;
using agent::ProgressSample;
using agent::ProgressVerdict;
using agent::ProgressWatch;

namespace {

constexpr std::int64_t kSecond = 1'000'000'000;

ProgressSample driving(double t, Vec2 here, Vec2 goal = {20.0, 0.0}) {
  ProgressSample s;
  s.nowNs = static_cast<std::int64_t>(t * 1e9);
  s.here = here;
  s.travelling = true;
  s.goal = goal;
  s.hasOrder = true;
  return s;
}

}  // namespace

TEST(ProgressWatch, FailsATaskThatComesNoCloserForThreeTimesTheBlockedLimit) {
  ProgressWatch watch({60.0, 4.0});
  watch.newOrder();
  EXPECT_EQ(watch.failAfterS(), 180);
  // Back and forth across 1 m for ever: it moves, but never gets 0.25 m closer than at the start.
  ProgressVerdict last = ProgressVerdict::kNone;
  double failedAt = -1.0;
  for (int k = 0; k <= 2000 && failedAt < 0.0; ++k) {
    const double t = 0.1 * k;
    last = watch.check(driving(t, {(k / 10) % 2 == 0 ? 0.0 : -1.0, 0.0}));
    if (last != ProgressVerdict::kNone) {
      failedAt = t;
    }
  }
  EXPECT_EQ(last, ProgressVerdict::kFailTask);
  EXPECT_NEAR(failedAt, 180.1, 1e-6) << "the first cycle more than 180 s after the order started";
}

TEST(ProgressWatch, CreepingCloserKeepsTheTaskAlive) {
  ProgressWatch watch({60.0, 4.0});
  watch.newOrder();
  // 0.3 m closer every 100 s: slow, but progress.
  for (int k = 0; k <= 4000; ++k) {
    const double t = 0.1 * k;
    ASSERT_EQ(watch.check(driving(t, {0.3 * static_cast<double>(k / 1000), 0.0})), ProgressVerdict::kNone)
        << "at " << t << " s";
  }
}

TEST(ProgressWatch, StandingStillOutsideTheTravellingPhasesIsNoFailure) {
  ProgressWatch watch({60.0, 4.0});
  watch.newOrder();
  for (int k = 0; k <= 3000; ++k) {
    auto s = driving(0.1 * k, {0.0, 0.0});
    s.travelling = false;  // dwelling, waiting to start
    ASSERT_EQ(watch.check(s), ProgressVerdict::kNone);
  }
}

TEST(ProgressWatch, WithoutAnOrderNothingFails) {
  ProgressWatch watch({60.0, 4.0});
  watch.newOrder();
  for (int k = 0; k <= 3000; ++k) {
    auto s = driving(0.1 * k, {0.0, 0.0});
    s.hasOrder = false;
    ASSERT_EQ(watch.check(s), ProgressVerdict::kNone);
  }
}

TEST(ProgressWatch, ASensorOutageDoesNotCountAsTimeWithoutProgress) {
  ProgressWatch watch({60.0, 4.0});
  watch.newOrder();
  EXPECT_EQ(watch.check(driving(0.0, {0.0, 0.0})), ProgressVerdict::kNone);
  watch.afterSensorOutage(100 * kSecond);
  EXPECT_EQ(watch.check(driving(170.0, {0.0, 0.0})), ProgressVerdict::kNone) << "70 s of it were driving";
  EXPECT_EQ(watch.check(driving(281.0, {0.0, 0.0})), ProgressVerdict::kFailTask);
}

TEST(ProgressWatch, AnOperatorsPauseDoesNotCountAsTimeWithoutProgress) {
  ProgressWatch watch({60.0, 4.0});
  watch.newOrder();
  ASSERT_EQ(watch.check(driving(0.0, {0.0, 0.0})), ProgressVerdict::kNone);
  // Held for five minutes, then standing a while longer: 190 s of the order's time, 10 s of it
  // unpaused, so no failure yet; the failure comes 180 s after the pause.
  watch.afterPause(300 * kSecond);
  EXPECT_EQ(watch.check(driving(310.0, {0.0, 0.0})), ProgressVerdict::kNone);
  EXPECT_EQ(watch.check(driving(479.0, {0.0, 0.0})), ProgressVerdict::kNone);
  EXPECT_EQ(watch.check(driving(481.0, {0.0, 0.0})), ProgressVerdict::kFailTask);
}

TEST(ProgressWatch, QueueingForAStationRestartsTheClock) {
  ProgressWatch watch({60.0, 4.0});
  watch.newOrder();
  EXPECT_EQ(watch.check(driving(0.0, {0.0, 0.0})), ProgressVerdict::kNone);
  watch.queueing(150 * kSecond);
  EXPECT_EQ(watch.check(driving(200.0, {0.0, 0.0})), ProgressVerdict::kNone);
  EXPECT_EQ(watch.check(driving(331.0, {0.0, 0.0})), ProgressVerdict::kFailTask);
}

TEST(ProgressWatch, AReturnThatStandsStillEndsAfterTwiceTheBackoffTime) {
  ProgressWatch watch({60.0, 4.0});
  watch.newOrder();
  ProgressVerdict v = ProgressVerdict::kNone;
  int k = 0;
  for (; k <= 200 && v == ProgressVerdict::kNone; ++k) {
    auto s = driving(0.1 * k, {5.0, 5.0});
    s.returning = true;
    v = watch.check(s);
  }
  EXPECT_EQ(v, ProgressVerdict::kEndReturn);
  EXPECT_EQ(k - 1, 81) << "the first cycle more than 8 s after it stopped moving";
}

TEST(ProgressWatch, AReturnThatMovesGoesOn) {
  ProgressWatch watch({60.0, 4.0});
  watch.newOrder();
  for (int k = 0; k <= 200; ++k) {
    auto s = driving(0.1 * k, {0.02 * k, 0.0});  // 0.2 m/s
    s.returning = true;
    ASSERT_EQ(watch.check(s), ProgressVerdict::kNone) << k;
  }
}

TEST(ProgressWatch, AStalledPlannerHandsOverToTheFollowerForEightSeconds) {
  ProgressWatch watch({60.0, 4.0});
  std::optional<std::int64_t> until;
  int k = 0;
  for (; k <= 100 && !until; ++k) {
    EXPECT_FALSE(watch.followerDrives(k * kSecond / 10));
    until = watch.watchPlanner(k * kSecond / 10, {1.0, 1.0}, true);
  }
  ASSERT_TRUE(until.has_value());
  EXPECT_EQ(k - 1, 61) << "the first cycle more than 6 s on one spot";
  EXPECT_EQ(*until, 61 * kSecond / 10 + 8 * kSecond);
  EXPECT_TRUE(watch.followerDrives(*until - 1));
  EXPECT_FALSE(watch.followerDrives(*until));
}

TEST(ProgressWatch, APlannerThatIsHeldOrMovesIsNoStall) {
  ProgressWatch watch({60.0, 4.0});
  for (int k = 0; k <= 200; ++k) {
    // Held every 5 s (which restarts the watch), else turning on the spot.
    ASSERT_FALSE(watch.watchPlanner(k * kSecond / 10, {1.0, 1.0}, k % 50 != 0)) << k;
  }
  for (int k = 0; k <= 200; ++k) {
    ASSERT_FALSE(watch.watchPlanner((30 + k) * kSecond / 10, {1.0 + 0.02 * k, 1.0}, true)) << k;
  }
}
