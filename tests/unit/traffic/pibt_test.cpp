#include "fleet/traffic/pibt.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <numeric>
#include <random>
#include <tuple>

#include "fleet/traffic/plan_check.hpp"
#include "fleet/traffic/untangle.hpp"
#include "pibt_test_support.hpp"

using namespace fleet;
using namespace fleet::traffic;
using fleet::traffic::test::firstViolations;
using fleet::traffic::test::gridOf;
using fleet::traffic::test::randomMap;
using fleet::traffic::test::runLifelong;
using fleet::traffic::test::turnsAlong;
using fleet::traffic::test::walkToGoal;

namespace {

PibtOptions plain() {
  PibtOptions o;
  o.escapeAfter = 0;
  return o;
}

/// Steps until every agent with a goal has stood on it at least once (the goals stay put), or -1.
int stepsUntilAllReached(Pibt& p, int limit, std::vector<std::vector<NodeId>>* plan = nullptr) {
  std::vector<bool> reached(p.size(), false);
  if (plan != nullptr) {
    plan->push_back(p.positions());
  }
  for (int t = 1; t <= limit; ++t) {
    const auto& next = p.step();
    if (plan != nullptr) {
      plan->push_back(next);
    }
    for (std::size_t i = 0; i < p.size(); ++i) {
      reached[i] = reached[i] || p.goal(i) == kNoNode || next[i] == p.goal(i);
    }
    if (std::all_of(reached.begin(), reached.end(), [](bool b) { return b; })) {
      return t;
    }
  }
  return -1;
}

/// A grid whose nodes also exclude their neighbours: robots wider than a cell, so that one
/// reservation excludes several nodes and may push several agents at once. `diagonal`: the 8
/// neighbours (a robot of about three cells), else the 4 of the cross.
Graph wideRobots(const GridMap& m, bool diagonal = true) {
  Graph g = m.graph;
  for (std::size_t v = 0; v < m.freeCells(); ++v) {
    const GridCell c = m.cell(static_cast<NodeId>(v));
    for (int dx = -1; dx <= 1; ++dx) {
      for (int dy = -1; dy <= 1; ++dy) {
        const NodeId u = m.node(c.x + dx, c.y + dy);
        if (u != kNoNode && u != static_cast<NodeId>(v) && (diagonal || dx == 0 || dy == 0)) {
          g.addConflict(static_cast<NodeId>(v), u);
        }
      }
    }
  }
  return g;
}

}  // namespace

TEST(Pibt, ALoneAgentDrivesAShortestPath) {
  const GridMap m = gridOf({
      ".....",
      ".@@@.",
      ".....",
  });
  const std::vector<NodeId> start = {m.node(0, 1)};
  Pibt p(m.graph, start);
  p.setGoal(0, m.node(4, 1));
  EXPECT_EQ(stepsUntilAllReached(p, 50), 6);
  // At the goal it stays, and its priority (steps since it last reached a goal) is back to 0.
  p.step();
  EXPECT_EQ(p.positions()[0], m.node(4, 1));
  EXPECT_EQ(p.elapsed(0), 0);
}

/// A busy agent (still driving its last move in a plan kept in time) stays where the plan has it
/// and is not pushed: the agent behind waits, and goes on once the busy one decides again.
TEST(Pibt, ABusyAgentIsNeitherPlannedNorPushed) {
  const GridMap m = gridOf({"....."});
  const std::vector<NodeId> start = {m.node(1, 0), m.node(2, 0)};
  Pibt p(m.graph, start);
  p.setGoal(0, m.node(4, 0));  // behind, wants to pass through where agent 1 stands
  p.setGoal(1, m.node(3, 0));  // busy: would otherwise move on (and be pushed)
  const std::vector<std::uint8_t> busy = {0, 1};
  p.setBusy(busy);
  for (int i = 0; i < 3; ++i) {
    p.step();
    EXPECT_EQ(p.positions()[1], m.node(2, 0)) << "the busy agent moved or was pushed";
    EXPECT_EQ(p.positions()[0], m.node(1, 0));
  }
  p.setBusy(std::vector<std::uint8_t>{0, 0});
  p.step();
  EXPECT_EQ(p.positions()[1], m.node(3, 0));
  EXPECT_EQ(p.positions()[0], m.node(2, 0));
}

