// The agent in reserved traffic (the harness, a small kinematic world with synthetic releases, is
// reserved_sim.hpp): it drives what is released and stops at its end, keeps going when the base
// is extended in time, reports every node it reaches, ignores releases it must not follow, docks
// when the base ends at its goal, waits (and fails nothing) without releases, reports itself
// blocked by a person, keeps to the released nodes round corners, drives off a corner node only
// once it faces the next node, drives a base that turns back to where it stands, and turns to its
// way when held by a robot beside it. Off its node: reserved_rejoin_test.cpp.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <optional>
#include <vector>

#include "fleet/core/angles.hpp"
#include "reserved_sim.hpp"

using namespace fleet;
using namespace fleet::reserved_test;

TEST_P(ReservedPlanner, StopsAtTheEndOfItsBaseWhenNoExtensionComes) {
  Sim sim(GetParam());
  sim.agent->onAssignment(order(kFarPickup));
  sim.agent->onRelease(release(1, lane(0, 6)));  // 3 m, to x = 4
  sim.run(20.0);
  const double end = lane(6).x;
  EXPECT_LE(sim.maxX, end + 0.05) << "overshot the end of the base";
  EXPECT_GE(sim.truth.x, end - 0.15) << "stopped short of the end of the base";
  EXPECT_NEAR(sim.truth.y, kY, 0.1);
  EXPECT_EQ(sim.twist.v, 0.0);
  EXPECT_EQ(sim.lastNode(), 6);
  EXPECT_FALSE(sim.failed());
  EXPECT_TRUE(sim.agent->busy());
}

namespace {

struct Cruise {
  double slowest = 1e9;  // the slowest speed between x = 2.5 m and 7 m (the robot is up to speed)
  double at7 = -1.0;     // when it passed x = 7 m
  Sim sim;
  explicit Cruise(const char* planner) : sim(planner) {}
};

/// Along the lane to node 16 (x = 9), the base either released at once or, as the traffic manager
/// does it, extended to 2 m ahead of every node the robot reports.
Cruise cruise(const char* planner, bool extendOnReports) {
  Cruise c(planner);
  Sim& sim = c.sim;
  sim.agent->onAssignment(order(kFarPickup));
  std::uint32_t seq = 1;
  sim.agent->onRelease(release(seq, lane(0, extendOnReports ? 4 : 16)));
  std::int32_t extendedFrom = 0;
  while (sim.now() < 30.0) {
    const auto out = sim.step();
    if (extendOnReports && out.traffic && out.traffic->node != extendedFrom && out.traffic->node >= 0) {
      extendedFrom = out.traffic->node;
      sim.agent->onRelease(release(++seq, lane(extendedFrom, std::min(extendedFrom + 4, 16))));
    }
    if (sim.truth.x > 2.5 && sim.truth.x < 7.0) {
      c.slowest = std::min(c.slowest, sim.twist.v);
    }
    if (c.at7 < 0.0 && sim.truth.x > 7.0) {
      c.at7 = sim.now();
    }
  }
  return c;
}

}  // namespace

TEST_P(ReservedPlanner, KeepsGoingWithoutStoppingWhileTheBaseIsExtendedInTime) {
  // The same drive as with the whole lane released at once: the ends of the bases never brake it.
  // And it cruises: DWA used to drive at about 0.45 m/s here (its progress term favours the speed
  // whose rollout ends on the carrot: 0.8 m over 1.7 s), so reserved traffic shortens its rollout.
  const Cruise whole = cruise(GetParam(), false);
  const Cruise extended = cruise(GetParam(), true);
  EXPECT_GT(whole.slowest, 0.7) << "below cruise (0.8 m/s) on an open straight";
  EXPECT_GT(extended.slowest, 0.7) << "stopped for the end of a base that was extended in time";
  EXPECT_GT(extended.slowest, whole.slowest - 0.05) << "braked for the end of a base";
  ASSERT_GT(extended.at7, 0.0);
  EXPECT_LT(extended.at7, whole.at7 + 0.3);
  const Sim& sim = extended.sim;
  EXPECT_LE(sim.maxX, lane(16).x + 0.05);
  EXPECT_GE(sim.truth.x, lane(16).x - 0.15);
  EXPECT_EQ(sim.lastNode(), 16);
  EXPECT_EQ(sim.agent->releases().ignored(), 0u);
  EXPECT_GE(sim.agent->releases().accepted, 13u);
}

