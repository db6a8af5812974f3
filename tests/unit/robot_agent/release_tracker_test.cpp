// The release tracker alone: which releases it takes, the nodes a robot reaches along a base, how
// far it still may go, and the speed from which it can stop in that distance.

#include "release_tracker.hpp"

#include <gtest/gtest.h>

#include <cmath>

using namespace fleet;
using agent::BaseNode;
using agent::Release;
using agent::ReleaseTracker;
using agent::ReleaseVerdict;

namespace {

/// Nodes `first`..`last` on the line y = 0, 0.5 m apart, node k at x = 0.5·k.
std::vector<BaseNode> line(int first, int last) {
  std::vector<BaseNode> b;
  for (int k = first; k <= last; ++k) {
    b.push_back({k, {0.5 * k, 0.0}});
  }
  return b;
}

Release release(std::uint32_t epoch, std::uint32_t seq, std::vector<BaseNode> base, bool atGoal = false) {
  return {epoch, seq, std::move(base), atGoal};
}

}  // namespace

TEST(ReleaseTracker, TakesAFirstReleaseOnlyFromTheNodeNextToTheRobot) {
  ReleaseTracker t;
  EXPECT_EQ(t.node(), -1);
  EXPECT_FALSE(t.hasRelease());
  EXPECT_EQ(t.offer(release(1, 1, line(0, 4)), {2.0, 0.0}), ReleaseVerdict::kOffNode) << "2 m away";
  EXPECT_FALSE(t.hasRelease());
  EXPECT_EQ(t.offer(release(1, 2, line(0, 4)), {0.3, 0.4}), ReleaseVerdict::kAccepted);
  EXPECT_EQ(t.node(), 0);
  EXPECT_EQ(t.epoch(), 1u);
  EXPECT_TRUE(t.nodesAhead());
  EXPECT_EQ(t.counts().accepted, 1u);
  EXPECT_EQ(t.counts().offNode, 1u);
}

TEST(ReleaseTracker, IgnoresStaleAndOutOfOrderReleasesOfItsEpoch) {
  ReleaseTracker t;
  ASSERT_EQ(t.offer(release(3, 10, line(0, 2)), {0.0, 0.0}), ReleaseVerdict::kAccepted);
  const auto rev = t.revision();
  EXPECT_EQ(t.offer(release(3, 10, line(0, 8)), {0.0, 0.0}), ReleaseVerdict::kStale) << "the same seq";
  EXPECT_EQ(t.offer(release(3, 9, line(0, 8)), {0.0, 0.0}), ReleaseVerdict::kStale) << "an older seq";
  // Newer, but planned from node 1, which the robot has not reported: its base could lead through
  // what was released to it from node 0 only.
  EXPECT_EQ(t.offer(release(3, 11, line(1, 8)), {0.0, 0.0}), ReleaseVerdict::kOffNode);
  EXPECT_EQ(t.revision(), rev) << "nothing was taken";
  EXPECT_EQ(t.end()->x, 1.0) << "still the first base";
  EXPECT_EQ(t.counts().stale, 2u);
  EXPECT_EQ(t.counts().offNode, 1u);
  // Once the robot has reached node 1, a release from there is taken.
  ASSERT_TRUE(t.advance({0.5, 0.0}));
  EXPECT_EQ(t.node(), 1);
  EXPECT_EQ(t.offer(release(3, 12, line(1, 8)), {0.5, 0.0}), ReleaseVerdict::kAccepted);
  EXPECT_EQ(t.end()->x, 4.0);
  EXPECT_EQ(t.counts().ignored(), 3u);
}

TEST(ReleaseTracker, ANewEpochIsTakenFromTheReportedNodeOrTheNodeNextToTheRobot) {
  ReleaseTracker t;
  ASSERT_EQ(t.offer(release(1, 50, line(0, 4)), {0.0, 0.0}), ReleaseVerdict::kAccepted);
  ASSERT_TRUE(t.advance({1.0, 0.0}));
  ASSERT_EQ(t.node(), 2);
  // A restarted traffic manager counts seqs from 1 again.
  EXPECT_EQ(t.offer(release(2, 1, line(2, 6)), {1.1, 0.0}), ReleaseVerdict::kAccepted) << "its reported node";
  EXPECT_EQ(t.epoch(), 2u);
  // Another restart that places the robot on a node of its own choosing: taken when that node is
  // next to the robot, refused when it is not.
  EXPECT_EQ(t.offer(release(3, 1, {{40, {1.6, 3.0}}, {41, {1.6, 4.0}}}), {1.1, 0.0}),
            ReleaseVerdict::kOffNode);
  EXPECT_EQ(t.epoch(), 2u);
  EXPECT_EQ(t.offer(release(3, 2, {{40, {1.5, 0.5}}, {41, {1.5, 1.0}}}), {1.1, 0.0}),
            ReleaseVerdict::kAccepted);
  EXPECT_EQ(t.node(), 40);
}