/// On an open grid a goal 5 across and 5 up has 252 shortest ways. Picking among them at random
/// zigzags (a real robot stops to turn at each zig); preferring the straightest takes one turn.
TEST(Pibt, AmongEquallyShortMovesTheStraightestIsTakenWhenAsked) {
  const GridMap m = gridOf({
      "......",
      "......",
      "......",
      "......",
      "......",
      "......",
  });
  auto turns = [&](bool straight, std::uint64_t seed) {
    PibtOptions o;
    o.preferStraight = straight;
    o.tieTolerance = 1e-3F;
    o.seed = seed;
    const std::vector<NodeId> start = {m.node(0, 5)};
    Pibt p(m.graph, start, o);
    p.setGoal(0, m.node(5, 0));
    const auto path = walkToGoal(m.graph, p, 20);
    EXPECT_EQ(path.size(), 11U) << "a shortest way either way";
    return turnsAlong(path);
  };
  int randomTurns = 0;
  for (std::uint64_t seed = 1; seed <= 8; ++seed) {
    EXPECT_EQ(turns(true, seed), 1) << "seed " << seed;
    randomTurns += turns(false, seed);
  }
  EXPECT_GT(randomTurns, 8 * 2) << "at random it zigzags (the reference behaviour, kept by default)";
}

TEST(Pibt, TaskPriorityDecidesWhoCrossesFirst) {
  const GridMap m = gridOf({
      "@.@",
      "...",
      "@.@",
  });
  for (const int first : {0, 1}) {
    const std::vector<NodeId> starts = {m.node(0, 1), m.node(1, 0)};
    Pibt p(m.graph, starts);
    p.setGoal(0, m.node(2, 1));
    p.setGoal(1, m.node(1, 2));
    p.setTaskPriority(static_cast<std::size_t>(first), 1);
    const auto& s1 = p.step();
    // The one with the higher task priority takes the crossing; the other waits.
    EXPECT_EQ(s1[static_cast<std::size_t>(first)], m.node(1, 1)) << "first " << first;
    EXPECT_EQ(s1[static_cast<std::size_t>(1 - first)], starts[static_cast<std::size_t>(1 - first)]);
    p.step();
    p.step();
    EXPECT_EQ(p.positions()[0], m.node(2, 1));
    EXPECT_EQ(p.positions()[1], m.node(1, 2));
  }
}

// A robot waiting at its place in a station's line has not reached anything: its goal is the
// place the line gives it, not where it is going. Agent 0 waits at the queue place q (line 0: q ->
// approach a -> dock) for 10 steps; agent 1 then drives 2 steps towards y through a, the line's
// approach. The place ahead frees and both want a: agent 0 has waited longer and goes first. (Its
// steps were counted from 0 again at every place it waited at, so through traffic took the line's
// next place every time: the head of a drop-off's line stood 36 s while robots from the next
// station's exit crossed in front of it; full stack, dense check, seed 29.)
TEST(Pibt, AnAgentWaitingInLineHasWaitedAndCrossesFirst) {
  Graph g;
  const NodeId q = g.addNode({0, 0});
  const NodeId a = g.addNode({1, 0});
  const NodeId dock = g.addNode({2, 0});
  const NodeId x2 = g.addNode({1, 3});
  const NodeId x1 = g.addNode({1, 2});
  const NodeId x = g.addNode({1, 1});
  const NodeId y = g.addNode({1, -1});
  for (const auto& [u, v] : {std::pair{q, a}, {a, dock}, {x2, x1}, {x1, x}, {x, a}, {a, y}}) {
    g.addEdge(u, v);
    g.addEdge(v, u);
  }
  const std::vector<NodeId> starts = {q, x2};
  Pibt p(g, starts);
  std::vector<std::int32_t> lineOf(g.size(), -1);
  std::vector<NodeId> forward(g.size(), kNoNode);
  lineOf[static_cast<std::size_t>(q)] = 0;
  lineOf[static_cast<std::size_t>(a)] = 0;
  forward[static_cast<std::size_t>(q)] = a;
  forward[static_cast<std::size_t>(a)] = dock;
  p.setLines(lineOf, forward);
  p.setLine(0, 0);
  p.setGoal(0, q);
  for (int k = 0; k < 10; ++k)
    p.step();
  EXPECT_EQ(p.elapsed(0), 10) << "waiting in line is not being done";
  p.setGoal(1, y);
  p.step();
  p.step();
  ASSERT_EQ(p.positions()[1], x);
  p.setGoal(0, a);
  const auto& next = p.step();
  EXPECT_EQ(next[0], a);
  EXPECT_EQ(next[1], x);
  p.setGoal(0, dock);
  for (int k = 0; k < 5 && p.positions()[0] != dock; ++k)
    p.step();
  ASSERT_EQ(p.positions()[0], dock);
  p.step();
  EXPECT_EQ(p.elapsed(0), 0) << "on the dock it is done";
}

