// Why a robot waits on another (wait_cause.hpp): by what that robot does and how its way lies
// against the waiting robot's next one, on a lattice whose edges meet at multiples of 45°.

#include "fleet/traffic/wait_cause.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

namespace fleet::traffic {
namespace {

WaitSeen driving(Vec2 way, Vec2 otherWay) {
  WaitSeen s;
  s.way = way;
  s.at = {0.0, 0.0};
  s.named = true;
  s.otherAt = {1.0, 0.0};
  s.otherDriving = true;
  s.otherWay = otherWay;
  return s;
}

TEST(WaitCause, ByHowTheOthersWayLiesAgainstTheNextOne) {
  const Vec2 east{0.5, 0.0};
  EXPECT_EQ(classifyWait(driving(east, {0.5, 0.0})), WaitCause::SameWay);
  EXPECT_EQ(classifyWait(driving(east, {-0.5, 0.0})), WaitCause::HeadOn);
  EXPECT_EQ(classifyWait(driving(east, {0.0, 0.5})), WaitCause::Across);
  EXPECT_EQ(classifyWait(driving(east, {0.0, -0.5})), WaitCause::Across);
  // One bend off (a diagonal edge against a straight one) is the same way or head-on, on both
  // sides of the line: 45° lies exactly on cos = 1/√2, so a 45° rule would split them by rounding.
  EXPECT_EQ(classifyWait(driving(east, {0.5, 0.5})), WaitCause::SameWay);
  EXPECT_EQ(classifyWait(driving(east, {0.5, -0.5})), WaitCause::SameWay);
  EXPECT_EQ(classifyWait(driving(east, {-0.5, 0.5})), WaitCause::HeadOn);
  EXPECT_EQ(classifyWait(driving({0.5, 0.5}, {-0.5, 0.0})), WaitCause::HeadOn);
  // Lengths do not matter, only directions.
  EXPECT_EQ(classifyWait(driving({3.0, 0.0}, {0.01, 0.0})), WaitCause::SameWay);
}

TEST(WaitCause, WithoutANextNodeTheWayTowardsTheOtherIsTaken) {
  WaitSeen s = driving({0.0, 0.0}, {0.5, 0.0});
  s.otherAt = {1.0, 0.0};  // ahead, driving away: following it
  EXPECT_EQ(classifyWait(s), WaitCause::SameWay);
  s.otherWay = {-0.5, 0.0};  // coming this way
  EXPECT_EQ(classifyWait(s), WaitCause::HeadOn);
  s.otherAt = {0.0, 1.0};  // beside, driving past
  EXPECT_EQ(classifyWait(s), WaitCause::Across);
}

TEST(WaitCause, WhatTheOtherDoesComesFirst) {
  WaitSeen s = driving({0.5, 0.0}, {0.5, 0.0});
  s.otherDwelling = true;
  EXPECT_EQ(classifyWait(s), WaitCause::Dwelling);
  s.otherDwelling = false;
  s.otherDriving = false;
  EXPECT_EQ(classifyWait(s), WaitCause::Standing);
  s.otherDriving = true;
  s.otherWay = {0.0, 0.0};  // on an edge of no length: not going anywhere
  EXPECT_EQ(classifyWait(s), WaitCause::Standing);
  s.named = false;  // nobody named: whatever else was filled in
  EXPECT_EQ(classifyWait(s), WaitCause::NoneNamed);
}

/// What a fleet loop sees of a wait, from the tick's snapshot: the waiting robot's next node (after
/// its node in the base, else the horizon's first), the robot it waits on and what that one does.
TEST(WaitCause, SeenFromTheTicksSnapshotAndTheRelease) {
  Graph g;
  const NodeId a = g.addNode({0.0, 0.0});
  const NodeId b = g.addNode({0.5, 0.0});
  const NodeId c = g.addNode({1.0, 0.0});
  const NodeId d = g.addNode({1.0, 0.5});
  std::vector<WaitSnapshot> robots(2);
  robots[0] = {a, kNoNode, false, 1};  // stands on a, waits on robot 1
  robots[1] = {c, d, false, 2};        // drives c -> d, across robot 0's way
  Release rel;
  rel.base = {a, b};
  WaitSeen s = waitSeen(g, robots, 0, rel);
  EXPECT_TRUE(s.named);
  EXPECT_DOUBLE_EQ(s.way.x, 0.5);
  EXPECT_DOUBLE_EQ(s.way.y, 0.0);
  EXPECT_TRUE(s.otherDriving);
  EXPECT_EQ(classifyWait(s), WaitCause::Across);
  // Its base ends on its node: the horizon's first node is its way.
  rel.base = {a};
  rel.horizon = {d};
  s = waitSeen(g, robots, 0, rel);
  EXPECT_DOUBLE_EQ(s.way.x, 1.0);
  EXPECT_DOUBLE_EQ(s.way.y, 0.5);
  // The other standing at the start of the tick (whatever it did later in the tick): standing.
  robots[1].to = kNoNode;
  EXPECT_EQ(classifyWait(waitSeen(g, robots, 0, rel)), WaitCause::Standing);
  robots[1].dwelling = true;
  EXPECT_EQ(classifyWait(waitSeen(g, robots, 0, rel)), WaitCause::Dwelling);
  // Nobody named (an index past the robots).
  robots[0].on = robots.size();
  EXPECT_EQ(classifyWait(waitSeen(g, robots, 0, rel)), WaitCause::NoneNamed);
}

TEST(WaitCause, EveryCauseHasItsOwnName) {
  std::string seen;
  for (const auto c : kWaitCauses) {
    const std::string name = toString(c);
    EXPECT_FALSE(name.empty());
    EXPECT_EQ(seen.find("|" + name + "|"), std::string::npos) << name;
    seen += "|" + name + "|";
  }
}

}  // namespace
}  // namespace fleet::traffic