TEST(ReleaseTracker, ReachesNodesInOrderWithinTheToleranceOrByPassingThem) {
  ReleaseTracker t;
  ASSERT_EQ(t.offer(release(1, 1, line(0, 6)), {0.0, 0.0}), ReleaseVerdict::kAccepted);
  EXPECT_FALSE(t.advance({0.3, 0.0})) << "0.2 m short of node 1";
  EXPECT_TRUE(t.advance({0.36, 0.05}));
  EXPECT_EQ(t.node(), 1) << "within 0.15 m";
  EXPECT_FALSE(t.advance({0.6, 0.0}));
  // A late cycle: the robot is past node 2 and 3 already, a little off the line. The report skips
  // node 2 (passing it counts).
  EXPECT_TRUE(t.advance({1.6, 0.2}));
  EXPECT_EQ(t.node(), 3);
  // Far off the base (swerved round something): passing along does not count, being close does.
  EXPECT_FALSE(t.advance({2.1, 0.5}));
  EXPECT_EQ(t.node(), 3);
  EXPECT_TRUE(t.advance({2.0, 0.1}));
  EXPECT_EQ(t.node(), 4);
  // The last node: within the tolerance, or overshot along the last leg.
  EXPECT_FALSE(t.advance({2.3, 0.0}));
  EXPECT_TRUE(t.advance({3.05, 0.0}));
  EXPECT_EQ(t.node(), 6) << "node 5 was passed";
  EXPECT_FALSE(t.nodesAhead());
  EXPECT_LT(t.remaining(), 0.0) << "past the end";
}

TEST(ReleaseTracker, AStationSpurIsDrivenInAndOutNotSkipped) {
  // From lane node 0 into a dock (7) 1 m up and back out to node 0: the robot starts on node 0,
  // which is also the base's last node.
  ReleaseTracker t;
  ASSERT_EQ(t.offer(release(1, 1, {{0, {0.0, 0.0}}, {7, {0.0, 1.0}}, {0, {0.0, 0.0}}}), {0.0, 0.0}),
            ReleaseVerdict::kAccepted);
  EXPECT_FALSE(t.advance({0.0, 0.0})) << "standing on the spur's mouth is not its end";
  EXPECT_NEAR(t.remaining(), 2.0, 1e-9);
  EXPECT_TRUE(t.advance({0.0, 0.9}));
  EXPECT_EQ(t.node(), 7);
  EXPECT_TRUE(t.advance({0.0, 0.1}));
  EXPECT_EQ(t.node(), 0);
  EXPECT_FALSE(t.nodesAhead());
}

TEST(ReleaseTracker, TheWayStopsWhereTheBaseTurnsBack) {
  // Out along a line and back along the line beside it: [0 1 2 9 8], 2 -> 9 turning back. The way
  // ends on node 2; once node 2 is reached, the rest.
  ReleaseTracker t;
  ASSERT_EQ(
      t.offer(
          release(1, 1,
                  {{0, {0.0, 0.0}}, {1, {0.5, 0.0}}, {2, {1.0, 0.0}}, {9, {0.5, -0.5}}, {8, {0.0, -0.5}}}),
          {0.0, 0.0}),
      ReleaseVerdict::kAccepted);
  auto way = t.aheadToTurnBack({0.0, 0.0});
  ASSERT_TRUE(way.turnsBackAt.has_value());
  EXPECT_EQ(*way.turnsBackAt, 2);
  ASSERT_EQ(way.points.size(), 3u);
  EXPECT_NEAR(way.points.back().x, 1.0, 1e-9);
  EXPECT_TRUE(t.advance({0.6, 0.0}));
  EXPECT_TRUE(t.advance({1.0, 0.0}));
  EXPECT_EQ(t.node(), 2);
  way = t.aheadToTurnBack({1.0, 0.0});
  EXPECT_FALSE(way.turnsBackAt.has_value());
  ASSERT_EQ(way.points.size(), 3u);
  EXPECT_NEAR(way.points.back().x, 0.0, 1e-9);
  ASSERT_TRUE(t.at().has_value());
  EXPECT_NEAR(t.at()->x, 1.0, 1e-9);
  // A right angle is no turning back: the whole base.
  ReleaseTracker r;
  ASSERT_EQ(r.offer(release(1, 1, {{0, {0.0, 0.0}}, {1, {0.5, 0.0}}, {2, {0.5, 0.5}}}), {0.0, 0.0}),
            ReleaseVerdict::kAccepted);
  EXPECT_FALSE(r.aheadToTurnBack({0.0, 0.0}).turnsBackAt.has_value());
}