TEST(Pibt, PriorityInheritancePushesAnIdleAgentAhead) {
  const GridMap m = gridOf({"......"});
  const std::vector<NodeId> starts = {m.node(0, 0), m.node(1, 0)};
  Pibt p(m.graph, starts);
  p.setGoal(0, m.node(4, 0));  // agent 1 has no goal and sits in the way
  std::vector<std::vector<NodeId>> plan;
  EXPECT_EQ(stepsUntilAllReached(p, 20, &plan), 4);  // no step lost to the idle agent
  EXPECT_EQ(p.positions()[1], m.node(5, 0));
  EXPECT_TRUE(checkPlan(m.graph, plan).empty());
}

// A push priced (PibtOptions::occupiedCost): agent 0 at A heads for G by B (1.0 s from G, agent 1
// standing there without a goal) or by C (1.1 s from G, free). Plain PIBT ranks B first and pushes
// agent 1 off it; priced at 0.5 s, the free way wins and agent 1 stays where it is.
TEST(Pibt, APricedPushLetsAFreeWayNearlyAsShortWin) {
  Graph g;
  const NodeId a = g.addNode({0.0, 0.0});
  const NodeId b = g.addNode({1.0, 0.0});
  const NodeId c = g.addNode({1.0, -1.0});
  const NodeId goal = g.addNode({2.0, 0.0});
  const NodeId aside = g.addNode({1.0, 1.0});
  for (const auto& [u, v, s] :
       {std::tuple{a, b, 1.0}, {b, goal, 1.0}, {a, c, 1.2}, {c, goal, 1.1}, {b, aside, 1.0}}) {
    g.addEdge(u, v, s);
    g.addEdge(v, u, s);
  }
  for (const float price : {0.0F, 0.5F}) {
    PibtOptions o;
    o.occupiedCost = price;
    const std::vector<NodeId> starts = {a, b};
    Pibt p(g, starts, o);
    p.setGoal(0, goal);
    const auto& next = p.step();
    if (price == 0.0F) {
      EXPECT_EQ(next[0], b);
      EXPECT_NE(next[1], b) << "pushed off";
    } else {
      EXPECT_EQ(next[0], c);
      EXPECT_EQ(next[1], b) << "left standing";
    }
    const auto path = walkToGoal(g, p, 10);
    ASSERT_FALSE(path.empty());
    EXPECT_EQ(path.back(), g.position(goal)) << "price " << price;
  }
}

TEST(Pibt, HeadOnInACorridorOneBacksOutAndBothGetThrough) {
  // A one-cell corridor between two rooms: the agent of lower priority backs out of it.
  const GridMap m = gridOf({
      "...@@@@...",
      "..........",
      "...@@@@...",
  });
  const std::vector<NodeId> starts = {m.node(3, 1), m.node(6, 1)};
  Pibt p(m.graph, starts);
  p.setGoal(0, m.node(9, 1));
  p.setGoal(1, m.node(0, 1));
  std::vector<std::vector<NodeId>> plan;
  const int t = stepsUntilAllReached(p, 100, &plan);
  EXPECT_GT(t, 0);
  EXPECT_LT(t, 30);
  EXPECT_TRUE(checkPlan(m.graph, plan).empty()) << firstViolations(checkPlan(m.graph, plan));
}

