// The bridge's order handling against the simulated VDA 5050 vehicle, which takes or rejects
// orders by the specification's rules: where new orders start, and what happens when the vehicle
// says no.

#include "bridge_node.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <optional>

#include "bridge_loop.hpp"
#include "fleet/vda5050/instant_actions.hpp"
#include "vehicle_rig.hpp"

namespace fleet::vdabridge {
namespace {

using bridge_test::kTopic;
using bridge_test::lineRoadmap;
using bridge_test::Loop;
using bridge_test::release;
using bridge_test::settings;

/// A charge task: drive to x = 1 (a charger) and charge there, at most `max_s`.
void chargeAtN1(Loop& l, const std::string& task, double max_s) {
  msg::TaskAssignment a;
  a.robot_id = "r1";
  a.task_id = task;
  a.goals = {{{1.0, 0.0, 0.0}, "C-1", msg::GoalAction::Charge, max_s}};
  BridgeOutbox out;
  l.bridge.onAssignment(a, l.now, out);
  auto r = release({0, 1});
  r.ends_at_goal = true;
  l.bridge.onRelease(r);
}

std::size_t count(const std::vector<std::string>& v, const std::string& what) {
  return static_cast<std::size_t>(std::count(v.begin(), v.end(), what));
}

// At the charge goal the vehicle is sent startCharging and reports Charging, holding its node, for
// as long as the task lasts (the fleet manager ends it when the battery is charged). The next task
// begins with stopCharging, and its order goes out only once the vehicle stopped: it takes no
// order while charging, so none is rejected.
TEST(Vda5050BridgeNode, ChargesAtTheChargeGoalAndStopsChargingBeforeTheNextOrder) {
  Loop l;
  l.rig.vehicle.senseBattery(0.3, true);  // its contacts touch a charger's (x = 1)
  chargeAtN1(l, "charge.r1", 1800.0);
  l.run(0.1);
  ASSERT_TRUE(l.runUntilAt("n1", 20.0));
  l.run(5.0);
  EXPECT_EQ(count(l.instants, "startCharging"), 1U);
  EXPECT_TRUE(l.state().batteryState.charging);
  ASSERT_TRUE(l.robot);
  EXPECT_EQ(l.robot->mode, msg::RobotMode::Charging);
  EXPECT_TRUE(l.progress.holding);
  ASSERT_FALSE(l.statuses.empty());
  EXPECT_EQ(l.statuses.back().task_id, "charge.r1");
  EXPECT_EQ(l.statuses.back().state, msg::TaskState::EnRoute) << "not done before the manager says so";
  EXPECT_EQ(l.bridge.counters().charges, 1U);

  const auto ordersBefore = l.orders.size();
  l.assign("t2", 3.0);  // the manager ended the charge task (charged) and gives it the next
  l.bridge.onRelease(release({1, 2, 3}));
  l.run(0.1);
  EXPECT_EQ(count(l.instants, "stopCharging"), 1U);
  EXPECT_FALSE(l.state().batteryState.charging);
  ASSERT_TRUE(l.runUntilAt("n3", 20.0));
  EXPECT_GT(l.orders.size(), ordersBefore);
  EXPECT_EQ(l.bridge.counters().rejected, 0U) << "an order reached the vehicle while it charged";
  EXPECT_EQ(count(l.instants, "stopCharging"), 1U);
  EXPECT_NE(l.robot->mode, msg::RobotMode::Charging);
}

// A charger that does not charge the battery holds the vehicle no longer than the goal's duration
// (charge_max_s): then the bridge stops the charging and reports the goal done, as an agent does.
TEST(Vda5050BridgeNode, AChargeGoalEndsAfterItsDuration) {
  Loop l;
  l.rig.vehicle.senseBattery(0.3, true);
  chargeAtN1(l, "charge.r1", 5.0);
  l.run(0.1);
  ASSERT_TRUE(l.runUntilAt("n1", 20.0));
  l.run(3.0);
  EXPECT_TRUE(l.state().batteryState.charging);
  EXPECT_NE(l.statuses.back().state, msg::TaskState::Done);
  l.run(4.0);
  EXPECT_EQ(count(l.instants, "stopCharging"), 1U);
  EXPECT_FALSE(l.state().batteryState.charging);
  EXPECT_EQ(l.statuses.back().state, msg::TaskState::Done);
}

// A vehicle that cannot start charging there (here: no charger under it) is asked again (a fresh
// action id each time: its state still lists the last FAILED), three times in all; then the task
// fails with its reason, logged.
TEST(Vda5050BridgeNode, AFailedStartChargingFailsTheTaskWithTheVehiclesReason) {
  Loop l;
  l.rig.vehicle.senseBattery(0.3, false);
  chargeAtN1(l, "charge.r1", 1800.0);
  l.run(0.1);
  ASSERT_TRUE(l.runUntilAt("n1", 20.0));
  l.run(2.0);
  ASSERT_FALSE(l.statuses.empty());
  EXPECT_EQ(l.statuses.back().state, msg::TaskState::Failed);
  EXPECT_NE(l.statuses.back().error.find("not on a charging spot"), std::string::npos)
      << l.statuses.back().error;
  EXPECT_TRUE(l.warned("startCharging failed"));
  EXPECT_EQ(count(l.instants, "startCharging"), 3U);
  EXPECT_EQ(l.bridge.counters().charge_failures, 3U);
  l.run(5.0);
  EXPECT_EQ(count(l.instants, "startCharging"), 3U) << "not tried again and again";
}

// A startCharging lost on the way (or one the vehicle never acts on) is sent again after 5 s; after
// three the task fails, and the goal never holds the vehicle past its duration from its arrival.
TEST(Vda5050BridgeNode, AStartChargingWithoutAnAnswerIsSentAgainThenTheTaskFails) {
  Loop l;
  l.rig.vehicle.senseBattery(0.3, true);
  chargeAtN1(l, "charge.r1", 1800.0);
  l.deliverInstants = false;
  l.run(0.1);
  ASSERT_TRUE(l.runUntilAt("n1", 20.0));
  l.run(1.0);
  EXPECT_EQ(count(l.instants, "startCharging"), 1U);
  l.run(5.0);
  EXPECT_EQ(count(l.instants, "startCharging"), 2U);
  l.run(10.0);
  EXPECT_EQ(count(l.instants, "startCharging"), 3U);
  EXPECT_EQ(l.statuses.back().state, msg::TaskState::Failed);
  EXPECT_TRUE(l.warned("the vehicle never charged"));
  EXPECT_FALSE(l.progress.has_goal && l.progress.goal.x == 1.0) << "a failed task no longer steers it";
}

TEST(Vda5050BridgeNode, AVehicleJoinsTheFleetOnlyWithItsFactsheet) {
  Loop l(settings(), false);
  l.assign("t1", 2.0);
  l.bridge.onRelease(release({0, 1, 2}));
  l.run(1.0);
  EXPECT_TRUE(l.orders.empty());
  EXPECT_FALSE(l.robot.has_value());
  EXPECT_FALSE(l.progress.follows);
  EXPECT_TRUE(l.warned("r1: not in the fleet: no factsheet yet"));
  EXPECT_EQ(count(l.instants, "factsheetRequest"), 1U);
  l.sendFactsheet();
  l.run(1.0);
  EXPECT_TRUE(l.warned("r1: joins the fleet: its footprint (radius 0.300 m, envelope 'default')"));
  EXPECT_EQ(l.orders.size(), 1U);
  ASSERT_TRUE(l.robot.has_value());
  EXPECT_FLOAT_EQ(l.robot->radius, 0.3F);
  EXPECT_TRUE(l.progress.follows);
}

// A vehicle larger than the robot the roadmap's conflicts were computed for is refused with the
// two sizes named; an order it was driving is cancelled. A roadmap for its size lets it in.
TEST(Vda5050BridgeNode, AVehicleLargerThanTheRoadmapsRobotIsRefusedSayingWhy) {
  Loop l;
  l.assign("t1", 5.0);
  l.bridge.onRelease(release({0, 1, 2, 3, 4, 5}));
  l.run(1.0);
  ASSERT_EQ(l.orders.size(), 1U);
  EXPECT_TRUE(l.state().driving);
  auto small = lineRoadmap();
  small.robot_radius = 0.25;
  l.bridge.onRoadmap(small);
  l.run(3.0);
  EXPECT_TRUE(l.warned(
      "r1: not in the fleet: its footprint (a disc of radius 0.300 m about its reference point, from "
      "its factsheet's envelope 'default') is larger than the robot the roadmap's conflicts "
      "are computed for (radius 0.250 m)"));
  EXPECT_EQ(count(l.instants, "cancelOrder"), 1U);
  EXPECT_FALSE(l.state().driving);
  EXPECT_FALSE(l.progress.follows);
  EXPECT_EQ(l.bridge.counters().refused_vehicles, 1U);
  const auto orders = l.orders.size();
  const auto states = l.robot->stamp_ns;
  l.run(2.0);
  EXPECT_EQ(l.orders.size(), orders) << "no order for a refused vehicle";
  EXPECT_EQ(l.robot->stamp_ns, states) << "no RobotState for a refused vehicle";
  auto fits = lineRoadmap();
  fits.robot_radius = 0.3;
  l.bridge.onRoadmap(fits);
  l.run(2.0);
  EXPECT_TRUE(l.warned("joins the fleet"));
  EXPECT_TRUE(l.progress.follows);
  EXPECT_GT(l.orders.size(), orders);
  EXPECT_TRUE(l.runUntilAt("n5", 20.0));
}

// A stop at the end of the order's base counts as late when the release went further (the update
// had not reached the vehicle), not when the traffic manager's release ended there too.
TEST(Vda5050BridgeNode, AStopAtABaseEndTheReleaseWentBeyondIsCountedLate) {
  Loop l;
  l.assign("t1", 5.0);
  l.bridge.onRelease(release({0, 1}, {2}));
  ASSERT_TRUE(l.runUntilAt("n1", 20.0));
  l.run(2.0);
  EXPECT_TRUE(l.state().newBaseRequest.value_or(false));
  EXPECT_EQ(l.bridge.counters().late_updates, 0U) << "the release ended at n1 too";
  l.bridge.onRelease(release({1, 2}, {3}));
  l.run(0.1);
  l.deliver = false;  // the next update is lost on the way
  l.bridge.onRelease(release({1, 2, 3, 4}, {5}));
  ASSERT_TRUE(l.runUntilAt("n2", 20.0));
  l.run(1.0);
  ASSERT_EQ(l.rig.vehicle.lastNodeId(), "n2");
  EXPECT_EQ(l.bridge.counters().late_updates, 1U);
}

TEST(Vda5050BridgeNode, ANewOrderAfterACancelStartsAtTheVehiclesLastNode) {
  Loop l;
  l.assign("t1", 5.0);
  l.bridge.onRelease(release({0, 1}, {2}));
  l.run(0.1);
  ASSERT_EQ(l.orders.size(), 1U);
  EXPECT_EQ(l.orders[0].nodes.front().nodeId, "n0");
  ASSERT_TRUE(l.runUntilAt("n1", 20.0));
  l.run(1.0);  // standing at its base end n1
  // The traffic manager has it at n2 (a report it took while the vehicle's own last node is n1):
  // the release does not pass n1, so the order is cancelled and a new one starts.
  l.bridge.onRelease(release({2, 3, 4}));
  l.run(1.0);
  ASSERT_NE(std::find(l.instants.begin(), l.instants.end(), "cancelOrder"), l.instants.end());
  ASSERT_EQ(l.orders.size(), 2U);
  const auto& o = l.orders[1];
  EXPECT_EQ(o.orderId, "t1-2");
  ASSERT_EQ(o.nodes.size(), 4U);
  EXPECT_EQ(o.nodes[0].nodeId, "n1") << "where the vehicle's state says it is, not the release's n2";
  EXPECT_EQ(o.nodes[1].nodeId, "n2");
  auto s = l.state();
  EXPECT_EQ(s.orderId, "t1-2") << "the vehicle took it";
  EXPECT_TRUE(s.errors.empty());
  EXPECT_TRUE(l.runUntilAt("n4", 30.0));
  EXPECT_EQ(l.bridge.counters().rejected, 0U);
}

TEST(Vda5050BridgeNode, ARejectedOrderIsLoggedAndSentAgainFromTheVehiclesLatestState) {
  Loop l;
  l.standAtN1("t1", 3.0);
  // In SEMIAUTOMATIC mode the vehicle stays online to the fleet but takes no order (orderError).
  l.rig.vehicle.setOperatingMode("SEMIAUTOMATIC");
  // The traffic manager has it at n2: the order is done, so a new one starts (from n1).
  l.bridge.onRelease(release({2, 3}));
  l.run(0.3);
  ASSERT_EQ(l.orders.size(), 2U);
  EXPECT_EQ(l.orders[1].orderId, "t1-2");
  EXPECT_TRUE(l.warned("order t1-2 update 0 rejected (orderError: the vehicle is in SEMIAUTOMATIC mode)"));
  EXPECT_EQ(l.bridge.counters().rejected, 1U);
  l.rig.vehicle.setOperatingMode("AUTOMATIC");
  l.run(0.5);
  EXPECT_EQ(l.orders.size(), 2U) << "no re-send before the back-off";
  l.run(1.0);
  ASSERT_EQ(l.orders.size(), 3U);
  EXPECT_EQ(l.orders[2].orderId, "t1-3") << "a new orderId: the rejected one never became the vehicle's";
  EXPECT_EQ(l.orders[2].nodes.front().nodeId, "n1");
  EXPECT_EQ(l.state().orderId, "t1-3");
  EXPECT_TRUE(l.runUntilAt("n3", 20.0));
  EXPECT_FALSE(l.progress.blocked);
}

TEST(Vda5050BridgeNode, ARejectedUpdateIsSentAgainFromTheBaseEndTheVehicleHas) {
  Loop l;
  l.assign("t1", 4.0);
  l.bridge.onRelease(release({0, 1}, {2}));
  l.run(0.1);
  ASSERT_TRUE(l.runUntilAt("n1", 20.0));
  l.rig.vehicle.setOperatingMode("SEMIAUTOMATIC");
  l.bridge.onRelease(release({1, 2, 3}, {4}));
  l.run(0.3);
  ASSERT_EQ(l.orders.size(), 2U);
  EXPECT_EQ(l.orders[1].orderUpdateId, 1U);
  EXPECT_TRUE(l.warned("order t1-1 update 1 rejected (orderError"));
  l.rig.vehicle.setOperatingMode("AUTOMATIC");
  l.run(1.5);
  ASSERT_EQ(l.orders.size(), 3U);
  const auto& u = l.orders[2];
  EXPECT_EQ(u.orderId, "t1-1");
  EXPECT_EQ(u.orderUpdateId, 2U);
  EXPECT_EQ(u.nodes.front().nodeId, "n1") << "the base end of update 0, which the vehicle has";
  EXPECT_EQ(u.nodes.front().sequenceId, 2U);
  const auto s = l.state();
  EXPECT_EQ(s.orderUpdateId, 2U);
  EXPECT_TRUE(s.errors.empty());
  EXPECT_TRUE(l.runUntilAt("n3", 20.0));
}

TEST(Vda5050BridgeNode, BoundedRetriesEndInALoggedRefusalAndABlockedReport) {
  Loop l;
  l.rig.vehicle.setOperatingMode("SEMIAUTOMATIC");
  l.assign("t1", 3.0);
  l.bridge.onRelease(release({0, 1, 2}));
  l.run(30.0);
  EXPECT_EQ(l.orders.size(), 4U) << "the first order and 3 retries";
  EXPECT_EQ(l.bridge.counters().rejected, 4U);
  EXPECT_EQ(l.bridge.counters().gave_up, 1U);
  EXPECT_TRUE(l.warned("r1: no order taken after 4 attempts (last: orderError"));
  EXPECT_TRUE(l.progress.blocked) << "the traffic manager hears it cannot follow";
  l.run(30.0);
  EXPECT_EQ(l.orders.size(), 4U) << "silent from then on, not sending for ever";
  // A changed release is a new chance.
  l.rig.vehicle.setOperatingMode("AUTOMATIC");
  l.bridge.onRelease(release({0, 1, 2, 3}));
  l.run(0.3);
  ASSERT_EQ(l.orders.size(), 5U);
  EXPECT_EQ(l.state().orderId, l.orders.back().orderId);
  EXPECT_FALSE(l.progress.blocked);
}

TEST(Vda5050BridgeNode, AVehicleHeldByAPersonWithBaseAheadHasItsOrderCancelledBeforeItIsReportedBlocked) {
  // Blocked, the traffic manager cuts the release back to the next node and plans others over the
  // rest; a vehicle would keep its order's base and drive on into them once the person has gone.
  Loop l;
  l.assign("t1", 9.0);
  l.bridge.onRelease(release({0, 1, 2, 3, 4}));
  l.run(0.1);
  ASSERT_TRUE(l.runUntilAt("n1", 20.0));
  l.rig.person = true;
  l.run(1.0);
  EXPECT_TRUE(l.state().safetyState.fieldViolation);
  EXPECT_FALSE(l.progress.blocked) << "it holds n2..n4 and will drive them: only late";
  EXPECT_EQ(std::count(l.instants.begin(), l.instants.end(), "cancelOrder"), 0);
  l.run(3.0);
  EXPECT_EQ(std::count(l.instants.begin(), l.instants.end(), "cancelOrder"), 1);
  EXPECT_EQ(l.bridge.counters().field_cancels, 1U);
  EXPECT_TRUE(l.state().nodeStates.empty()) << "the vehicle ended its order";
  EXPECT_TRUE(l.progress.blocked) << "holding nothing beyond where it is, it can be planned round";
  const auto ordersBefore = l.orders.size();
  l.rig.person = false;
  l.run(3.0);
  EXPECT_FALSE(l.progress.blocked);
  // Until the traffic manager's next release the old one may have been taken back but for its
  // first two nodes (n0, n1): nothing beyond n1 is ordered, so the vehicle stays there.
  for (std::size_t k = ordersBefore; k < l.orders.size(); ++k) {
    for (const auto& n : l.orders[k].nodes) {
      EXPECT_TRUE(n.nodeId == "n0" || n.nodeId == "n1") << n.nodeId << " ordered from a stale release";
    }
  }
  EXPECT_EQ(l.rig.vehicle.lastNodeId(), "n1");
  // The traffic manager releases it again from its node: a new order from where it stands.
  auto again = release({1, 2, 3, 4});
  again.seq = 2;
  l.bridge.onRelease(again);
  EXPECT_TRUE(l.runUntilAt("n4", 30.0));
  EXPECT_EQ(l.orders.back().nodes.front().nodeId, "n1");
}

TEST(Vda5050BridgeNode, AVehicleHeldByAPersonBeforeItsLastBaseNodeIsReportedBlockedAtOnce) {
  Loop l;
  l.assign("t1", 9.0);
  l.bridge.onRelease(release({0, 1, 2}));
  l.run(0.1);
  ASSERT_TRUE(l.runUntilAt("n1", 20.0));
  l.rig.person = true;
  l.run(1.0);
  EXPECT_TRUE(l.progress.blocked) << "only n2 is left: cutting back to it takes nothing it holds";
  l.run(4.0);
  EXPECT_EQ(std::count(l.instants.begin(), l.instants.end(), "cancelOrder"), 0);
  l.rig.person = false;
  EXPECT_TRUE(l.runUntilAt("n2", 10.0));
  EXPECT_FALSE(l.progress.blocked);
}

TEST(Vda5050BridgeNode, AnOrderLostOnTheWayIsSentAgain) {
  Loop l;
  l.deliver = false;
  l.assign("t1", 2.0);
  l.bridge.onRelease(release({0, 1, 2}));
  l.run(5.0);
  EXPECT_EQ(l.orders.size(), 1U);
  l.deliver = true;
  l.run(7.0);  // 10 s without an answer, then the back-off
  ASSERT_EQ(l.orders.size(), 2U);
  EXPECT_TRUE(l.warned("order t1-1 update 0 rejected (neither taken nor rejected in 10 s)"));
  EXPECT_EQ(l.state().orderId, "t1-2");
}

TEST(Vda5050BridgeNode, ANewOrderTheVehicleCouldNotTakeIsNotSent) {
  // The vehicle's last node n1 is not next to n5, where the release starts.
  Loop l;
  l.standAtN1("t1", 1.0);
  l.bridge.onRelease(release({5, 6}));
  l.run(30.0);
  EXPECT_EQ(l.orders.size(), 1U);
  EXPECT_TRUE(l.warned("r1: no new order: the release starts at n5, the vehicle's last node is n1"));
  EXPECT_TRUE(l.progress.blocked);
}

TEST(Vda5050BridgeNode, ErrorsWithMissingFieldsDoNotUpsetTheBridge) {
  Loop l;
  l.assign("t1", 2.0);
  l.deliver = false;
  l.bridge.onRelease(release({0, 1, 2}));
  l.run(0.1);
  ASSERT_EQ(l.orders.size(), 1U);
  auto j = vda5050::toJson(l.state());
  BridgeOutbox out;
  // Without references or description: it names no order, so it is not taken as a rejection.
  j["errors"] = nlohmann::json::array({{{"errorType", "noRouteError"}, {"errorLevel", "WARNING"}}});
  l.bridge.onMqtt(kTopic + "state", j.dump(), out);
  l.bridge.tick(l.now, out);
  EXPECT_EQ(l.bridge.counters().rejected, 0U);
  // Required fields missing: the message is refused with a reason.
  nlohmann::json no_value = {{"errorType", "orderError"}, {"errorLevel", "WARNING"}};
  no_value["errorReferences"] = nlohmann::json::array({nlohmann::json{{"referenceKey", "orderId"}}});
  for (const auto& bad :
       {nlohmann::json{{"errorType", "orderError"}}, no_value, nlohmann::json{{"errorLevel", "WARNING"}}}) {
    j["errors"] = nlohmann::json::array({bad});
    const auto before = l.bridge.counters().refused_messages;
    l.bridge.onMqtt(kTopic + "state", j.dump(), out);
    l.bridge.tick(l.now, out);
    EXPECT_EQ(l.bridge.counters().refused_messages, before + 1) << bad.dump();
  }
  EXPECT_EQ(l.bridge.counters().rejected, 0U);
  l.deliver = true;
  l.run(15.0);  // back to the vehicle's own states; the lost order is sent again
  EXPECT_EQ(l.state().orderId, l.orders.back().orderId);
}

TEST(Vda5050BridgeNode, AnOrderFromAManagerOfAnOlderEpochIsIgnoredOnceANewerOneHasSpoken) {
  // The vehicle drives task t1 of the manager of epoch 2; the manager it succeeded (epoch 1), still
  // running, takes the task away: the bridge ignores it (counted) and the vehicle goes on.
  Loop l;
  msg::TaskAssignment a;
  a.robot_id = "r1";
  a.task_id = "t1";
  a.epoch = 2;
  a.goals = {{{5.0, 0.0, 0.0}, "", msg::GoalAction::None, 0.0}};
  BridgeOutbox out;
  l.bridge.onAssignment(a, l.now, out);
  l.bridge.onRelease(release({0, 1}));
  l.run(0.1);
  ASSERT_TRUE(l.runUntilAt("n1", 20.0));
  msg::TaskAssignment stale;
  stale.robot_id = "r1";
  stale.epoch = 1;
  stale.revision = 99;
  l.bridge.onAssignment(stale, l.now, out);
  l.run(1.0);
  EXPECT_EQ(count(l.instants, "cancelOrder"), 0U);
  EXPECT_EQ(l.bridge.counters().stale_epoch, 1U);
  EXPECT_EQ(l.bridge.counters().cancels, 0U);
}

}  // namespace
}  // namespace fleet::vdabridge