TEST_P(ReservedPlanner, ReportsEveryNodeItReachesInOrderWhenItIsThere) {
  Sim sim(GetParam());
  sim.agent->onAssignment(order(kFarPickup));
  sim.agent->onRelease(release(1, lane(0, 12)));
  sim.run(20.0);
  ASSERT_FALSE(sim.reports.empty());
  std::vector<std::int32_t> nodes;
  for (std::size_t i = 0; i < sim.reports.size(); ++i) {
    const auto& r = sim.reports[i];
    EXPECT_EQ(r.robot_id, "r1");
    EXPECT_EQ(r.epoch, 1u);
    EXPECT_TRUE(r.follows);
    if (nodes.empty() || r.node != nodes.back()) {
      nodes.push_back(r.node);
      if (r.node > 0) {
        // Reported when the robot is on the node (within the tolerance) or just past it.
        EXPECT_GT(sim.reportX[i], lane(r.node).x - 0.15) << "node " << r.node << " reported early";
        EXPECT_LT(sim.reportX[i], lane(r.node).x + 0.15) << "node " << r.node << " reported late";
      }
    }
  }
  std::vector<std::int32_t> expected;
  for (int k = 0; k <= 12; ++k) {
    expected.push_back(k);
  }
  EXPECT_EQ(nodes, expected) << "every node once, in order (0: the release's first, reported at once)";
}

TEST_P(ReservedPlanner, APersonOnTheBaseStopsTheRobotWhichReportsItselfBlockedAfterThreeSeconds) {
  Sim sim(GetParam());
  sim.people = {{4.5, kY}};
  sim.agent->onAssignment(order(kFarPickup));
  sim.agent->onRelease(release(1, lane(0, 16)));
  std::optional<double> heldAt;  // when the gate first held the robot in front of the person
  std::optional<double> blockedAt;
  bool unblocked = false;  // reported blocked and then not, while the person stood there
  double xAt10 = 0.0;
  // Longer than the reactive conduct's 60 s after which a blocked task fails (having backed off
  // and tried detours before): none of that here, the traffic manager plans round the person.
  while (sim.now() < 75.0) {
    const auto out = sim.step();
    if (!heldAt && out.state.mode == msg::RobotMode::Waiting) {
      heldAt = sim.now();
    }
    if (out.traffic && out.traffic->blocked && !blockedAt) {
      blockedAt = sim.now();
    }
    unblocked = unblocked || (blockedAt && out.traffic && !out.traffic->blocked);
    if (sim.k == 100) {
      xAt10 = sim.truth.x;
    }
  }
  ASSERT_TRUE(heldAt) << "never held up by the person";
  ASSERT_TRUE(blockedAt) << "never reported blocked";
  // (3 s, not less: a person walking past should not make the traffic manager plan round the robot.)
  EXPECT_GT(*blockedAt - *heldAt, 3.0) << "blocked is reported after three seconds of being held";
  EXPECT_LT(*blockedAt - *heldAt, 3.5);
  EXPECT_FALSE(unblocked) << "the blocked flag flapped";
  EXPECT_LT(std::abs(sim.truth.x - xAt10), 0.05) << "did not stop";
  EXPECT_GE(sim.minToPeople, 0.25 + 0.3 + 0.1) << "came too close to the person";
  EXPECT_LT(sim.maxX, 4.5) << "went round the person, off the base";
  EXPECT_FALSE(sim.failed());
  // What the service logs about a robot standing with its task: why, and since when.
  const auto& standing = sim.agent->standingStill();
  EXPECT_EQ(standing.why, "held by human");
  EXPECT_NEAR(static_cast<double>(standing.sinceNs) * 1e-9, *heldAt, 1.0);
  ASSERT_TRUE(standing.next.has_value());
  // The person walks away: the robot goes on to the end of its base and is no longer blocked.
  sim.people.clear();
  sim.run(25.0);
  EXPECT_FALSE(sim.reports.back().blocked);
  EXPECT_EQ(sim.lastNode(), 16);
}