TEST(ReleaseTracker, TheWayStopsBeforeALoopComesBackToTheRobot) {
  // The loop a robot was released round a block in the 20-robot scenario: from 649 by
  // two gentle corners and back to 1137, 0.25 m from where it started. Its last leg passes 0.1 m
  // from the robot, so a projection on the whole way takes it for nearly there; the way ends on
  // 1138 instead, and from there on, the rest.
  ReleaseTracker t;
  const std::vector<BaseNode> loop{{649, {25.75, 13.75}},
                                   {632, {25.25, 13.25}},
                                   {616, {25.25, 12.75}},
                                   {1138, {25.5, 12.75}},
                                   {1137, {25.5, 13.75}}};
  ASSERT_EQ(t.offer(release(1, 1, loop), {25.41, 13.64}), ReleaseVerdict::kAccepted);
  EXPECT_FALSE(t.advance({25.41, 13.64}));
  EXPECT_EQ(t.node(), 649);
  auto way = t.aheadToTurnBack({25.41, 13.64});
  ASSERT_TRUE(way.turnsBackAt.has_value());
  EXPECT_EQ(*way.turnsBackAt, 1138);
  EXPECT_NEAR(way.points.back().x, 25.5, 1e-9);
  EXPECT_NEAR(way.points.back().y, 12.75, 1e-9);
  EXPECT_TRUE(t.advance({25.26, 13.26}));
  EXPECT_EQ(t.node(), 632);
  EXPECT_TRUE(t.advance({25.26, 12.76}));
  EXPECT_TRUE(t.advance({25.5, 12.76}));
  EXPECT_EQ(t.node(), 1138);
  way = t.aheadToTurnBack({25.5, 12.76});
  EXPECT_FALSE(way.turnsBackAt.has_value());
  EXPECT_NEAR(way.points.back().y, 13.75, 1e-9);
  // Round one corner the way comes no closer to where it began than the arc allows: no cut.
  ReleaseTracker r;
  ASSERT_EQ(
      r.offer(release(1, 1,
                      {{0, {0.0, 0.0}}, {1, {0.5, 0.0}}, {2, {1.0, 0.0}}, {3, {1.0, 0.5}}, {4, {1.0, 1.0}}}),
              {0.0, 0.0}),
      ReleaseVerdict::kAccepted);
  EXPECT_FALSE(r.aheadToTurnBack({0.0, 0.0}).turnsBackAt.has_value());
}

TEST(ReleaseTracker, RemainingAndTheWayAheadFollowTheRobot) {
  ReleaseTracker t;
  // Along x to node 2 at (1, 0), then up to node 3 at (1, 1).
  ASSERT_EQ(t.offer(release(1, 1, {{0, {0.0, 0.0}}, {1, {0.5, 0.0}}, {2, {1.0, 0.0}}, {3, {1.0, 1.0}}}),
                    {0.0, 0.0}),
            ReleaseVerdict::kAccepted);
  (void)t.advance({0.7, 0.05});
  EXPECT_NEAR(t.remaining(), 1.3, 1e-9);
  const auto way = t.ahead({0.7, 0.05});
  ASSERT_EQ(way.size(), 3u);
  EXPECT_EQ(way[0], (Vec2{0.7, 0.05}));
  EXPECT_EQ(way[1], (Vec2{1.0, 0.0}));
  EXPECT_EQ(way[2], (Vec2{1.0, 1.0}));
  EXPECT_TRUE(t.onLastLeg() == false);
  (void)t.advance({1.0, 0.2});
  EXPECT_TRUE(t.onLastLeg());
  EXPECT_EQ(*t.next(), (Vec2{1.0, 1.0}));
}

