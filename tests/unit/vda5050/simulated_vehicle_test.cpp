#include "fleet/sim/vda5050_vehicle.hpp"

#include <gtest/gtest.h>

#include <utility>

#include "order_fixtures.hpp"
#include "vehicle_rig.hpp"

namespace fleet::sim {
namespace {

using vda5050::OrderDecision;
using vda5050::test::lineOrder;

using test::Rig;

TEST(Vda5050Vehicle, FollowsTheBaseAndStopsAtItsEnd) {
  Rig r;
  ASSERT_EQ(r.vehicle.onOrder(lineOrder("o1", 0, 0, 6, 3)).decision, OrderDecision::kAcceptNew);
  r.run(20.0);
  EXPECT_NEAR(r.pose.x, 2.0, 0.2);  // n2 is the last base node; n3.. are horizon
  auto s = r.state();
  EXPECT_EQ(s.lastNodeId, "n2");
  EXPECT_FALSE(s.driving);
  EXPECT_TRUE(s.newBaseRequest.value_or(false));
  ASSERT_EQ(s.nodeStates.size(), 3U);
  EXPECT_FALSE(s.nodeStates[0].released);
  EXPECT_EQ(r.vehicle.baseStarvedStops(), 1U);

  ASSERT_EQ(r.vehicle.onOrder(lineOrder("o1", 1, 2, 4, 4)).decision, OrderDecision::kAcceptUpdate);
  r.run(20.0);
  EXPECT_NEAR(r.pose.x, 5.0, 0.2);
  s = r.state();
  EXPECT_EQ(s.lastNodeId, "n5");
  EXPECT_EQ(s.orderUpdateId, 1U);
  EXPECT_TRUE(s.nodeStates.empty());
  EXPECT_TRUE(s.edgeStates.empty());
}

// Order-to-motion is timed from the order that got a standing vehicle going, at the step it
// starts; an update that reaches it while it drives, or one that releases nothing new, is not.
TEST(Vda5050Vehicle, SaysOnceWhichOrderGotItMoving) {
  Rig r;
  auto first = lineOrder("o1", 0, 0, 6, 3);
  first.header.timestamp = "2026-11-27T02:00:00.000Z";
  ASSERT_EQ(r.vehicle.onOrder(first).decision, OrderDecision::kAcceptNew);
  EXPECT_FALSE(r.vehicle.takeMotionStart().has_value());  // not moved yet
  r.run(0.1);
  EXPECT_EQ(r.vehicle.takeMotionStart(), "2026-11-27T02:00:00.000Z");
  EXPECT_FALSE(r.vehicle.takeMotionStart().has_value());  // once
  auto moving = lineOrder("o1", 1, 2, 4, 4);
  moving.header.timestamp = "2026-11-27T02:00:01.000Z";
  ASSERT_EQ(r.vehicle.onOrder(moving).decision, OrderDecision::kAcceptUpdate);  // still driving
  r.run(20.0);
  EXPECT_FALSE(r.vehicle.takeMotionStart().has_value());
  EXPECT_NEAR(r.pose.x, 5.0, 0.2);  // stands at its base end, n5
  auto again = lineOrder("o1", 2, 5, 2, 2);
  again.header.timestamp = "2026-11-27T02:00:30.000Z";
  ASSERT_EQ(r.vehicle.onOrder(again).decision, OrderDecision::kAcceptUpdate);
  r.run(0.1);
  EXPECT_EQ(r.vehicle.takeMotionStart(), "2026-11-27T02:00:30.000Z");
}

/// An order through `points` (all released), node ids p0, p1, ...
vda5050::Order pathOrder(const std::vector<Vec2>& points) {
  vda5050::Order o = lineOrder("o1", 0, 0, static_cast<int>(points.size()), static_cast<int>(points.size()));
  for (std::size_t i = 0; i < points.size(); ++i) {
    o.nodes[i].nodeId = "p" + std::to_string(i);
    o.nodes[i].nodePosition->x = points[i].x;
    o.nodes[i].nodePosition->y = points[i].y;
    if (i > 0) {
      o.edges[i - 1].startNodeId = o.nodes[i - 1].nodeId;
      o.edges[i - 1].endNodeId = o.nodes[i].nodeId;
    }
  }
  return o;
}

// Into a parking place and straight back out (the roadmap's dock leg, driven there and back when
// the next goal is already planned), and round a right angle: a vehicle that reaches such a node
// at cruise speed slides on past it while it brakes (into the place's back wall, in a mixed-fleet
// run). With the speed following the command at 1 m/s², it stays within 5 cm of each turn node.
TEST(Vda5050Vehicle, SlowsForANodeWhereTheWayTurnsAndDoesNotOvershootIt) {
  for (const bool reverse : {true, false}) {
    Rig r;
    r.accel = 1.0;
    const std::vector<Vec2> path = reverse
                                       ? std::vector<Vec2>{{0, 0}, {1, 0}, {2, 0}, {3, 0}, {2, 0}, {1, 0}}
                                       : std::vector<Vec2>{{0, 0}, {1, 0}, {2, 0}, {3, 0}, {3, 1}, {3, 2}};
    ASSERT_EQ(r.vehicle.onOrder(pathOrder(path)).decision, OrderDecision::kAcceptNew);
    double furthest = 0.0;
    r.run(20.0, [&] { furthest = std::max(furthest, r.pose.x); });
    EXPECT_LT(furthest, 3.05) << (reverse ? "back out of the place" : "round the corner");
    EXPECT_EQ(r.state().lastNodeId, "p5");
  }
}

double distanceToPolyline(const std::vector<Vec2>& path, Vec2 p) {
  double best = 1e9;
  for (std::size_t i = 0; i + 1 < path.size(); ++i) {
    const Vec2 a = path[i];
    const Vec2 ab = path[i + 1] - a;
    const double u = std::clamp((p - a).dot(ab) / ab.dot(ab), 0.0, 1.0);
    best = std::min(best, (a + ab * u - p).norm());
  }
  return best;
}

// The roadmap's lattice joins straight and diagonal moves: a route bends by 45° at most nodes. A
// vehicle that stopped and turned on the spot at each drove its legs at ~0.2 m/s in mixed-fleet
// runs (our agents: 0.4). Such bends are driven through at a corner speed, turning from the node
// on (not before it, so the inside of the bend, where a shelf's corner would be, is not cut).
TEST(Vda5050Vehicle, DrivesThroughGentleBendsWithoutStoppingAndKeepsToTheWay) {
  Rig r;
  r.accel = 1.0;
  const std::vector<Vec2> path = {{0, 0},     {0.5, 0},   {1.0, 0.5}, {1.5, 0.5},
                                  {2.0, 1.0}, {2.5, 1.0}, {3.0, 1.5}, {3.5, 1.5}};
  ASSERT_EQ(r.vehicle.onOrder(pathOrder(path)).decision, OrderDecision::kAcceptNew);
  double slowest = 1e9, widest = 0.0, arrived = -1.0;
  Vec2 prev{0, 0};
  r.run(30.0, [&] {
    const Vec2 p{r.pose.x, r.pose.y};
    widest = std::max(widest, distanceToPolyline(path, p));
    if (p.x > 0.3 && (p - path.back()).norm() > 0.3) {
      slowest = std::min(slowest, (p - prev).norm() / 0.1);
    }
    if (arrived < 0.0 && r.state().lastNodeId == "p7") {
      arrived = r.t;
    }
    prev = p;
  });
  EXPECT_GT(slowest, 0.15) << "stopped at a bend";
  EXPECT_LT(widest, 0.08);
  ASSERT_GT(arrived, 0.0);
  EXPECT_LT(arrived, 12.0);  // 4.1 m; stopping at each bend took 22.5 s
}

TEST(Vda5050Vehicle, RejectsAnUpdateThatDoesNotExtendTheBaseAndSaysWhy) {
  Rig r;
  ASSERT_EQ(r.vehicle.onOrder(lineOrder("o1", 0, 0, 6, 3)).decision, OrderDecision::kAcceptNew);
  r.run(3.0);
  EXPECT_EQ(r.vehicle.onOrder(lineOrder("o1", 1, 3, 3, 3)).decision, OrderDecision::kReject);
  auto s = r.state();
  ASSERT_EQ(s.errors.size(), 1U);
  EXPECT_EQ(s.errors[0].errorType, "orderUpdateError");
  EXPECT_EQ(s.orderUpdateId, 0U);
  // A new orderId while this one runs is refused too; the old order goes on.
  EXPECT_EQ(r.vehicle.onOrder(lineOrder("o2", 0, 0, 2, 2)).decision, OrderDecision::kReject);
  r.run(20.0);
  EXPECT_EQ(r.state().lastNodeId, "n2");
}

TEST(Vda5050Vehicle, RefusesAnOrderOnAnotherMap) {
  Rig r;
  auto o = lineOrder("o1", 0, 0, 3, 3);
  for (auto& n : o.nodes) {
    n.nodePosition->mapId = "other";
  }
  const auto v = r.vehicle.onOrder(o);
  EXPECT_EQ(v.decision, OrderDecision::kReject);
  EXPECT_NE(v.description.find("other"), std::string::npos);
}

TEST(Vda5050Vehicle, APersonInTheProtectiveFieldStopsIt) {
  Rig r;
  ASSERT_EQ(r.vehicle.onOrder(lineOrder("o1", 0, 0, 6, 6)).decision, OrderDecision::kAcceptNew);
  r.run(2.0);
  const double x = r.pose.x;
  EXPECT_GT(x, 0.3);
  r.person = true;
  r.run(3.0);
  EXPECT_NEAR(r.pose.x, x, 0.15);  // at most the step in flight
  auto s = r.state();
  EXPECT_TRUE(s.safetyState.fieldViolation);
  EXPECT_FALSE(s.driving);
  r.person = false;
  r.run(10.0);
  EXPECT_GT(r.pose.x, x + 1.0);

  // The field is ahead, not behind, a little wider than the vehicle (standing: 0.3 + 1 m ahead of
  // the centre, 0.3 + 0.3 m to each side).
  const Pose2 p{0.0, 0.0, 0.0};
  EXPECT_TRUE(r.vehicle.inProtectiveField(p, 1.0, 0.0, 0.25));
  EXPECT_FALSE(r.vehicle.inProtectiveField(p, -1.5, 0.0, 0.25));
  EXPECT_FALSE(r.vehicle.inProtectiveField(p, 1.0, 1.5, 0.25));
  EXPECT_TRUE(r.vehicle.inProtectiveField(p, 1.0, 0.8, 0.25)) << "beside the vehicle's width";
  EXPECT_FALSE(r.vehicle.inProtectiveField(p, 1.8, 0.0, 0.25));
}

// A vehicle its field stops may still turn on the spot when it stands (its body is a disc): one
// that had to turn towards its next node with a neighbour diagonally ahead in its field stood
// there for good. It drives only once the field is clear.
TEST(Vda5050Vehicle, StoppedByItsFieldItStillTurnsOnTheSpot) {
  Rig r;
  auto o = pathOrder({{0.0, 0.0}, {0.0, 2.0}});  // its next node lies 90 degrees to the left
  ASSERT_EQ(r.vehicle.onOrder(o).decision, OrderDecision::kAcceptNew);
  r.person = true;  // something in its field along its present heading
  r.run(3.0);
  EXPECT_NEAR(r.pose.x, 0.0, 1e-9);
  EXPECT_NEAR(r.pose.y, 0.0, 1e-9);
  EXPECT_NEAR(r.pose.theta, M_PI / 2.0, 0.1) << "turned towards its next node";
  r.person = false;
  r.run(6.0);
  EXPECT_NEAR(r.pose.y, 2.0, 0.15);

  // Driving, a field violation stops it, turning included.
  Rig d;
  ASSERT_EQ(d.vehicle.onOrder(pathOrder({{0.0, 0.0}, {3.0, 0.0}, {3.5, 0.5}})).decision,
            OrderDecision::kAcceptNew);
  d.accel = 1.0;
  d.run(2.5);
  ASSERT_GT(d.v, 0.3);
  d.person = true;
  const auto c = d.vehicle.step(d.t, d.pose, true);
  EXPECT_EQ(c.v, 0.0);
  EXPECT_EQ(c.w, 0.0);
}

TEST(Vda5050Vehicle, ItsProtectiveFieldGrowsWithItsSpeed) {
  Rig r;
  ASSERT_EQ(r.vehicle.onOrder(lineOrder("o1", 0, 0, 6, 6)).decision, OrderDecision::kAcceptNew);
  const Pose2 p{0.0, 0.0, 0.0};
  EXPECT_FALSE(r.vehicle.inProtectiveField(p, 1.8, 0.0, 0.25)) << "standing";
  r.run(2.0);  // up to speed along the line
  EXPECT_TRUE(r.vehicle.inProtectiveField(p, 1.8, 0.0, 0.25)) << "driving: its braking distance too";
  // And wider by it: a person 0.9 m off its side, 0.8 m ahead (standing, 0.6 m beside the body).
  EXPECT_TRUE(r.vehicle.inProtectiveField(p, 0.8, -1.1, 0.25)) << "driving: wider by its braking distance";
  Rig still;
  EXPECT_FALSE(still.vehicle.inProtectiveField(p, 0.8, -1.1, 0.25)) << "standing";
  // Braking, the command drops at once and the vehicle does not: the field stays sized for the
  // speed it drives at (sized for the command, it shrank under a vehicle still at 1 m/s).
  r.accel = 1.0;
  r.v = 1.0;
  r.warned = true;  // commands 0.3 m/s from now on
  r.run(0.2);
  EXPECT_TRUE(r.vehicle.inProtectiveField(p, 1.8, 0.0, 0.25)) << "braking from 1 m/s";
}

// A person walking head-on into a vehicle at 1.6 m/s (the approach speed ISO 13855 sizes safety
// distances for), stopping only when 5 cm from it: with the warning field the vehicle slows early
// and stands before they meet; with the protective field alone it braked too late (what a mixed
// fleet run showed: a 5 cm contact).
TEST(Vda5050Vehicle, ItsWarningFieldSlowsItForAPersonWalkingTowardsIt) {
  auto gapAtTheEnd = [](bool warningField) {
    Rig r;
    Vda5050VehicleConfig c = test::rigConfig();
    c.personApproachSpeed = 1.6;  // ISO 13855's K (off by default)
    r.vehicle = Vda5050Vehicle(c, Pose2{0.0, 0.0, 0.0});
    r.accel = 1.0;  // the vehicle's braking
    EXPECT_EQ(r.vehicle.onOrder(lineOrder("o1", 0, 0, 30, 30)).decision, OrderDecision::kAcceptNew);
    r.run(2.0);  // up to speed
    double px = r.pose.x + 9.0;
    double vehicleSpeedWhenMet = -1.0;
    r.run(8.0, [&] {
      const double gap = px - r.pose.x - 0.3 - 0.25;  // vehicle's half length, person's radius
      if (gap > 0.05) {
        px -= 1.6 * 0.1;
      } else if (vehicleSpeedWhenMet < 0.0) {
        vehicleSpeedWhenMet = r.v;
      }
      r.person = r.vehicle.inProtectiveField(r.pose, px, 0.0, 0.25);
      r.warned = warningField && r.vehicle.inWarningField(r.pose, px, 0.0, 0.25);
    });
    return std::make_pair(px - r.pose.x - 0.3 - 0.25, vehicleSpeedWhenMet);
  };
  const auto [gap, speed] = gapAtTheEnd(true);
  const auto [gapWithout, speedWithout] = gapAtTheEnd(false);
  EXPECT_GE(gap, 0.0) << "with the warning field they never touch";
  EXPECT_EQ(speed, 0.0) << "with the warning field the vehicle stands when the person reaches it";
  EXPECT_GT(speedWithout, 0.0)
      << "with the protective field alone it is still moving then (why the warning field)";
  EXPECT_LT(gapWithout, gap);
  // The warning field reaches farther than the protective field only while driving.
  Rig r;
  Vda5050VehicleConfig c = test::rigConfig();
  c.personApproachSpeed = 1.6;
  r.vehicle = Vda5050Vehicle(c, Pose2{0.0, 0.0, 0.0});
  const Pose2 p{0.0, 0.0, 0.0};
  EXPECT_EQ(r.vehicle.inWarningField(p, 1.8, 0.0, 0.25), r.vehicle.inProtectiveField(p, 1.8, 0.0, 0.25));
  ASSERT_EQ(r.vehicle.onOrder(lineOrder("o1", 0, 0, 6, 6)).decision, OrderDecision::kAcceptNew);
  r.run(2.0);
  EXPECT_TRUE(r.vehicle.inWarningField(p, 3.0, 0.0, 0.25));
  EXPECT_FALSE(r.vehicle.inProtectiveField(p, 3.0, 0.0, 0.25));
}

// Its scanner sees machines too, in a shorter field than people's (so vehicles can follow one
// another on the roadmap): a robot 0.5 m ahead of the front stops it when it drives, not when it
// stands; one beside or behind does not.
TEST(Vda5050Vehicle, ItsFieldForMachinesIsShortAndGrowsWithItsSpeed) {
  Rig r;
  const Pose2 p{0.0, 0.0, 0.0};
  // Standing: the front at 0.3 m, the field to 0.45 m, a robot of radius 0.3 whose centre is at x.
  EXPECT_TRUE(r.vehicle.machineInField(p, 0.7, 0.0, 0.3));
  EXPECT_FALSE(r.vehicle.machineInField(p, 0.8, 0.0, 0.3)) << "standing: just beyond";
  EXPECT_FALSE(r.vehicle.machineInField(p, -0.8, 0.0, 0.3)) << "behind";
  EXPECT_FALSE(r.vehicle.machineInField(p, 0.5, 0.7, 0.3)) << "beside, clear of the width";
  EXPECT_TRUE(r.vehicle.inProtectiveField(p, 1.2, 0.0, 0.3)) << "people are seen farther";
  ASSERT_EQ(r.vehicle.onOrder(lineOrder("o1", 0, 0, 6, 6)).decision, OrderDecision::kAcceptNew);
  r.run(2.0);
  EXPECT_TRUE(r.vehicle.machineInField(p, 0.8, 0.0, 0.3)) << "driving: its braking distance too";
}

TEST(Vda5050Vehicle, PauseResumeAndCancel) {
  Rig r;
  ASSERT_EQ(r.vehicle.onOrder(lineOrder("o1", 0, 0, 6, 6)).decision, OrderDecision::kAcceptNew);
  r.run(2.0);
  vda5050::InstantActions ia;
  ia.actions.push_back({"startPause", "p1", "HARD", {}, {}});
  r.vehicle.onInstantActions(ia);
  const double x = r.pose.x;
  r.run(3.0);
  EXPECT_NEAR(r.pose.x, x, 1e-9);
  EXPECT_TRUE(r.state().paused.value_or(false));
  ia.actions = {{"stopPause", "p2", "HARD", {}, {}}};
  r.vehicle.onInstantActions(ia);
  r.run(2.0);
  EXPECT_GT(r.pose.x, x + 0.5);

  ia.actions = {{"cancelOrder", "c1", "HARD", {}, {}}};
  r.vehicle.onInstantActions(ia);
  r.run(3.0);
  auto s = r.state();
  EXPECT_TRUE(s.nodeStates.empty());
  EXPECT_TRUE(s.edgeStates.empty());
  EXPECT_FALSE(s.driving);
  // After a cancel a new order is welcome, from where the vehicle last passed a node.
  const int last = std::stoi(s.lastNodeId.substr(1));
  EXPECT_EQ(r.vehicle.onOrder(lineOrder("o2", 0, last, 2, 2)).decision, OrderDecision::kAcceptNew);

  ia.actions = {{"dance", "d1", "NONE", {}, {}}};
  r.vehicle.onInstantActions(ia);
  s = r.state();
  EXPECT_EQ(s.actionStates.back().actionStatus, "FAILED");
}

// startCharging works only standing on a charger with nothing left to drive (else FAILED with a
// chargingError saying why); while charging the vehicle takes no order (VDA 5050 2.1, 6.8.1:
// stopCharging comes first); its state reports the battery and the charging flag.
TEST(Vda5050Vehicle, ChargesOnAChargerOnlyAndTakesNoOrderWhileCharging) {
  Rig r;
  const auto action = [&](const std::string& type, const std::string& id) {
    vda5050::InstantActions ia;
    ia.actions.push_back({type, id, "HARD", {}, {}});
    r.vehicle.onInstantActions(ia);
    for (const auto& a : r.state().actionStates) {
      if (a.actionId == id) {
        return a;
      }
    }
    return vda5050::ActionState{};
  };
  r.vehicle.senseBattery(0.4, false);
  auto a = action("startCharging", "c1");
  EXPECT_EQ(a.actionStatus, "FAILED");
  EXPECT_EQ(a.resultDescription.value_or(""), "not on a charging spot");
  auto s = r.state();
  ASSERT_FALSE(s.errors.empty());
  EXPECT_EQ(s.errors.back().errorType, "chargingError");
  EXPECT_FALSE(s.batteryState.charging);
  EXPECT_NEAR(s.batteryState.batteryCharge, 40.0, 1e-9);

  // On a charger but with an order to drive: no.
  r.vehicle.senseBattery(0.4, true);
  ASSERT_EQ(r.vehicle.onOrder(lineOrder("o1", 0, 0, 3, 3)).decision, OrderDecision::kAcceptNew);
  EXPECT_EQ(action("startCharging", "c2").actionStatus, "FAILED");
  r.run(10.0);  // drives to n2 and stops: the order is done
  ASSERT_TRUE(r.state().nodeStates.empty());

  EXPECT_EQ(action("startCharging", "c3").actionStatus, "FINISHED");
  EXPECT_TRUE(r.vehicle.charging());
  r.vehicle.senseBattery(0.45, true);
  s = r.state();
  EXPECT_TRUE(s.batteryState.charging);
  EXPECT_NEAR(s.batteryState.batteryCharge, 45.0, 1e-9);
  const auto v = r.vehicle.onOrder(lineOrder("o2", 0, 2, 2, 2));
  EXPECT_EQ(v.decision, OrderDecision::kReject);
  EXPECT_EQ(v.errorType, "orderError");
  EXPECT_NE(v.description.find("charging"), std::string::npos) << v.description;

  EXPECT_EQ(action("stopCharging", "c4").actionStatus, "FINISHED");
  EXPECT_FALSE(r.vehicle.charging());
  EXPECT_FALSE(r.state().batteryState.charging);
  EXPECT_EQ(action("stopCharging", "c5").actionStatus, "FINISHED");  // idempotent
  EXPECT_EQ(r.vehicle.onOrder(lineOrder("o2", 0, 2, 2, 2)).decision, OrderDecision::kAcceptNew);
  const auto f = r.vehicle.factsheet(0);
  EXPECT_NE(std::find(f.agvActions.begin(), f.agvActions.end(), "startCharging"), f.agvActions.end());
}

TEST(Vda5050Vehicle, PickAtANodeHoldsTheVehicleUntilFinished) {
  Rig r;
  auto o = lineOrder("o1", 0, 0, 3, 3);
  o.nodes[1].actions.push_back({"pick", "pick-1", "HARD", {}, {}});
  ASSERT_EQ(r.vehicle.onOrder(o).decision, OrderDecision::kAcceptNew);
  EXPECT_EQ(r.state().actionStates.at(0).actionStatus, "WAITING");
  bool seen_running = false;
  for (int i = 0; i < 200 && r.pose.x < 1.5; ++i) {
    r.run(0.1);
    const auto s = r.state();
    if (s.actionStates.at(0).actionStatus == "RUNNING") {
      seen_running = true;
      EXPECT_NEAR(r.pose.x, 1.0, 0.2);
    }
  }
  EXPECT_TRUE(seen_running);
  r.run(10.0);
  EXPECT_EQ(r.state().actionStates.at(0).actionStatus, "FINISHED");
  EXPECT_NEAR(r.pose.x, 2.0, 0.2);
}

TEST(Vda5050Vehicle, StateIsDueAtTheIntervalAndOnEvents) {
  Rig r;
  (void)r.state();
  EXPECT_FALSE(r.vehicle.stateDue(r.t + 0.5));
  EXPECT_TRUE(r.vehicle.stateDue(r.t + 1.0));
  ASSERT_EQ(r.vehicle.onOrder(lineOrder("o1", 0, 0, 3, 3)).decision, OrderDecision::kAcceptNew);
  EXPECT_TRUE(r.vehicle.stateDue(r.t));  // an accepted order is an event
  const auto a = r.state();
  const auto b = r.state();
  EXPECT_EQ(b.header.headerId, a.header.headerId + 1);
}

}  // namespace
}  // namespace fleet::sim
