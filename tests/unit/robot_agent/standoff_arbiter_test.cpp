// The standoff arbiter alone: holds of given lengths, blockers and neighbours in, its moves out
// (wait, plan around a standing robot, yield, detour, fail) and the standoffs it counts.

#include "standoff_arbiter.hpp"

#include <gtest/gtest.h>

#include <cstdint>

using namespace fleet;
using agent::OtherRobot;
using agent::Standoff;
using agent::StandoffArbiter;
using agent::StandoffMove;

namespace {

constexpr std::int64_t kSecond = 1'000'000'000;

StandoffArbiter arbiter(const std::string& self = "r5") {
  return StandoffArbiter({self, 0.3, 4.0, 60.0});
}

// Held since t = 0, at `t` seconds, by `blocker` (a robot unless "human" or empty).
Standoff heldBy(const std::string& blocker, double t, bool blockPointKnown = true) {
  Standoff s;
  s.nowNs = static_cast<std::int64_t>(t * 1e9);
  s.sinceNs = 0;
  s.byRobot = !blocker.empty() && blocker != "human";
  s.blocker = blocker;
  s.blockPointKnown = blockPointKnown;
  s.position = {0.0, 0.0};
  return s;
}

// A robot 1 m ahead (+x) facing this one, driving on an order.
OtherRobot facing(const std::string& id, OtherRobot::Mode mode = OtherRobot::Mode::kMoving) {
  OtherRobot o;
  o.id = id;
  o.pos = {1.0, 0.0};
  o.theta = 3.14159;
  o.mode = mode;
  o.hasTask = true;
  return o;
}

}  // namespace

TEST(StandoffArbiter, WaitsUntilTheBackoffTimeThenTheLargerIdYields) {
  auto a = arbiter("r5");
  const std::vector<OtherRobot> others{facing("r3")};
  EXPECT_EQ(a.decide(heldBy("r3", 0.5), others).move, StandoffMove::kWait);
  EXPECT_EQ(a.decide(heldBy("r3", 4.0), others).move, StandoffMove::kWait) << "4 s is not past 4 s";
  EXPECT_EQ(a.decide(heldBy("r3", 4.1), others).move, StandoffMove::kYield) << "r5 > r3";
  auto b = arbiter("r2");
  EXPECT_EQ(b.decide(heldBy("r3", 4.1), others).move, StandoffMove::kWait) << "r2 < r3: the other yields";
}

TEST(StandoffArbiter, ARobotDrivingHomeYieldsToOneOnAnOrder) {
  auto a = arbiter("r2");
  const std::vector<OtherRobot> others{facing("r3")};
  auto s = heldBy("r3", 4.1);
  s.homing = true;
  EXPECT_EQ(a.decide(s, others).move, StandoffMove::kYield) << "homing, though the smaller id";
  auto b = arbiter("r5");
  auto homeward = others;
  homeward[0].hasTask = false;
  EXPECT_EQ(b.decide(heldBy("r3", 4.1), homeward).move, StandoffMove::kWait) << "r3 drives home: it yields";
}

TEST(StandoffArbiter, AlwaysYieldsToAPersonAndToStaticObstaclesAfterTheBackoffTime) {
  auto a = arbiter("r1");
  EXPECT_EQ(a.decide(heldBy("human", 4.1), {}).move, StandoffMove::kYield);
  EXPECT_EQ(a.decide(heldBy("", 4.1), {}).move, StandoffMove::kYield);
}

TEST(StandoffArbiter, MakesRoomForAWaitingRobotItStandsRightBehind) {
  auto a = arbiter("r1");  // the smaller id: would not yield by the ids
  OtherRobot ahead = facing("r9", OtherRobot::Mode::kWaiting);
  ahead.theta = 0.0;  // facing away: this robot at (0, 0) is 1 m behind it
  ahead.pos = {0.8, 0.0};
  EXPECT_EQ(a.decide(heldBy("r9", 4.1), {ahead}).move, StandoffMove::kYield);
  ahead.pos = {1.5, 0.0};  // further off than a body length and the gap
  auto b = arbiter("r1");
  EXPECT_EQ(b.decide(heldBy("r9", 4.1), {ahead}).move, StandoffMove::kWait);
}