TEST_P(ReservedPlanner, HeldByAPersonOnItsWayToACornerNodeItReportsItselfBlocked) {
  // As r39 stood 196 s in the full-stack dense check (seed 8, 40 robots; shifted by (-10, +1)
  // here): 0.24 m short of a corner node B, its way turning west there, a person 0.6 m ahead to
  // its right. Turned to face B it was held by the person, and held it turned on the spot towards
  // its carrot past the corner; the corner rule turned it back to B. Never held at the end of a
  // cycle, it never said it was blocked, and a robot behind it waited 120 s on a step it could
  // not make. Held by the person while it turns, it reports itself blocked after 3 s.
  Sim sim(GetParam());
  sim.restartAt({5.684, 4.661, 2.26});
  sim.people = {{5.9, 5.22}};
  sim.agent->onAssignment(order(kFarPickup));
  sim.agent->onRelease(release(
      1, {{100, 5.62, 3.94}, {101, 5.70, 4.90}, {102, 5.20, 4.75}, {103, 4.70, 4.75}, {104, 4.20, 4.75}}));
  std::optional<double> blockedAt;
  while (sim.now() < 20.0) {
    const auto out = sim.step();
    if (out.traffic && out.traffic->blocked && !blockedAt) {
      blockedAt = sim.now();
    }
  }
  EXPECT_GE(sim.minToPeople, 0.25 + 0.3) << "touched the person";
  ASSERT_TRUE(blockedAt) << "never reported blocked; standing: " << sim.agent->standingStill().why;
  EXPECT_LT(*blockedAt, 5.0);
  // 0.76 m past its node, it then backs onto it and gives way (as below).
  EXPECT_EQ(sim.agent->standingStill().why, "giving way to a person");
  EXPECT_LT(distance(sim.truth.position(), {5.62, 3.94}), 0.2);
  EXPECT_FALSE(sim.failed());
}

TEST_P(ReservedPlanner, HeldByAPersonPastItsNodeItBacksOntoItAndGivesWay) {
  // The person stands so that the robot stops 0.3 m past node 5 (x = 3.5), holding node 6 too: the
  // traffic manager re-plans only a robot on its node. After 10 s it backs onto node 5 and stands
  // there "giving way" (blocked all along, no flapping) for 15 s, then tries again.
  Sim sim(GetParam());
  sim.people = {{4.7, kY}};
  sim.agent->onAssignment(order(kFarPickup));
  sim.agent->onRelease(release(1, lane(0, 16)));
  std::optional<double> blockedAt;
  std::optional<double> backAt;
  bool unblocked = false;
  double farthest = 0.0;
  while (sim.now() < 45.0) {
    const auto out = sim.step();
    if (out.traffic && out.traffic->blocked && !blockedAt) {
      blockedAt = sim.now();
    }
    // (Until it tries again, 15 s after it is back.)
    const bool givingWay = !backAt || sim.now() < *backAt + 14.0;
    unblocked = unblocked || (blockedAt && givingWay && out.traffic && !out.traffic->blocked);
    if (blockedAt && !backAt) {
      farthest = std::max(farthest, sim.truth.x);
    }
    if (blockedAt && !backAt && std::abs(sim.truth.x - lane(5).x) < 0.08 &&
        sim.agent->standingStill().why == "giving way to a person") {
      backAt = sim.now();
    }
  }
  ASSERT_TRUE(blockedAt);
  EXPECT_GT(farthest, lane(5).x + 0.2) << "stopped short of where the test wants it";
  ASSERT_TRUE(backAt) << "never backed onto its node";
  EXPECT_GT(*backAt - *blockedAt, 5.0);
  EXPECT_LT(*backAt - *blockedAt, 20.0);
  EXPECT_FALSE(unblocked) << "the blocked flag dropped while it backed off or gave way";
  EXPECT_GE(sim.minToPeople, 0.25 + 0.3 + 0.1);
  EXPECT_EQ(sim.lastNode(), 5);
  EXPECT_FALSE(sim.failed());
  // The person leaves: it goes on.
  sim.people.clear();
  sim.run(30.0);
  EXPECT_FALSE(sim.reports.back().blocked);
  EXPECT_EQ(sim.lastNode(), 16);
}