// The case plain PIBT cannot leave: a dead-end spur off a corridor. Agent 0 is at the end of the
// spur and wants out; agent 1, of higher priority, stands at the spur's first cell and wants the end.
// Agent 1 tries the end, pushes agent 0, which has nowhere to go but agent 1's cell (a swap), so
// agent 1 stays where it is, its next best node, and nothing ever changes.
TEST(Pibt, DeadEndSpurStallsPlainPibtButNotWithEscape) {
  const GridMap m = gridOf({
      ".........",
      ".........",
      "@@@@.@@@@",
      "@@@@.@@@@",
  });
  const NodeId end = m.node(4, 3);
  const NodeId first = m.node(4, 2);
  int worst = 0;
  for (std::uint64_t seed = 1; seed <= 20; ++seed) {
    const std::vector<NodeId> starts = {end, first};
    for (const bool escape : {false, true}) {
      PibtOptions o = escape ? PibtOptions{} : plain();
      o.seed = seed;
      Pibt p(m.graph, starts, o);
      p.setGoal(0, m.node(0, 0));
      p.setGoal(1, end);
      p.setTaskPriority(1, 1);
      std::vector<std::vector<NodeId>> plan;
      const int t = stepsUntilAllReached(p, 1000, &plan);
      EXPECT_TRUE(checkPlan(m.graph, plan).empty()) << firstViolations(checkPlan(m.graph, plan));
      if (!escape) {
        EXPECT_EQ(t, -1) << "seed " << seed;
        EXPECT_EQ(p.positions(), starts) << "plain PIBT never moves either agent";
      } else {
        EXPECT_GT(t, 0) << "seed " << seed;
        EXPECT_GE(p.stats().escalations, 1U);
        worst = std::max(worst, t);
      }
    }
  }
  // Escalation waits escapeAfter (16) steps of standing still, then the way out takes ~10 steps.
  EXPECT_LT(worst, 200);
}

// A station at the end of a one-cell spur with a queue: the robot at the station wants out, three
// robots of higher priority want in, one after the other (each leaves for a far corner once there).
TEST(Pibt, StationSpurWithAQueueServesEveryoneOnlyWithEscape) {
  const GridMap m = gridOf({
      ".........",
      ".........",
      ".........",
      "@@@@.@@@@",
  });
  const NodeId station = m.node(4, 3);
  for (const bool escape : {false, true}) {
    PibtOptions o = escape ? PibtOptions{} : plain();
    const std::vector<NodeId> starts = {station, m.node(4, 2), m.node(3, 2), m.node(5, 2)};
    Pibt p(m.graph, starts, o);
    p.setGoal(0, m.node(0, 0));
    for (std::size_t i = 1; i < 4; ++i) {
      p.setGoal(i, station);
      p.setTaskPriority(i, 1);
    }
    std::vector<std::vector<NodeId>> plan{starts};
    int served = 0;
    int lastServed = -1;
    for (int t = 1; t <= 600; ++t) {
      const auto& next = p.step();
      plan.push_back(next);
      for (std::size_t i = 1; i < 4; ++i) {
        if (next[i] == station && p.goal(i) == station) {
          ++served;
          lastServed = t;
          p.setGoal(i, m.node(8, 0));  // done at the station: off to a far corner, no priority left
          p.setTaskPriority(i, 0);
        }
      }
    }
    EXPECT_TRUE(checkPlan(m.graph, plan).empty()) << firstViolations(checkPlan(m.graph, plan));
    if (escape) {
      EXPECT_EQ(served, 3);
      EXPECT_LT(lastServed, 300);
    } else {
      EXPECT_EQ(served, 0);
    }
  }
}

/// A parking place off a one-line lane, as the small warehouse's parking row: the dock D, its
/// approach A (the only way out, joined to the three lane nodes in front), lane nodes 0.5 m apart
/// that exclude the lane within 1 m. A robot standing in the dock excludes the lane nodes in front
/// of it and the approach; a robot on the approach excludes the lane within 1.25 m.
struct DockOffALane {
  Graph graph;
  std::vector<NodeId> lane;   // x = 0, 0.5, ..., 5 at y = 1.75
  NodeId dock = kNoNode;      // (3, 0.9)
  NodeId approach = kNoNode;  // (3, 1.9)
};

DockOffALane dockOffALane() {
  DockOffALane d;
  Graph& g = d.graph;
  for (int i = 0; i <= 10; ++i)
    d.lane.push_back(g.addNode({0.5 * i, 1.75}));
  d.dock = g.addNode({3.0, 0.9});
  d.approach = g.addNode({3.0, 1.9});
  const double step = 0.625;  // 0.5 m at 0.8 m/s
  for (std::size_t i = 0; i + 1 < d.lane.size(); ++i) {
    g.addEdge(d.lane[i], d.lane[i + 1], step);
    g.addEdge(d.lane[i + 1], d.lane[i], step);
  }
  g.addEdge(d.dock, d.approach, step);
  g.addEdge(d.approach, d.dock, step);
  for (const std::size_t i : {5U, 6U, 7U}) {
    g.addEdge(d.approach, d.lane[i], step);
    g.addEdge(d.lane[i], d.approach, step);
  }
  for (std::size_t i = 0; i < d.lane.size(); ++i) {
    for (std::size_t j = i + 1; j < d.lane.size() && j <= i + 2; ++j)
      g.addConflict(d.lane[i], d.lane[j]);
  }
  for (std::size_t i = 4; i <= 8; ++i)
    g.addConflict(d.approach, d.lane[i]);
  g.addConflict(d.dock, d.approach);
  g.addConflict(d.dock, d.lane[6]);
  g.addConflict(d.dock, d.lane[7]);
  return d;
}

