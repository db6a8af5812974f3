// The motion gate alone: a perception, the other robots and a map in, the stop rule's speed, the
// rear check, the cross-traffic check and what holds the robot up out.

#include "motion_gate.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include "map_faces.hpp"

using namespace fleet;
using agent::Blocker;
using agent::GateView;
using agent::MotionGate;
using agent::OtherRobot;
using agent::Perception;
using agent::SeenKind;

namespace {

agent::GateParams params() {
  agent::GateParams p;
  p.radius = 0.3;
  p.stopGap = 0.35;
  p.headway = 1.0;
  p.limits = {0.8, -0.3, 1.5, 1.0, 3.0};
  return p;
}

// The robot at (2, 2) facing +x, having seen (robot frame) `points` and `seen`.
Perception perception(const std::vector<Vec2>& points, const std::vector<agent::Detection>& seen = {}) {
  Perception p;
  p.valid = true;
  p.pose = {2.0, 2.0, 0.0};
  for (const Vec2 q : points) {
    p.scan.push_back({q.norm(), q, p.pose.transform(q)});
  }
  for (auto d : seen) {
    d.map = p.pose.transform(d.local);
    p.detections.push_back(d);
  }
  return p;
}

const planning::OccupancyGrid& emptyMap() {
  static const planning::OccupancyGrid map(40, 40, 0.25, Vec2{0, 0});
  return map;
}

/// heldUp on 0.8 m/s along a 0.5 m⁻¹ curve comes out at `speed` on the same curve, not held.
void expectSlowedNotHeld(const MotionGate& gate, const GateView& view, double speed, const char* what) {
  double v = 0.8;
  double w = 0.4;
  Blocker b;
  const auto hold = gate.heldUp(view, v, w, b);
  EXPECT_DOUBLE_EQ(v, speed) << what;
  EXPECT_DOUBLE_EQ(w, 0.4 * speed / 0.8) << what << ": same curvature";
  EXPECT_FALSE(hold.held) << what << " is no hold";
}

}  // namespace

TEST(MotionGate, NothingSeenKeepsTheSpeed) {
  const MotionGate gate(params());
  const Perception seen = perception({});
  const std::vector<OtherRobot> others;
  Blocker b;
  const auto c = gate.clearSpeed({seen, others, emptyMap(), {}, false}, 0.8, b);
  EXPECT_EQ(c.speed, 0.8);
  EXPECT_FALSE(c.blockPoint);
  Perception none;
  EXPECT_EQ(gate.clearSpeed({none, others, emptyMap(), {}, false}, 0.8, b).speed, 0.8)
      << "no reading yet: nothing to go by";
}

TEST(MotionGate, APointAheadLimitsTheSpeedToKeepTheGap) {
  const MotionGate gate(params());
  // 1 m ahead in the corridor, and one beside it (0.4 m off the axis) that does not count.
  const Perception seen = perception({{1.0, 0.0}, {0.5, 0.4}});
  const std::vector<OtherRobot> others;
  Blocker b;
  const auto c = gate.clearSpeed({seen, others, emptyMap(), {}, false}, 0.8, b);
  EXPECT_NEAR(c.speed, (1.0 - 0.3 - 0.35) / 1.0, 1e-12);
  ASSERT_TRUE(c.blockPoint);
  EXPECT_NEAR(c.blockPoint->x, 3.0, 1e-12);
  EXPECT_FALSE(b.robot);
  EXPECT_TRUE(b.id.empty()) << "a static point is named by nobody";
  // Docking: static points may come to 8 cm.
  const Perception close = perception({{0.45, 0.0}});
  EXPECT_EQ(gate.clearSpeed({close, others, emptyMap(), {}, false}, 0.8, b).speed, 0.0);
  EXPECT_NEAR(gate.clearSpeed({close, others, emptyMap(), {}, true}, 0.8, b).speed, 0.07, 1e-12);
}