TEST_P(ReservedPlanner, FollowsABaseRoundCornersAndStaysOnIt) {
  // Behind the robot first (it turns on the spot), then along the lane, up and back along the lane
  // above: 0.5 m nodes, two right angles.
  Sim sim(GetParam());
  sim.restartAt({sim.params.start.x, sim.params.start.y, M_PI});
  std::vector<Vec2> route;
  std::vector<msg::RouteNode> base = lane(0, 6);  // to (4, 5)
  for (int k = 1; k <= 4; ++k) {
    base.push_back({100 + k, 4.0, kY + kSpacing * k});  // up to (4, 7)
  }
  for (int k = 1; k <= 4; ++k) {
    base.push_back({200 + k, 4.0 - kSpacing * k, kY + 2.0});  // back to (2, 7)
  }
  for (const auto& n : base) {
    route.push_back({n.x, n.y});
  }
  sim.agent->onAssignment(order(kFarPickup));
  sim.agent->onRelease(release(1, base));
  double offRoute = 0.0;
  double intoCorners = 0.0;  // the fastest it came up to a corner node (the last 0.15 m before it)
  const std::vector<Vec2> corners{{4.0, kY}, {4.0, kY + 2.0}};
  std::vector<double> before(corners.size(), 1e9);
  while (sim.now() < 40.0) {
    (void)sim.step();
    for (std::size_t i = 0; i < corners.size(); ++i) {
      const double d = distance(sim.truth.position(), corners[i]);
      if (d < 0.15 && d < before[i]) {
        intoCorners = std::max(intoCorners, sim.twist.v);
      }
      before[i] = d;
    }
    double d = 1e9;
    for (std::size_t i = 0; i + 1 < route.size(); ++i) {
      const Vec2 a = route[i];
      const Vec2 ab = route[i + 1] - a;
      const double t = std::clamp((sim.truth.position() - a).dot(ab) / ab.squaredNorm(), 0.0, 1.0);
      d = std::min(d, distance(sim.truth.position(), a + ab * t));
    }
    offRoute = std::max(offRoute, d);
  }
  // (The roadmap allows 0.1 m of tracking error; the follower cuts 0.1 m, DWA 0.06 m, at 90°.)
  EXPECT_LT(offRoute, 0.15) << "left the released nodes";
  EXPECT_LT(intoCorners, 0.25) << "came up to a right angle at speed";
  EXPECT_LT(distance(sim.truth.position(), route.back()), 0.15);
  EXPECT_GE(sim.truth.x, 2.0 - 0.05) << "overshot the end of the base";
  EXPECT_EQ(sim.lastNode(), 204);
  EXPECT_EQ(sim.twist.v, 0.0);
}