// The knot of the virtual fleet's parking row (20 robots, seed 1: four such pairs stood for the
// whole 600 s). Robot 0 is parked in the dock and wants east along the lane; robot 1 stands on the
// lane just west of the dock's front and wants east too. Robot 1's way east is excluded by the
// parked robot, the parked robot's only way out (the approach) by robot 1. Each waits for the
// other: a cycle, so the escape escalates one of them, but that does not help either way: robot 1's
// every single move (one node west, or east) is still excluded by the approach, and the parked
// robot cannot move while robot 1 stands where it does. Only two moves west of robot 1 and then the
// parked robot's way out untie it, which a search over a few steps of both finds.
TEST(Pibt, ARobotParkedBehindOneOnTheLaneGetsOutOnlyByUntangling) {
  const DockOffALane d = dockOffALane();
  const Graph& g = d.graph;
  const std::vector<NodeId> starts{d.dock, d.lane[5]};
  ASSERT_TRUE(g.conflicting(d.approach, d.lane[5]));  // robot 1 shuts the way out
  ASSERT_TRUE(g.conflicting(d.dock, d.lane[6]));      // the parked robot shuts robot 1's way east
  for (const NodeId v : {d.lane[4], d.lane[6]})
    ASSERT_TRUE(g.conflicting(d.approach, v));  // no single move of robot 1 clears the way out
  for (std::uint64_t seed = 1; seed <= 10; ++seed) {
    for (const bool untangling : {false, true}) {
      PibtOptions o;
      o.seed = seed;
      if (!untangling)
        o.untangleGroup = 0;  // PIBT with its escape (escalation) only: the planner before the search
      Pibt p(g, starts, o);
      p.setGoal(0, d.lane[10]);
      p.setGoal(1, d.lane[7]);
      std::vector<std::vector<NodeId>> plan;
      const int t = stepsUntilAllReached(p, 400, &plan);
      EXPECT_TRUE(checkPlan(g, plan).empty()) << firstViolations(checkPlan(g, plan));
      if (!untangling) {
        EXPECT_EQ(t, -1) << "seed " << seed;
        EXPECT_EQ(p.positions(), starts) << "seed " << seed << ": escalation alone moves neither";
        EXPECT_GE(p.stats().escalations, 1U);
      } else {
        // 16 steps of standing still tell the knot from a wait; then 3 moves out and ~8 east.
        EXPECT_GT(t, 0) << "seed " << seed;
        EXPECT_LT(t, 60) << "seed " << seed;
        EXPECT_GE(p.stats().untangles, 1U);
        EXPECT_EQ(p.stats().untangleAborts, 0U);
      }
    }
  }
}

// A way out of a knot moves a member only where its filter lets it: a robot waiting in a station's
// line moves forward along it, never sideways out of it (sent sideways it lost its place in the
// line: full stack, 40 robots, seed 13, a robot stood 71 s at its line's tail). Robot 1 wants to
// pass where robot 0 stands; robot 0 has three ways to make room.
TEST(Untangle, AMemberMovesOnlyWhereItsFilterAllows) {
  Graph g;
  const NodeId x = g.addNode({0, 0});
  const NodeId b = g.addNode({1, 0});
  const NodeId goal = g.addNode({2, 0});
  const NodeId side = g.addNode({1, 1});
  const NodeId forward = g.addNode({1, -1});
  for (const NodeId v : {x, goal, side, forward}) {
    g.addEdge(b, v);
    g.addEdge(v, b);
  }
  const std::vector<float> toGoal{2, 1, 0, 2, 2};
  UntangleProblem p;
  p.starts = {b, x};
  p.tables = {nullptr, toGoal.data()};
  p.counts = {0, 1};
  p.clearOfOthers = [](NodeId) { return true; };
  const auto robot0Visits = [&](const UntangleResult& r) {
    std::vector<NodeId> at;
    for (const auto& config : r.steps)
      at.push_back(config[0]);
    return at;
  };
  // Unfiltered, the first way found sends robot 0 on to the goal's node.
  const auto free = untangle(g, p);
  ASSERT_TRUE(free.has_value());
  EXPECT_EQ(free->improved, 1U);
  EXPECT_EQ(robot0Visits(*free), (std::vector<NodeId>{b, goal, goal}));
  // Only forward: robot 0 makes room there and nowhere else.
  p.mayMove = [&](std::size_t member, NodeId from, NodeId to) {
    return member != 0 || (from == b && to == forward);
  };
  const auto ahead = untangle(g, p);
  ASSERT_TRUE(ahead.has_value());
  EXPECT_EQ(robot0Visits(*ahead), (std::vector<NodeId>{b, forward, forward}));
  // Its forward way shut: no way out, rather than one that takes it out of its line.
  p.mayMove = [&](std::size_t member, NodeId, NodeId) { return member != 0; };
  EXPECT_FALSE(untangle(g, p).has_value());
}

