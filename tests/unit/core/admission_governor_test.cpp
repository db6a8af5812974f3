// The admission governor: the lines' slots scaled by what the fleet's robot time did.

#include "fleet/core/admission_governor.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

using namespace fleet;

namespace {

// One window (30 s of fleet time, ticks of 0.5 s) of `robots` robots: `waiting` of them waiting on
// another robot, `idle` without a task, the rest driving. Returns whether k changed at its end.
bool window(AdmissionGovernor& g, int robots, int waiting, int idle, bool held) {
  bool changed = false;
  for (int t = 0; t < 60; ++t) {
    for (int r = 0; r < robots; ++r) {
      g.add(r < waiting          ? RobotActivity::WaitingOnRobot
            : r < waiting + idle ? RobotActivity::NoTask
                                 : RobotActivity::Driving,
            0.5);
    }
    changed = g.tick(0.5, held) || changed;
  }
  return changed;
}

}  // namespace

TEST(AdmissionGovernor, StartsAtTheLinesOwnPlaces) {
  const AdmissionGovernor g;
  EXPECT_EQ(g.scale(), 1.0);
  EXPECT_EQ(g.slots(0), 0u) << "no line: no slots to scale";
  EXPECT_EQ(g.slots(3), 3u);
}

// 300 robots on the site for 300 by the lines' places: 64 % without a task, 4 % waiting on a robot.
TEST(AdmissionGovernor, RobotsIdleWhileTasksAreHeldAndFewWaitingWidenTheLinesAStepAWindow) {
  AdmissionGovernor g;
  EXPECT_TRUE(window(g, 100, 4, 64, true));
  EXPECT_EQ(g.scale(), 1.25);
  EXPECT_EQ(g.slots(4), 5u) << "floor(1.25 × 4)";
  EXPECT_NEAR(g.lastWaitingShare(), 0.04, 1e-12);
  EXPECT_NEAR(g.lastIdleShare(), 0.64, 1e-12);
  for (int w = 0; w < 40; ++w) {
    window(g, 100, 4, 64, true);
  }
  EXPECT_EQ(g.scale(), AdmissionGovernorConfig{}.maxScale) << "bounded";
}

TEST(AdmissionGovernor, NoStepUpWithoutAHeldTaskOrWithoutIdleRobots) {
  AdmissionGovernor g;
  EXPECT_FALSE(window(g, 100, 4, 64, false)) << "robots idle, but no task waits for a place";
  EXPECT_FALSE(window(g, 100, 4, 2, true)) << "nearly every robot works already";
  EXPECT_FALSE(window(g, 100, 7, 40, true)) << "in the band: waiting neither few nor many";
  EXPECT_EQ(g.scale(), 1.0);
}

// 100 robots on the site for 100 with wider lines: a quarter of the robot time waiting on a robot.
TEST(AdmissionGovernor, ManyWaitingOnARobotNarrowTheLinesBackButNeverBelowTheirPlaces) {
  AdmissionGovernor g;
  window(g, 100, 4, 64, true);
  window(g, 100, 4, 64, true);
  ASSERT_EQ(g.scale(), 1.5);
  EXPECT_TRUE(window(g, 100, 25, 1, true));
  EXPECT_EQ(g.scale(), 1.25);
  window(g, 100, 25, 1, true);
  EXPECT_EQ(g.scale(), 1.0);
  EXPECT_FALSE(window(g, 100, 25, 1, true));
  EXPECT_EQ(g.scale(), 1.0);
}

TEST(AdmissionGovernor, AHeldTaskAnywhereInTheWindowCountsAndBadTimesAreIgnored) {
  AdmissionGovernor g;
  g.add(RobotActivity::NoTask, 50.0);
  g.add(RobotActivity::Driving, 50.0);
  EXPECT_FALSE(g.tick(10.0, true));
  EXPECT_FALSE(g.tick(std::numeric_limits<double>::quiet_NaN(), false));
  EXPECT_FALSE(g.tick(-5.0, false));
  EXPECT_TRUE(g.tick(20.0, false)) << "30 s in: the held task 20 s ago counts";
  EXPECT_EQ(g.scale(), 1.25);
  EXPECT_FALSE(g.tick(30.0, true)) << "an empty window decides nothing";
  // ... and is over: a tenth of a second filed after it is no window to step on.
  g.add(RobotActivity::NoTask, 0.1);
  EXPECT_FALSE(g.tick(0.1, true));
  EXPECT_EQ(g.scale(), 1.25);
}
