// The agent in reserved traffic off its node: back onto it through its node when the straight way
// on passes a shelf corner (reached just within reach of the node, or on its edge far past it), a
// loop back to where it stands, and no going back when an obstacle stands on the edge itself (it
// reports itself blocked instead). The harness is reserved_sim.hpp.

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cstdint>
#include <memory>
#include <vector>

#include "reserved_sim.hpp"

using namespace fleet;
using namespace fleet::reserved_test;

TEST_P(ReservedPlanner, HeldOffItsNodeItDrivesALoopBackToWhereItStands) {
  // As the whole fleet stood in a full-stack run (seed 3): a person stopped the robot
  // 0.6 m off its node A, on the spot of a queue node Q; the traffic manager, still placing it on
  // A, released a loop [A, B, C, D, Q] out along the lane and back to Q. Given the whole base, the
  // path follower took the way back for the way out and the robot stood for good; it drives the
  // way up to where the base turns back (C), then the rest, and reports every node.
  Sim sim(GetParam());
  sim.restartAt({lane(0).x - 0.235, kY - 0.56, 2.58});  // as it stood, 6 cm from Q
  sim.agent->onAssignment(order(kFarPickup));
  sim.agent->onRelease(release(1, {lane(0)}));
  sim.run(2.0);
  const msg::RouteNode q{200, lane(0).x - 0.25, kY - 0.5};
  sim.agent->onRelease(release(2, {lane(0),
                                   {101, lane(0).x + 0.5, kY - 0.5},
                                   {102, lane(0).x + 1.0, kY - 0.5},
                                   {103, lane(0).x + 0.75, kY - 0.5},
                                   q}));
  std::vector<std::int32_t> nodes;
  while (sim.now() < 30.0) {
    (void)sim.step();
    if (nodes.empty() || nodes.back() != sim.lastNode()) {
      nodes.push_back(sim.lastNode());
    }
  }
  EXPECT_EQ(nodes, (std::vector<std::int32_t>{0, 101, 102, 103, 200}));
  EXPECT_LT(distance(sim.truth.position(), {q.x, q.y}), 0.15);
}

/// Standing at `start` beside the corner `corner` of one shelf (cells [cx0, cx1) x [cy0, cy1) of a
/// 15 m x 10 m floor), released {a, b}: the robot goes back to a and drives the edge to b, clear
/// of the corner, with one rejoin.
void expectRejoinRoundCorner(Sim& sim, std::array<int, 4> shelf, Pose2 start, msg::RouteNode a,
                             msg::RouteNode b, Vec2 corner, const msg::Goal& goal) {
  auto grid = std::make_shared<planning::OccupancyGrid>(60, 40, 0.25, Vec2{0, 0});
  for (int cx = shelf[0]; cx < shelf[1]; ++cx) {
    for (int cy = shelf[2]; cy < shelf[3]; ++cy) {
      grid->setBlocked({cx, cy});
    }
  }
  sim.restartAt(start, grid);
  sim.agent->onAssignment(order(goal));
  sim.agent->onRelease(release(1, {a, b}));
  double closest = 1e9;  // to the shelf corner
  while (sim.now() < 40.0 && sim.lastNode() != b.node) {
    (void)sim.step();
    closest = std::min(closest, distance(sim.truth.position(), corner));
  }
  EXPECT_EQ(sim.lastNode(), b.node) << "held at " << sim.truth.x << ", " << sim.truth.y << ": "
                                    << sim.agent->standingStill().why;
  EXPECT_GT(closest, sim.params.radius) << "touched the corner";
  EXPECT_EQ(sim.agent->conduct().rejoins, 1u);
}

TEST_P(ReservedPlanner, OffItsNodeWithAShelfCornerInTheStraightWayItRejoinsThroughItsNode) {
  // As r10 stood 2,100 s in a full-stack run (seed 3): 0.28 m off its node A in the
  // gap between two shelves, its next node B (a parking place's approach) beyond a shelf corner
  // that the straight way from where it stands passes 0.29 m off, less than its radius. The
  // roadmap's edge A-B clears the corner; the robot goes back to A and drives the edge.
  Sim sim(GetParam());
  expectRejoinRoundCorner(sim, {4, 16, 10, 14} /* x 1..4, y 2.5..3.5 */, {4.47, 2.76, -1.95},
                          {131, 4.75, 2.75}, {1075, 4.0, 1.9}, {4.0, 2.5}, kFarPickup);
}