TEST_P(ReservedPlanner, DrivesOffACornerNodeOnlyOnceItFacesTheNextNode) {
  // Along the lane, then a sharp turn (135°) up and back along a diagonal: standing on the corner
  // node the robot turns on the spot until it faces the next node, then drives (an arc driven off
  // A corner at speed swung it off a diagonal leg towards the shelf corner the leg passes).
  Sim sim(GetParam());
  std::vector<msg::RouteNode> base = lane(0, 6);  // to (4, 5)
  for (int k = 1; k <= 4; ++k) {
    base.push_back({100 + k, 4.0 - kSpacing * k, kY + kSpacing * k});  // to (2, 7)
  }
  sim.agent->onAssignment(order(kFarPickup));
  sim.agent->onRelease(release(1, base));
  const Vec2 corner{4.0, kY};
  const double leg = 0.75 * M_PI;
  double worst = 0.0;  // the largest heading error off the leg while driving off the corner
  while (sim.now() < 30.0) {
    (void)sim.step();
    if (sim.twist.v > 0.05 && distance(sim.truth.position(), corner) < 0.5 && sim.truth.y > kY + 0.02) {
      worst = std::max(worst, std::abs(angleDiff(leg, sim.truth.theta)));
    }
  }
  EXPECT_LT(worst, 0.15) << "drove off the corner still turning";
  EXPECT_LT(distance(sim.truth.position(), {2.0, kY + 2.0}), 0.15);
  EXPECT_EQ(sim.lastNode(), 104);
}

TEST_P(ReservedPlanner, DrivesABaseThatStepsAsideAndComesBackThroughItsOwnNode) {
  // The planner moves a robot aside for another and back: [A, B, A, C] with the robot on A. A robot
  // in the full stack stood 447 s on such a base, the traffic manager waiting for it to report B.
  Sim sim(GetParam());
  sim.agent->onAssignment(order(kFarPickup));
  sim.agent->onRelease(release(1, {lane(0), lane(-1), lane(0), lane(1)}));
  std::vector<std::int32_t> nodes;
  while (sim.now() < 30.0) {
    (void)sim.step();
    if (nodes.empty() || nodes.back() != sim.lastNode()) {
      nodes.push_back(sim.lastNode());
    }
  }
  EXPECT_EQ(nodes, (std::vector<std::int32_t>{0, -1, 0, 1})) << "the nodes reported in order";
  EXPECT_LT(distance(sim.truth.position(), {lane(1).x, lane(1).y}), 0.15);
  EXPECT_LT(sim.truth.x, lane(1).x + 0.1);
}

TEST_P(ReservedPlanner, DrivesABaseThatEndsOnTheNodeItStandsOn) {
  // [A, B, C, A] and [A, B, C, B] (released as far as the base reaches; more to come): the robot
  // drives out and back and reports each node, though the base ends where it stands or behind it.
  for (const auto& base : {std::vector<msg::RouteNode>{lane(0), lane(1), lane(2), lane(0)},
                           std::vector<msg::RouteNode>{lane(0), lane(1), lane(2), lane(1)}}) {
    Sim sim(GetParam());
    sim.agent->onAssignment(order(kFarPickup));
    sim.agent->onRelease(release(1, base));
    std::vector<std::int32_t> nodes;
    while (sim.now() < 40.0) {
      (void)sim.step();
      if (sim.lastNode() >= 0 && (nodes.empty() || nodes.back() != sim.lastNode())) {
        nodes.push_back(sim.lastNode());
      }
    }
    std::vector<std::int32_t> want;
    for (const auto& n : base) {
      want.push_back(n.node);
    }
    EXPECT_EQ(nodes, want) << "the nodes reported in order, ending on " << base.back().node;
    EXPECT_LT(distance(sim.truth.position(), {base.back().x, base.back().y}), 0.15);
  }
}

TEST_P(ReservedPlanner, DrivesALoopRoundABlockWhoseLastNodeIsBesideIt) {
  // As one robot stood 300 s with six waiting on it (20 robots): released from its
  // node A round a block by gentle corners to E, 0.14 m from where it stood. The path follower's
  // projection took it for at E at once and it stood "at the end of its base"; it drives to D,
  // where the way comes back, then on to E, and reports every node.
  Sim sim(GetParam());
  sim.restartAt({2.89, 4.99, 0.64});  // facing away, as it got the base
  sim.agent->onAssignment(order(kFarPickup));
  sim.agent->onRelease(
      release(1, {{649, 3.0, 5.0}, {632, 2.5, 4.5}, {616, 2.5, 4.0}, {1138, 2.75, 4.0}, {1137, 2.75, 5.0}}));
  std::vector<std::int32_t> nodes;
  while (sim.now() < 30.0) {
    (void)sim.step();
    if (sim.lastNode() >= 0 && (nodes.empty() || nodes.back() != sim.lastNode())) {
      nodes.push_back(sim.lastNode());
    }
  }
  EXPECT_EQ(nodes, (std::vector<std::int32_t>{649, 632, 616, 1138, 1137})) << "every node, in order";
  EXPECT_LT(distance(sim.truth.position(), {2.75, 5.0}), 0.15);
}