TEST(MotionGate, WithARouteTheGapIsKeptAlongTheRouteNotStraightAhead) {
  const MotionGate gate(params());
  const std::vector<OtherRobot> others;
  // The route bends right after 0.3 m. A shelf corner 0.67 m ahead and 0.2 m left is in the
  // straight corridor but 0.42 m from the route; a point 0.55 m ahead and 0.5 m right is outside
  // The straight corridor but on the route.
  const std::vector<Vec2> route{{2.0, 2.0}, {2.3, 2.0}, {2.6, 1.4}};
  const Perception corner = perception({{0.67, 0.2}});
  Blocker b;
  EXPECT_NEAR(gate.clearSpeed({corner, others, emptyMap(), {}, false}, 0.8, b).speed, 0.02, 1e-9)
      << "straight corridor: held by the corner";
  EXPECT_EQ(gate.clearSpeed({corner, others, emptyMap(), {}, false, &route}, 0.8, b).speed, 0.8)
      << "the route passes clear of the corner";
  const Perception onRoute = perception({{0.55, -0.5}});
  EXPECT_EQ(gate.clearSpeed({onRoute, others, emptyMap(), {}, false}, 0.8, b).speed, 0.8);
  EXPECT_NEAR(gate.clearSpeed({onRoute, others, emptyMap(), {}, false, &route}, 0.8, b).speed,
              std::hypot(0.55, 0.5) - 0.3 - 0.35, 1e-9)
      << "on the route: the gap straight to the point";
  // Behind the robot, the route's start does not count; and a straight-ahead point on the route
  // still keeps the straight gap.
  const Perception both = perception({{-0.2, 0.0}, {0.5, 0.0}});
  EXPECT_NEAR(gate.clearSpeed({both, others, emptyMap(), {}, false, &route}, 0.8, b).speed, 0.0, 1e-12);
  const Perception behind = perception({{-0.2, 0.0}});
  EXPECT_EQ(gate.clearSpeed({behind, others, emptyMap(), {}, false, &route}, 0.8, b).speed, 0.8);
}

// 100 robots: a parking place's approach node 0.335 m from a shelf corner, its route
// on to the lane leading along the corner, not towards it. The stop rule held the robot there for
// 595 s (0.035 m of gap where it keeps 0.35 m); a point the route leads away from only slows the
// robot to a creep (0.15 m/s) while it is within the gap.
TEST(MotionGate, APointTheRouteLeadsAwayFromDoesNotHoldTheRobot) {
  const MotionGate gate(params());
  const std::vector<OtherRobot> others;
  // The robot at (2, 2) faces +x, its route straight on; the corner 0.3 m to the right and 0.15 m
  // behind its front, as at r60's approach node (turned into the robot's frame).
  const std::vector<Vec2> route{{2.0, 2.0}, {3.0, 2.0}};
  const Perception beside = perception({{0.01, -0.335}});
  Blocker b;
  EXPECT_NEAR(gate.clearSpeed({beside, others, emptyMap(), {}, false, &route}, 0.8, b).speed, 0.15, 1e-12)
      << "the route leads along the corner, not nearer to it: a creep";
  EXPECT_NEAR(gate.clearSpeed({beside, others, emptyMap(), {}, false, &route}, 0.1, b).speed, 0.1, 1e-12);
  const Perception clear = perception({{0.01, -0.7}, {-0.3, -0.34}});
  EXPECT_EQ(gate.clearSpeed({clear, others, emptyMap(), {}, false, &route}, 0.8, b).speed, 0.8)
      << "beyond the gap, or behind: no creep";
  EXPECT_NEAR(gate.clearSpeed({beside, others, emptyMap(), {}, false}, 0.8, b).speed, 0.0, 1e-12)
      << "the straight corridor (reactive traffic) still counts it";
  // The same corner once the route bends towards it: held.
  const std::vector<Vec2> bends{{2.0, 2.0}, {2.1, 2.0}, {2.4, 1.6}};
  EXPECT_NEAR(gate.clearSpeed({beside, others, emptyMap(), {}, false, &bends}, 0.8, b).speed, 0.0, 1e-12);
  // A point ahead beside the route, which the robot comes nearer to, still keeps the gap.
  const Perception ahead = perception({{1.0, -0.32}});
  EXPECT_NEAR(gate.clearSpeed({ahead, others, emptyMap(), {}, false, &route}, 0.8, b).speed, 1.0 - 0.3 - 0.35,
              1e-9);
}