TEST(StandoffArbiter, CountsAStandoffOncePerHoldAndAWaitCycleWhenTheBlockerWaits) {
  auto a = arbiter("r1");
  const std::vector<OtherRobot> others{facing("r3", OtherRobot::Mode::kWaiting)};
  EXPECT_FALSE(a.decide(heldBy("r3", 1.0), others).newStandoff) << "not more than 1 s yet";
  const auto first = a.decide(heldBy("r3", 1.1), others);
  EXPECT_TRUE(first.newStandoff);
  EXPECT_EQ(first.waitCycles, 1);
  EXPECT_FALSE(a.decide(heldBy("r3", 2.0), others).newStandoff);
  auto later = heldBy("r3", 10.5);  // a new hold since 10 s
  later.sinceNs = 10 * kSecond;
  EXPECT_FALSE(a.decide(later, others).newStandoff);
  later.nowNs = 11 * kSecond + 1;
  EXPECT_TRUE(a.decide(later, others).newStandoff) << "a new hold";
}

TEST(StandoffArbiter, PlansAroundAStandingRobotEveryThreeSeconds) {
  auto a = arbiter("r1");
  const std::vector<OtherRobot> others{facing("r3", OtherRobot::Mode::kLoading)};
  EXPECT_EQ(a.decide(heldBy("r3", 1.0), others).move, StandoffMove::kWait);
  EXPECT_EQ(a.decide(heldBy("r3", 1.1), others).move, StandoffMove::kPlanAroundStanding);
  EXPECT_EQ(a.decide(heldBy("r3", 4.0), others).move, StandoffMove::kWait) << "2.9 s after the last";
  EXPECT_EQ(a.decide(heldBy("r3", 4.2), others).move, StandoffMove::kPlanAroundStanding);
}

TEST(StandoffArbiter, DetoursAroundTheBlockingPointEveryEightSecondsThenFails) {
  auto a = arbiter("r1");  // does not yield to r3
  const std::vector<OtherRobot> others{facing("r3")};
  EXPECT_EQ(a.decide(heldBy("r3", 8.0), others).move, StandoffMove::kWait);
  EXPECT_EQ(a.decide(heldBy("r3", 8.1), others).move, StandoffMove::kDetour);
  EXPECT_EQ(a.decide(heldBy("r3", 16.0), others).move, StandoffMove::kWait);
  EXPECT_EQ(a.decide(heldBy("r3", 16.2), others).move, StandoffMove::kDetour);
  EXPECT_EQ(a.decide(heldBy("r3", 60.5), others).move, StandoffMove::kDetour);
  EXPECT_EQ(a.decide(heldBy("r3", 61.0), others).move, StandoffMove::kFail);
  auto b = arbiter("r1");
  EXPECT_EQ(b.decide(heldBy("r3", 30.0, false), others).move, StandoffMove::kWait)
      << "no blocking point: nothing to plan around";
  EXPECT_EQ(b.decide(heldBy("r3", 60.1, false), others).move, StandoffMove::kFail);
}

TEST(StandoffArbiter, WhenItCannotYieldItDetoursOrFails) {
  auto a = arbiter("r5");
  const std::vector<OtherRobot> others{facing("r3")};
  const auto s = heldBy("r3", 9.0);
  EXPECT_EQ(a.decide(s, others).move, StandoffMove::kYield);
  EXPECT_EQ(a.cannotYield(s), StandoffMove::kDetour);
  EXPECT_EQ(a.cannotYield(heldBy("r3", 10.0)), StandoffMove::kWait) << "the last detour was 1 s ago";
  EXPECT_EQ(a.cannotYield(heldBy("r3", 5.0)), StandoffMove::kWait) << "too early for a detour";
  EXPECT_EQ(a.cannotYield(heldBy("r3", 61.0, false)), StandoffMove::kFail);
}
