// Why a robot waits on another (wait_cause.hpp): by what that robot does and how its way lies
// against the waiting robot's next one, on a lattice whose edges meet at multiples of 45°.

#include "fleet/traffic/wait_cause.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <string>

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