TEST_P(ReservedPlanner, HeldByARobotBesideItsWayItTurnsToItsWayAndGoesOn) {
  // As r8 stood 1,200 s in a full-stack run (seed 4): on the band in front of the
  // parking row, 7 cm below its lane and facing 24° down towards a robot parked beside the lane,
  // which its stop rule's corridor took in. The way on runs along the lane, clear of that robot:
  // The robot turns on the spot to face its way and drives on.
  Sim sim(GetParam());
  sim.restartAt({lane(0).x, kY - 0.07, -0.42});
  sim.parked = {{lane(0).x + 0.24, kY - 0.85}};
  sim.agent->onAssignment(order(kFarPickup));
  sim.agent->onRelease(release(1, lane(0, 4)));
  while (sim.now() < 20.0 && sim.lastNode() != 4) {
    (void)sim.step();
  }
  EXPECT_EQ(sim.lastNode(), 4);
}

// Disabled for a while (docs/algorithms.md, "robot agent: reserved traffic"): the release
// tracker and the path follower projected the robot onto the leg back into A and took the base as
// driven. Both now stop at C, where the base turns back (ReleaseParams::turnBack).
TEST_P(ReservedPlanner, DrivesALoopBackToItsNodeFacingAway) {
  // As a robot stood 579 s in the full stack (seed 2): a little off its node, facing away from the
  // base [A, B, C, A] where C is beside B and the last leg a diagonal back to A.
  Sim sim(GetParam());
  sim.restartAt({1.03, kY + 0.07, -2.77});
  sim.agent->onAssignment(order(kFarPickup));
  sim.agent->onRelease(release(1, {lane(0)}));
  sim.run(5.0);
  const msg::RouteNode up{100, lane(1).x, kY + kSpacing};
  sim.agent->onRelease(release(2, {lane(0), lane(1), up, lane(0)}));
  std::vector<std::int32_t> nodes;
  while (sim.now() < 45.0) {
    (void)sim.step();
    if (sim.lastNode() >= 0 && (nodes.empty() || nodes.back() != sim.lastNode())) {
      nodes.push_back(sim.lastNode());
    }
  }
  EXPECT_EQ(nodes, (std::vector<std::int32_t>{0, 1, 100, 0}));
}

INSTANTIATE_TEST_SUITE_P(Reserved, ReservedPlanner, ::testing::Values("dwa", "follow"));

TEST(Reserved, IgnoresForeignStaleAndOutOfOrderReleases) {
  Sim sim;
  sim.agent->onAssignment(order(kFarPickup));
  sim.agent->onRelease(release(5, lane(0, 4)));  // to x = 3
  sim.run(1.0);
  sim.agent->onRelease(release(6, lane(0, 16), false, 1, "r2"));  // another robot's
  sim.agent->onRelease(release(5, lane(0, 16)));                  // the same seq again
  sim.agent->onRelease(release(4, lane(0, 16)));                  // an older one
  sim.agent->onRelease(release(7, lane(3, 16)));                  // from a node it has not reported
  EXPECT_EQ(sim.agent->releases().foreign, 1u);
  EXPECT_EQ(sim.agent->releases().stale, 2u);
  EXPECT_EQ(sim.agent->releases().offNode, 1u);
  EXPECT_EQ(sim.agent->releases().ignored(), 4u);
  sim.run(15.0);
  EXPECT_LE(sim.maxX, lane(4).x + 0.05) << "drove what an ignored release offered";
  EXPECT_EQ(sim.lastNode(), 4);
  // A newer one from the node it reported is followed.
  sim.agent->onRelease(release(8, lane(4, 8)));
  sim.run(15.0);
  EXPECT_EQ(sim.lastNode(), 8);
  EXPECT_LE(sim.maxX, lane(8).x + 0.05);
  EXPECT_EQ(sim.agent->releases().accepted, 2u);
}