TEST_P(ReservedPlanner, JustWithinReachOfItsNodeWithAShelfCornerInTheWayItRejoinsThroughItsNode) {
  // As r34 stood 240 s with its task in the full-stack dense check (seed 24, 40 robots): it
  // reached its node A (8.5, 3.9) 0.149 m off, within the reach tolerance, below a shelf whose
  // corner (8.5, 4.5) the straight way on to B (9.25, 4.75) passes 0.31 m off; the edge A-B passes
  // it 0.40 m off. Its scan sees the corner, the stop rule held it, and it never went back to A:
  // it rejoined only from more than the reach tolerance off. Its task failed after 180 s.
  Sim sim(GetParam());
  expectRejoinRoundCorner(sim, {18, 34, 18, 22} /* x 4.5..8.5, y 4.5..5.5 */, {8.45, 4.04, 0.69},
                          {2472, 8.5, 3.9}, {2473, 9.25, 4.75}, {8.5, 4.5},
                          msg::Goal{{13.0, 4.75, 0.0}, "P-9", msg::GoalAction::Load, 2.0});
}

TEST_P(ReservedPlanner, OnItsEdgeFarPastItsNodeWithAShelfCornerBesideItRejoinsThroughItsNode) {
  // As r35 stood 223 s in the full-stack dense check (seed 29, 40 robots; shifted by (-30, -10)
  // here): it counted its node A reached 0.10 m short and drove the straight way from there to B,
  // nearing the edge A-B as it neared B, and its stop rule held it 0.046 m off the edge, 0.6 m past
  // A, with a shelf corner 0.05 m from its body. Off the edge by less than the rule's 0.05 m, it
  // never went back to A; off A by more than the reach tolerance, it does. (It starts on that
  // straight way where the harness's gate holds it, 0.048 m off the edge.)
  Sim sim(GetParam());
  expectRejoinRoundCorner(sim, {8, 24, 18, 22} /* x 2..6, y 4.5..5.5 */, {6.30, 5.72, -1.31},
                          {1115, 6.25, 6.25}, {2570, 6.5, 4.928542}, {6.0, 5.5},
                          msg::Goal{{6.5, 1.0, -M_PI_2}, "P-9", msg::GoalAction::Load, 2.0});
}

TEST_P(ReservedPlanner, HeldByAnObstacleOnItsEdgeItDoesNotGoBackButReportsItselfBlocked) {
  // An obstacle the roadmap does not know stands on the edge ahead: the robot stops in front of it
  // on the edge, past its node. Going back to the node gains nothing (the edge is the way on), so
  // it stands and reports itself blocked, for the traffic manager to plan round it; rejoining it
  // went back and forth every 10 s, and never stood held long enough to say it was blocked.
  Sim sim(GetParam());
  auto grid = std::make_shared<planning::OccupancyGrid>(40, 40, 0.25, Vec2{0, 0});
  for (int cy = 19; cy < 21; ++cy) {  // x 2.25 .. 2.5, y 4.75 .. 5.25
    grid->setBlocked({9, cy});
  }
  sim.restartAt({lane(0).x, kY, 0.0}, grid);
  sim.agent->onAssignment(order(kFarPickup));
  sim.agent->onRelease(release(1, lane(0, 6)));
  bool blocked = false;
  while (sim.now() < 40.0) {
    const auto out = sim.step();
    blocked = blocked || (out.traffic && out.traffic->blocked);
  }
  EXPECT_LT(sim.maxX, 2.25 - sim.params.radius) << "touched the obstacle";
  EXPECT_EQ(sim.agent->conduct().rejoins, 0u);
  EXPECT_TRUE(blocked) << "never reported itself blocked";
}

INSTANTIATE_TEST_SUITE_P(Reserved, ReservedPlanner, ::testing::Values("dwa", "follow"));