// A bend under the sharp-turn angle is rounded, except at a node said to be tight (beside a
// shelf): there it is a corner too, as a 40-robot run's 39° bend at a parking row's approach node
// beside a shelf corner needed.
TEST(ReleaseTracker, AGentleBendIsACornerWhereTheNodeIsTight) {
  ReleaseTracker t;
  // Up from (0, 0) to (0, 0.85), then 39° to the left on to (-0.45, 1.4).
  ASSERT_EQ(t.offer(release(1, 1, {{0, {0.0, 0.0}}, {1, {0.0, 0.85}}, {2, {-0.45, 1.4}}}), {0.0, 0.0}),
            ReleaseVerdict::kAccepted);
  (void)t.advance({0.0, 0.1});
  EXPECT_FALSE(t.nextTurn(0.9).has_value());
  const auto near = [](Vec2 at) { return at.norm() > 0.5 && at.norm() < 1.0; };
  const auto turn = t.nextTurn(0.9, 0.3, near);
  ASSERT_TRUE(turn.has_value());
  EXPECT_EQ(turn->at, (Vec2{0.0, 0.85}));
  EXPECT_NEAR(turn->distance, 0.75, 1e-9);
  EXPECT_FALSE(t.nextTurn(0.9, 0.3, [](Vec2) { return false; }).has_value()) << "not tight: rounded";
  EXPECT_FALSE(t.nextTurn(0.9, 0.8, near).has_value()) << "under the tight angle: rounded";
}

TEST(ReleaseTracker, AnEmptyBaseHoldsTheRobotAtTheLastNodeItReached) {
  ReleaseTracker t;
  ASSERT_EQ(t.offer(release(1, 1, line(0, 8)), {0.0, 0.0}), ReleaseVerdict::kAccepted);
  ASSERT_TRUE(t.advance({1.0, 0.0}));
  EXPECT_EQ(t.offer(release(1, 2, {}), {1.1, 0.0}), ReleaseVerdict::kAccepted);
  EXPECT_FALSE(t.nodesAhead());
  EXPECT_EQ(t.node(), 2);
  EXPECT_LE(t.remaining(), 0.0);
}

TEST(ReleaseTracker, ANodeThatIsNotANumberIsRefused) {
  ReleaseTracker t;
  auto base = line(0, 3);
  base[2].at.x = std::nan("");
  EXPECT_EQ(t.offer(release(1, 1, base), {0.0, 0.0}), ReleaseVerdict::kMalformed);
  EXPECT_FALSE(t.hasRelease());
  EXPECT_EQ(t.counts().malformed, 1u);
}

TEST(ReleaseTracker, ForeignReleasesAreCountedAsIgnored) {
  ReleaseTracker t;
  t.noteForeign();
  EXPECT_EQ(t.counts().foreign, 1u);
  EXPECT_EQ(t.counts().ignored(), 1u);
}

TEST(StoppingSpeed, StopsWithinTheDistanceOneControlPeriodLate) {
  const double a = 1.0;
  const double dt = 0.1;
  EXPECT_EQ(agent::stoppingSpeed(0.0, a, dt), 0.0);
  EXPECT_EQ(agent::stoppingSpeed(-0.2, a, dt), 0.0);
  for (const double d : {0.01, 0.1, 0.4, 2.0}) {
    const double v = agent::stoppingSpeed(d, a, dt);
    EXPECT_NEAR(v * dt + v * v / (2.0 * a), d, 1e-12) << d;
  }
  // Without latency it is the textbook sqrt(2·a·d).
  EXPECT_NEAR(agent::stoppingSpeed(0.32, a, 0.0), 0.8, 1e-12);
  // Braking from that speed at `a`, the robot covers the distance and no more (integrated finely).
  const double d = 0.5;
  double v = agent::stoppingSpeed(d, a, dt);
  double x = v * dt;  // the latency: the command in force for one more period
  const double h = 1e-4;
  while (v > 0.0) {
    x += v * h;
    v -= a * h;
  }
  EXPECT_LE(x, d + 1e-3);
}