TEST(Reserved, DocksOnItsGoalAtTheEndOfTheBaseDwellsAndReportsHolding) {
  // P-1 at x = 6 faces back along the lane (its approach point is 1 m in front, on node 8 at
  // x = 5); the base ends on its dock node (100) and says so.
  Sim sim;
  const msg::Goal p1{{6.0, kY, M_PI}, "P-1", msg::GoalAction::Load, 3.0};
  sim.agent->onAssignment(order(p1));
  auto base = lane(0, 8);
  base.push_back({100, 6.0, kY});
  sim.agent->onRelease(release(1, base, true));
  std::optional<double> loadingAt;
  std::optional<double> doneAt;
  bool holdingWhileDocking = false;
  bool holdingWhileDwelling = false;
  while (sim.now() < 40.0) {
    const auto out = sim.step();
    if (out.status && out.status->state == msg::TaskState::Loading) {
      loadingAt = sim.now();
    }
    if (out.status && out.status->state == msg::TaskState::Done) {
      doneAt = sim.now();
    }
    if (out.traffic && out.traffic->holding) {
      holdingWhileDocking = holdingWhileDocking || (!loadingAt && sim.truth.x > 4.8);
      holdingWhileDwelling = holdingWhileDwelling || (loadingAt && !doneAt);
    }
  }
  ASSERT_TRUE(loadingAt) << "never docked";
  ASSERT_TRUE(doneAt);
  EXPECT_NEAR(*doneAt - *loadingAt, 3.0, 0.15) << "dwelt for the goal's duration";
  EXPECT_LT(distance(sim.truth.position(), p1.pose.position()), 0.15);
  EXPECT_LE(sim.maxX, 6.05);
  EXPECT_TRUE(holdingWhileDocking) << "the last leg onto the station is reported as holding";
  EXPECT_TRUE(holdingWhileDwelling);
  EXPECT_EQ(sim.lastNode(), 100);
  // Done, it has no task: its goal is its home now (the trip there is planned for it too).
  const auto& last = sim.reports.back();
  EXPECT_FALSE(last.holding);
  EXPECT_TRUE(last.has_goal);
  EXPECT_EQ(last.goal, sim.params.start);
  EXPECT_FALSE(sim.agent->busy());
}

TEST(Reserved, CountedOnItsGoalsNodeShortOfThePoseItDocksWithoutAnotherRelease) {
  // It passed beside its dock node (100, P-1 at x = 6) 0.28 m off, so it reported that node; the
  // traffic manager takes it as arrived and its release is the goal's node alone, from then on.
  Sim sim;
  sim.restartAt({5.78, 5.18, 0.63});
  const msg::Goal p1{{6.0, kY, M_PI_2}, "P-1", msg::GoalAction::Load, 2.0};
  sim.agent->onAssignment(order(p1));
  sim.agent->onRelease(release(1, {{100, 6.0, kY}}, true));
  std::optional<double> loadingAt;
  while (sim.now() < 20.0 && !loadingAt) {
    const auto out = sim.step();
    if (out.status && out.status->state == msg::TaskState::Loading) {
      loadingAt = sim.now();
    }
  }
  ASSERT_TRUE(loadingAt) << "stood 0.28 m from its dock with nothing more to come";
  EXPECT_LT(*loadingAt, 10.0);
  EXPECT_LT(distance(sim.truth.position(), p1.pose.position()), 0.15);
  EXPECT_EQ(sim.lastNode(), 100);
  EXPECT_FALSE(sim.failed());
}