// Reserved traffic: the traffic layer plans robots one behind another at its following distance,
// so the gap to a robot is smaller than to a person or a shelf; the laser's readings on a robot's
// body keep the robot gap too (the laser sees a robot as it sees a shelf).
TEST(MotionGate, ARobotKeepsTheRobotGapAPersonAndAShelfTheStopGap) {
  auto p = params();
  p.robotStopGap = 0.25;
  const MotionGate gate(p);
  const MotionGate plain(params());
  const std::vector<OtherRobot> none;
  Blocker b;
  // Centres 1.0 m apart (the roadmap's following distance): 0.4 m between the discs.
  const Perception robot = perception({}, {{SeenKind::kRobot, {1.0, 0.0}, 0.3, {}}});
  EXPECT_NEAR(gate.clearSpeed({robot, none, emptyMap(), {}, false}, 0.8, b).speed, 0.4 - 0.25, 1e-9);
  EXPECT_NEAR(plain.clearSpeed({robot, none, emptyMap(), {}, false}, 0.8, b).speed, 0.4 - 0.35, 1e-9)
      << "no robot gap given: the stop gap";
  const Perception person = perception({}, {{SeenKind::kHuman, {0.95, 0.0}, 0.25, {}}});
  EXPECT_NEAR(gate.clearSpeed({person, none, emptyMap(), {}, false}, 0.8, b).speed, 0.4 - 0.35, 1e-9);
  // The laser's reading on the front of that robot: the robot gap when the robot is detected
  // there or reports itself there, the stop gap for a reading on nothing known (a shelf).
  const Perception hit = perception({{0.7, 0.0}}, {{SeenKind::kRobot, {1.0, 0.0}, 0.3, {}}});
  EXPECT_NEAR(gate.clearSpeed({hit, none, emptyMap(), {}, false}, 0.8, b).speed, 0.4 - 0.25, 1e-9);
  const Perception reading = perception({{0.7, 0.0}});
  std::vector<OtherRobot> reported(1);
  reported[0].id = "r2";
  reported[0].pos = {3.0, 2.0};
  EXPECT_NEAR(gate.clearSpeed({reading, reported, emptyMap(), {}, false}, 0.8, b).speed, 0.4 - 0.25, 1e-9);
  EXPECT_NEAR(gate.clearSpeed({reading, none, emptyMap(), {}, false}, 0.8, b).speed, 0.4 - 0.35, 1e-9);
  reported[0].pos = {3.5, 2.0};
  EXPECT_NEAR(gate.clearSpeed({reading, reported, emptyMap(), {}, false}, 0.8, b).speed, 0.4 - 0.35, 1e-9)
      << "a robot 0.8 m beyond the reading is not what the laser hit";
}