TEST(Pibt, FixedAgentsAreObstaclesThatNeverMove) {
  const GridMap m = gridOf({
      "........",
      "........",
  });
  const std::vector<NodeId> starts = {m.node(0, 0), m.node(3, 0), m.node(7, 1)};
  Pibt p(m.graph, starts);
  p.setControlled(1, false);  // stopped in the top lane
  p.setGoal(0, m.node(7, 0));
  p.setGoal(2, m.node(3, 0));  // wants the fixed agent's node: waits next to it, never pushes it
  std::vector<std::vector<NodeId>> plan{starts};
  for (int t = 0; t < 40; ++t) {
    plan.push_back(p.step());
    EXPECT_EQ(p.positions()[1], m.node(3, 0));
  }
  EXPECT_EQ(p.positions()[0], m.node(7, 0));  // drove round it through the bottom lane
  EXPECT_TRUE(checkPlan(m.graph, plan).empty());
  // Back under control, it is an ordinary agent that can be pushed.
  p.setControlled(1, true);
  for (int t = 0; t < 20; ++t) {
    p.step();
  }
  EXPECT_EQ(p.positions()[2], m.node(3, 0));
}

TEST(Pibt, ClosedNodesAreNotEnteredButCanBeLeft) {
  GridMap m = gridOf({
      ".....",
      ".....",
  });
  m.graph.setOpen(m.node(2, 0), false);
  m.graph.setOpen(m.node(0, 1), false);
  const std::vector<NodeId> starts = {m.node(0, 0), m.node(0, 1)};
  Pibt p(m.graph, starts);
  p.setGoal(0, m.node(4, 0));
  p.setGoal(1, m.node(4, 1));  // starts on a closed node: must be allowed to drive off it
  std::vector<std::vector<NodeId>> plan;
  EXPECT_GT(stepsUntilAllReached(p, 40, &plan), 0);
  for (std::size_t t = 1; t < plan.size(); ++t) {
    for (const NodeId v : plan[t]) {
      EXPECT_NE(v, m.node(2, 0));
    }
  }
  EXPECT_EQ(plan[1][1], m.node(1, 1));
  // Reopened and told so, the shorter way through it is taken again.
  m.graph.setOpen(m.node(2, 0), true);
  p.graphChanged();
  p.setGoal(0, m.node(0, 0));
  p.setGoal(1, m.node(4, 0));
  p.step();
  p.step();
  EXPECT_EQ(p.positions()[0], m.node(2, 0));
}

// The risk map's weight: a costly band on the short way sends the agent round by the long one;
// without it the short way is taken.
TEST(Pibt, AgentsGoRoundCostlyNodesWhenTheDetourIsCheaper) {
  const GridMap m = gridOf({
      ".....",
      ".@@@.",
      ".....",
  });
  auto route = [&](const std::vector<float>& cost) {
    Pibt p(m.graph, std::vector<NodeId>{m.node(0, 0)});
    p.setNodeCost(cost);
    p.setGoal(0, m.node(4, 0));
    std::vector<NodeId> visited;
    for (int t = 0; t < 20 && p.positions()[0] != m.node(4, 0); ++t) {
      p.step();
      visited.push_back(p.positions()[0]);
    }
    EXPECT_EQ(p.positions()[0], m.node(4, 0));
    return visited;
  };
  const auto straight = route({});
  EXPECT_EQ(straight.size(), 4U) << "the top row, 4 steps";
  std::vector<float> cost(m.graph.size(), 0.0F);
  cost[static_cast<std::size_t>(m.node(2, 0))] = 5.0F;  // a person's predicted disc on the top row
  const auto round = route(cost);
  EXPECT_EQ(round.size(), 8U) << "down, along the bottom row and up";
  EXPECT_EQ(std::count(round.begin(), round.end(), m.node(2, 0)), 0);
  cost[static_cast<std::size_t>(m.node(2, 0))] = 1.0F;  // cheaper than the 4 steps more of the detour
  EXPECT_EQ(route(cost).size(), 4U);
}