TEST(Reserved, WithoutAReleaseItStandsStillWithItsTaskFor120sAndNothingFails) {
  // With the failure timer shortened (60 s without getting closer to its goal), so that 120 s
  // would fail it if it ran while it waits.
  Sim sim("dwa", 60.0);
  sim.agent->onAssignment(order(kFarPickup));
  sim.run(120.0);
  EXPECT_LT(distance(sim.truth.position(), sim.params.start.position()), 0.01);
  EXPECT_FALSE(sim.failed());
  EXPECT_TRUE(sim.agent->busy());
  ASSERT_GE(sim.reports.size(), 119u) << "a report at least every second";
  for (std::size_t i = 1; i < sim.reports.size(); ++i) {
    EXPECT_LE(sim.reports[i].stamp_ns - sim.reports[i - 1].stamp_ns, 1'000'000'000);
  }
  EXPECT_EQ(sim.reports.back().node, -1) << "placed by its pose";
  EXPECT_EQ(sim.reports.back().epoch, 0u);
  EXPECT_TRUE(sim.reports.back().has_goal);
  EXPECT_EQ(sim.reports.back().goal_station, "P-9");
  EXPECT_FALSE(sim.reports.back().holding);
  EXPECT_FALSE(sim.reports.back().blocked);
}

TEST(Reserved, AtTheEndOfItsBaseItWaitsLongerThanTheNoProgressLimitWithoutFailing) {
  // The traffic manager is away (or holds it back for another robot) for 200 s, longer than the
  // 180 s after which a robot that gets no closer to its goal fails its task.
  Sim sim;
  sim.agent->onAssignment(order(kFarPickup));
  sim.agent->onRelease(release(1, lane(0, 4)));
  sim.run(200.0);
  EXPECT_FALSE(sim.failed());
  EXPECT_TRUE(sim.agent->busy());
  EXPECT_EQ(sim.lastNode(), 4);
  // It comes back and the robot carries on.
  sim.agent->onRelease(release(1, lane(4, 8), false, 2));
  sim.run(10.0);
  EXPECT_EQ(sim.lastNode(), 8);
}

TEST(Reserved, PausedOrBlindItReportsHolding) {
  Sim sim;
  auto a = order(kFarPickup);
  sim.agent->onAssignment(a);
  sim.run(2.0);
  EXPECT_FALSE(sim.reports.back().holding);
  a.paused = true;
  ++a.revision;
  sim.agent->onAssignment(a);
  sim.run(2.0);
  EXPECT_TRUE(sim.reports.back().holding) << "paused by the operator";
  a.paused = false;
  ++a.revision;
  sim.agent->onAssignment(a);
  sim.run(2.0);
  EXPECT_FALSE(sim.reports.back().holding);
  // No sensor frames for a while: faulted, holding where it is.
  const std::size_t before = sim.reports.size();
  for (int i = 0; i < 20; ++i) {
    const auto out = sim.agent->step(static_cast<std::int64_t>(sim.k++) * 100'000'000, kDt);
    if (out.traffic) {
      sim.reports.push_back(*out.traffic);
    }
  }
  ASSERT_GT(sim.reports.size(), before);
  EXPECT_TRUE(sim.reports.back().holding) << "sensor stream lost";
}

// The task's priority reaches the traffic manager with the robot's progress; without a task it is 0.
TEST(Reserved, ItReportsItsTasksPriority) {
  Sim sim;
  auto a = order(kFarPickup);
  a.priority = 7;
  sim.agent->onAssignment(a);
  sim.run(1.0);
  ASSERT_FALSE(sim.reports.empty());
  EXPECT_EQ(sim.reports.back().priority, 7);
  msg::TaskAssignment cancel;
  cancel.robot_id = "r1";
  cancel.revision = a.revision + 1;
  cancel.priority = 7;  // a stale field on a cancel means nothing
  sim.agent->onAssignment(cancel);
  sim.run(1.0);
  EXPECT_EQ(sim.reports.back().priority, 0);
}