TEST(MotionGate, ARobotInTheWayIsNamedByTheNearestKnownRobot) {
  const MotionGate gate(params());
  const Perception seen = perception({}, {{SeenKind::kRobot, {0.8, 0.1}, 0.3, {}}});
  std::vector<OtherRobot> others(2);
  others[0].id = "r7";
  others[0].pos = {2.85, 2.05};
  others[1].id = "r9";
  others[1].pos = {5.0, 2.0};
  Blocker b;
  const auto c = gate.clearSpeed({seen, others, emptyMap(), {}, false}, 0.8, b);
  EXPECT_EQ(c.speed, 0.0);
  EXPECT_TRUE(b.robot);
  EXPECT_EQ(b.id, "r7");
  // Unknown robot: "robot"; a person: "human".
  Blocker unknown;
  (void)gate.clearSpeed({seen, {}, emptyMap(), {}, false}, 0.8, unknown);
  EXPECT_EQ(unknown.id, "robot");
  const Perception person = perception({}, {{SeenKind::kHuman, {0.8, 0.0}, 0.25, {}}});
  Blocker h;
  (void)gate.clearSpeed({person, others, emptyMap(), {}, false}, 0.8, h);
  EXPECT_FALSE(h.robot);
  EXPECT_EQ(h.id, "human");
}

TEST(MotionGate, TheRearIsClearUnlessSomethingIsCloseBehind) {
  const MotionGate gate(params());
  const std::vector<OtherRobot> others;
  EXPECT_TRUE(gate.rearClear({perception({{1.0, 0.0}, {-1.0, 0.0}}), others, emptyMap(), {}, false}));
  EXPECT_FALSE(gate.rearClear({perception({{-0.5, 0.1}}), others, emptyMap(), {}, false}));
  EXPECT_FALSE(gate.rearClear(
      {perception({}, {{SeenKind::kHuman, {-0.7, 0.0}, 0.25, {}}}), others, emptyMap(), {}, false}));
  const Perception none;
  EXPECT_FALSE(gate.rearClear({none, others, emptyMap(), {}, false})) << "blind: not clear";
}

TEST(MotionGate, HeldUpByARobotCrossingFromTheSide) {
  const MotionGate gate(params());
  // 0.9 m ahead and 0.9 m to the right, driving across the path at 0.8 m/s: outside the stop
  // rule's corridor, on collision course all the same.
  const Perception seen = perception({});
  std::vector<OtherRobot> others(1);
  others[0].id = "r2";
  others[0].pos = {2.9, 1.1};
  others[0].velocity = {0.0, 0.8};
  double v = 0.8;
  double w = 0.0;
  Blocker b;
  (void)gate.heldUp({seen, others, emptyMap(), {0.8, 0.0}, false}, v, w, b);
  EXPECT_LT(v, 0.5) << "did not slow for the crossing robot";
  // A robot standing off to the side (not crossing) does not hold the robot.
  others[0].pos = {3.5, 1.0};
  others[0].velocity = {};
  double v2 = 0.8;
  double w2 = 0.0;
  Blocker b2;
  EXPECT_FALSE(gate.heldUp({seen, others, emptyMap(), {0.8, 0.0}, false}, v2, w2, b2).held);
  EXPECT_NEAR(v2, 0.8, 1e-9);
}

TEST(MotionGate, HeldUpByAPointAheadKeepsTheCurvatureAndTheBlockPoint) {
  const MotionGate gate(params());
  const Perception seen = perception({{0.66, 0.0}});
  const std::vector<OtherRobot> others;
  double v = 0.8;
  double w = 0.4;
  Blocker b;
  const auto h = gate.heldUp({seen, others, emptyMap(), {0.8, 0.4}, false}, v, w, b);
  EXPECT_TRUE(h.held) << "0.01 m/s allowed";
  EXPECT_LT(v, 0.05);
  EXPECT_NEAR(w / v, 0.5, 1e-6) << "slowed along the same arc";
  ASSERT_TRUE(h.blockPoint);
  EXPECT_NEAR(h.blockPoint->x, 2.66, 1e-12);
}

TEST(MotionGate, ReversingStopsForWhatIsBehind) {
  const MotionGate gate(params());
  const std::vector<OtherRobot> others;
  double v = -0.2;
  double w = 0.0;
  Blocker b;
  (void)gate.heldUp({perception({{-0.5, 0.0}}), others, emptyMap(), {}, false}, v, w, b);
  EXPECT_EQ(v, 0.0);
  v = -0.2;
  (void)gate.heldUp({perception({{1.5, 0.0}}), others, emptyMap(), {}, false}, v, w, b);
  EXPECT_EQ(v, -0.2);
}