TEST(Pibt, StartsAndMovesThatConflictAreRefused) {
  const GridMap m = gridOf({"...."});
  const std::vector<NodeId> same = {0, 0};
  EXPECT_THROW(Pibt(m.graph, same), std::invalid_argument);
  const std::vector<NodeId> invalid = {0, 99};
  EXPECT_THROW(Pibt(m.graph, invalid), std::invalid_argument);
  const Graph wide = wideRobots(m);
  const std::vector<NodeId> neighbours = {0, 1};
  EXPECT_THROW(Pibt(wide, neighbours), std::invalid_argument);
  const std::vector<NodeId> apart = {0, 2};
  Pibt p(wide, apart);
  EXPECT_FALSE(p.setPosition(0, 3));  // next to agent 1
  EXPECT_FALSE(p.setPosition(0, 17));
  EXPECT_TRUE(p.setPosition(1, 3));
  EXPECT_EQ(p.positions(), (std::vector<NodeId>{0, 3}));
  EXPECT_THROW(p.setGoal(0, 42), std::invalid_argument);
}

TEST(Pibt, RotationsAreTheMapfConventionOnlyWhenAllowed) {
  // Four agents fill a 2 x 2 map, each wanting the next cell clockwise: only a rotation moves them.
  const GridMap m = gridOf({"..", ".."});
  const std::vector<NodeId> starts = {m.node(0, 0), m.node(1, 0), m.node(1, 1), m.node(0, 1)};
  for (const auto rot : {Rotations::kAllow, Rotations::kCancel, Rotations::kAvoid}) {
    PibtOptions o;
    o.rotations = rot;
    Pibt p(m.graph, starts, o);
    for (std::size_t i = 0; i < 4; ++i) {
      p.setGoal(i, starts[(i + 1) % 4]);
    }
    const std::vector<std::vector<NodeId>> plan = {starts, p.step()};
    if (rot == Rotations::kAllow) {
      EXPECT_EQ(plan[1], (std::vector<NodeId>{starts[1], starts[2], starts[3], starts[0]}));
      EXPECT_FALSE(checkPlan(m.graph, plan).empty());
    } else {
      EXPECT_EQ(plan[1], starts);
      EXPECT_TRUE(checkPlan(m.graph, plan).empty());
      // kCancel gets there by planning the rotation and stopping it; kAvoid never plans it.
      EXPECT_EQ(p.stats().rotationStops, rot == Rotations::kCancel ? 4U : 0U);
    }
  }
}

TEST(Pibt, RandomMapsThousandsOfLifelongStepsWithoutConflicts) {
  std::mt19937_64 rng(11);
  std::size_t steps = 0;
  for (int round = 0; round < 12; ++round) {
    const GridMap m = randomMap(14 + round % 5, 12 + round % 4, 0.15 + 0.02 * (round % 6), rng);
    const std::size_t agents = std::max<std::size_t>(2, m.freeCells() * (5 + round % 20) / 100);
    for (const auto rot : {Rotations::kAvoid, Rotations::kCancel, Rotations::kAllow}) {
      PibtOptions o;
      o.rotations = rot;
      o.escapeAfter = round % 3 == 0 ? 0 : 8;
      const auto run = runLifelong(m.graph, agents, 500, 100 + static_cast<std::uint64_t>(round), o,
                                   round % 2 == 0 ? 0.05 : 0.0);
      const auto v = checkPlan(m.graph, run.configs, {.rotations = rot != Rotations::kAllow});
      EXPECT_TRUE(v.empty()) << "round " << round << ": " << firstViolations(v);
      if (rot == Rotations::kAvoid) {
        // The pass behind kAvoid is a net: if it ever stops anyone, the planner closed a cycle.
        EXPECT_EQ(run.stats.rotationStops, 0U) << "round " << round;
      }
      steps += run.configs.size() - 1;
    }
  }
  EXPECT_GE(steps, 18000U);
}