TEST(MapFaces, OnlyTheFacesTurnedTowardsTheRobotWithinRange) {
  planning::OccupancyGrid map(20, 20, 0.25, Vec2{0, 0});
  map.setBlocked({10, 10});  // the cell [2.5, 2.75] x [2.5, 2.75]
  const auto pts = agent::mapFaces(map, {2.0, 2.625}, 1.0);
  // The robot is left of the cell: only its left face (x = 2.5), in points every 0.0833 m.
  ASSERT_EQ(pts.size(), 4u);
  for (const Vec2 q : pts) {
    EXPECT_NEAR(q.x, 2.5, 1e-12);
  }
  EXPECT_TRUE(agent::mapFaces(map, {0.5, 0.5}, 1.0).empty()) << "out of range";
}

TEST(MotionGate, SpeedZonesSlowTheRobotBeforeItEntersAndKeepTheCurvature) {
  auto p = params();
  const double slow = 0.3;  // (captured: gcc 12 warns on copying a captureless lambda's std::function)
  p.speedLimit = [slow](Vec2 q) { return q.x > 2.5 ? slow : std::numeric_limits<double>::infinity(); };
  const MotionGate gate(p);
  const Perception seen = perception({});
  const std::vector<OtherRobot> others;
  const GateView view{seen, others, emptyMap(), {}, false};
  // At (2, 2) facing +x: 0.8 m/s reaches the zone within the 1 s headway.
  EXPECT_DOUBLE_EQ(gate.zoneSpeed(view, 0.8), 0.3);
  expectSlowedNotHeld(gate, view, 0.3, "a speed zone");
  // Slow enough not to reach it within the headway's look-ahead (at least the radius): unchanged.
  EXPECT_TRUE(std::isinf(gate.zoneSpeed(view, 0.2)));
  // Backing away from it: unchanged; without zones: unchanged.
  EXPECT_TRUE(std::isinf(gate.zoneSpeed(view, -0.3)));
  EXPECT_TRUE(std::isinf(MotionGate(params()).zoneSpeed(view, 0.8)));
}

namespace {

// The robot at (2, 2) facing +x, having seen `people` (map frame, with their velocities).
Perception seeing(const std::vector<agent::Person>& people) {
  Perception p = perception({});
  p.people = people;
  return p;
}

}  // namespace

TEST(MotionGate, APersonBesideTheWayCloseAheadSlowsTheRobotAndKeepsTheCurvature) {
  const MotionGate gate(params());
  const std::vector<OtherRobot> others;
  // Level with the robot's front, 0.3 m beside its corridor (centre 0.85 m off its axis).
  const Perception level = seeing({{{2.3, 2.85}, {}, 0.25, true}});
  const GateView view{level, others, emptyMap(), {0.8, 0.4}, false};
  EXPECT_DOUBLE_EQ(gate.besidePeopleSpeed(view), 0.3);
  expectSlowedNotHeld(gate, view, 0.3, "a person beside");
  // 0.7 m ahead of the front, as beside: the stop rule's law on the gap along (headway 1 s).
  EXPECT_NEAR(
      gate.besidePeopleSpeed({seeing({{{3.25, 2.85}, {}, 0.25, true}}), others, emptyMap(), {}, false}), 0.7,
      1e-12);
  // Beside the robot's body (a person overtaking it): no faster than the near speed.
  EXPECT_DOUBLE_EQ(gate.besidePeopleSpeed(
                       {seeing({{{2.0, 1.15}, {1.7, 0.0}, 0.25, true}}), others, emptyMap(), {}, false}),
                   0.3);
}