TEST(Pibt, WideRobotsOnAGraphWithConflictSetsNeverConflict) {
  std::mt19937_64 rng(5);
  for (int round = 0; round < 8; ++round) {
    const GridMap m = randomMap(14, 14, 0.1, rng);
    const Graph wide = wideRobots(m, round % 2 == 0);
    for (const auto rot : {Rotations::kAvoid, Rotations::kAllow}) {
      PibtOptions o;
      o.rotations = rot;
      o.escapeAfter = round % 4 < 2 ? 16 : 0;
      const auto run = runLifelong(wide, 8, 1000, 40 + static_cast<std::uint64_t>(round), o, 0.02);
      const auto v = checkPlan(wide, run.configs);
      EXPECT_TRUE(v.empty()) << "round " << round << ": " << firstViolations(v);
      EXPECT_EQ(run.stats.rotationStops, 0U);
    }
  }
}

// Robots that exclude the four cells around them on an open floor: in about half of these runs
// plain PIBT locks some of them against each other for good (each wants through the other and the
// one of higher priority will not step aside); with the escape every robot keeps reaching goals.
TEST(Pibt, WideRobotsKeepReachingGoalsOnlyWithEscape) {
  const GridMap m = gridOf(std::vector<std::string>(14, std::string(14, '.')));
  const Graph wide = wideRobots(m, false);
  int plainLocked = 0;
  for (std::uint64_t seed = 40; seed < 48; ++seed) {
    const auto plainRun = runLifelong(wide, 8, 1500, seed, plain());
    const auto escapeRun = runLifelong(wide, 8, 1500, seed, {});
    EXPECT_TRUE(checkPlan(wide, escapeRun.configs).empty());
    const int plainLeast = *std::min_element(plainRun.reached.begin(), plainRun.reached.end());
    const int least = *std::min_element(escapeRun.reached.begin(), escapeRun.reached.end());
    EXPECT_GE(least, 50) << "seed " << seed;
    plainLocked += plainLeast < 20 ? 1 : 0;
    std::printf("seed %llu: fewest goals of a robot, plain %d, with escape %d\n",
                static_cast<unsigned long long>(seed), plainLeast, least);
  }
  EXPECT_GE(plainLocked, 4) << "plain PIBT locks robots in half of these runs (5 of 8 when written)";
}

TEST(Pibt, EveryAgentKeepsReachingGoalsOnBiconnectedGraphs) {
  const GridMap open = gridOf(
      {"........", "........", "........", "........", "........", "........", "........", "........"});
  auto shelves = parseGridMap(warehouseMapText({3, 3, 4, 1, 1}), "small warehouse");
  ASSERT_TRUE(shelves.has_value());
  for (const GridMap* m : {&open, static_cast<const GridMap*>(&*shelves)}) {
    for (const auto rot : {Rotations::kAvoid, Rotations::kAllow}) {
      PibtOptions o;
      o.rotations = rot;
      const std::size_t agents = m->freeCells() / 4;
      const auto run = runLifelong(m->graph, agents, 3000, 9, o);
      EXPECT_TRUE(checkPlan(m->graph, run.configs, {.rotations = rot != Rotations::kAllow}).empty());
      const int least = *std::min_element(run.reached.begin(), run.reached.end());
      EXPECT_GE(least, 10) << m->source << " " << static_cast<int>(rot);
    }
  }
}

TEST(Pibt, SameSeedSamePlanAnotherSeedAnotherPlan) {
  std::mt19937_64 rng(21);
  const GridMap m = randomMap(20, 16, 0.2, rng);
  const auto a = runLifelong(m.graph, 40, 400, 7, {});
  const auto b = runLifelong(m.graph, 40, 400, 7, {});
  const auto c = runLifelong(m.graph, 40, 400, 8, {});
  EXPECT_EQ(a.configs, b.configs);
  EXPECT_NE(a.configs, c.configs);
  // Only the planner's own seed differs: same starts and goals drawn by the driver, other ties.
  const auto sameStarts = [&](std::uint64_t plannerSeed) {
    std::vector<NodeId> starts(40);
    std::iota(starts.begin(), starts.end(), 0);
    PibtOptions o;
    o.seed = plannerSeed;
    Pibt p(m.graph, starts, o);
    for (std::size_t i = 0; i < 40; ++i) {
      p.setGoal(i, static_cast<NodeId>(m.freeCells() - 1 - i));
    }
    std::vector<std::vector<NodeId>> plan;
    for (int t = 0; t < 60; ++t) {
      plan.push_back(p.step());
    }
    return plan;
  };
  EXPECT_EQ(sameStarts(1), sameStarts(1));
  EXPECT_NE(sameStarts(1), sameStarts(2));
}