TEST(MotionGate, APersonFarBesideBehindOrFarAheadDoesNotSlowTheRobot) {
  const MotionGate gate(params());
  const std::vector<OtherRobot> others;
  auto speed = [&](agent::Person h) {
    return gate.besidePeopleSpeed({seeing({h}), others, emptyMap(), {}, false});
  };
  EXPECT_TRUE(std::isinf(speed({{2.5, 3.0}, {}, 0.25, true}))) << "0.45 m beside the corridor";
  EXPECT_TRUE(std::isinf(speed({{1.6, 2.6}, {}, 0.25, true}))) << "behind the robot";
  EXPECT_GE(speed({{3.9, 2.6}, {}, 0.25, true}), 0.8) << "1.35 m ahead of its front";
  // Reversing: the rule is for the way ahead.
  double v = -0.2;
  double w = 0.0;
  Blocker b;
  (void)gate.heldUp({seeing({{{2.3, 2.85}, {}, 0.25, true}}), others, emptyMap(), {}, false}, v, w, b);
  EXPECT_EQ(v, -0.2);
}

TEST(MotionGate, APersonOvertakingAndTurningOntoTheWayIsNotTouched) {
  // As a robot touched a person in a 40-robot run: driving +x at 0.8 m/s, a person overtakes it at
  // 1.7 m/s 0.33 m beside its corridor and, just ahead of it, turns onto its way and stops there.
  // The robot sees the person two cycles late (their velocity from two readings) and its
  // speed follows the gate's command a cycle late within 1 m/s² of deceleration. Without the rule
  // for people beside the way, the same robot touches the person.
  auto closest = [](double sideGap, double turnAhead) {
    auto p = params();
    p.personSideGap = sideGap;
    const MotionGate gate(p);
    const std::vector<OtherRobot> others;
    double x = 2.0;
    double speed = 0.8;
    double command = 0.8;
    Vec2 person{0.8, 2.0 + 0.3 + 0.25 + 0.33};
    Vec2 velocity{1.7, 0.0};
    std::vector<Vec2> past(4, person);  // past[0] now, past[i] i cycles ago
    double gap = 1e9;                   // centre to centre, less the two radii
    for (int k = 0; k < 60; ++k) {
      Perception seen = perception({});
      seen.pose = {x, 2.0, 0.0};
      seen.people = {{past[2], (past[2] - past[3]) / 0.1, 0.25, true}};
      double v = 0.8;
      double w = 0.0;
      Blocker b;
      (void)gate.heldUp({seen, others, emptyMap(), {command, 0.0}, false}, v, w, b);
      speed = std::max(command - 0.1, std::min(speed + 0.1, command));  // last cycle's command
      command = v;
      x += speed * 0.1;
      std::rotate(past.rbegin(), past.rbegin() + 1, past.rend());
      past[0] = person;
      if (velocity.x > 0.0 && person.x - x >= turnAhead) {
        velocity = {0.0, -1.5};  // turns onto the robot's way
      }
      person += velocity * 0.1;
      if (person.y <= 2.0) {
        person.y = 2.0;
        velocity = {};  // stands there
      }
      gap = std::min(gap, std::hypot(person.x - x, person.y - 2.0) - 0.55);
    }
    return gap;
  };
  // The person turns with their centre 0.6 to 1.5 m ahead of the robot's (0.05 to 0.95 m ahead of
  // its front; nearer, they walk into its side, which no speed of the robot's can prevent).
  bool touchedWithout = false;
  for (int cm = 60; cm <= 150; cm += 10) {
    const double turnAhead = cm / 100.0;
    EXPECT_GT(closest(params().personSideGap, turnAhead), 0.0) << "turning " << turnAhead << " m ahead";
    touchedWithout = touchedWithout || closest(-1.0, turnAhead) < 0.0;
  }
  EXPECT_TRUE(touchedWithout) << "the scenario no longer needs the rule";
}
