// Safe intervals, the single-robot search over them (SIPP with headings) and prioritized planning:
// the search against a plain search over every quarter second, the plans against an independent
// pairwise check of the robots' occupancy.

#include "fleet/traffic/sipp.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <numeric>
#include <random>
#include <stdexcept>

#include "fleet/traffic/prioritized_planner.hpp"
#include "fleet/traffic/safe_intervals.hpp"
#include "pibt_test_support.hpp"
#include "roadmap_test_support.hpp"

using namespace fleet;
using namespace fleet::traffic;

namespace {

/// Nodes 0..n-1 on a line 1 m apart, joined both ways by 1 s edges.
Graph lineGraph(int n) {
  Graph g;
  for (int i = 0; i < n; ++i)
    g.addNode({static_cast<double>(i), 0.0});
  for (int i = 0; i + 1 < n; ++i) {
    g.addEdge(i, i + 1, 1.0);
    g.addEdge(i + 1, i, 1.0);
  }
  return g;
}

/// A 3 x 3 grid 1 m apart (node y * 3 + x), 4-connected by 1 s edges both ways.
Graph threeByThree() {
  Graph g;
  for (int y = 0; y < 3; ++y)
    for (int x = 0; x < 3; ++x)
      g.addNode({static_cast<double>(x), static_cast<double>(y)});
  for (int y = 0; y < 3; ++y) {
    for (int x = 0; x < 3; ++x) {
      const int v = y * 3 + x;
      if (x + 1 < 3) {
        g.addEdge(v, v + 1, 1.0);
        g.addEdge(v + 1, v, 1.0);
      }
      if (y + 1 < 3) {
        g.addEdge(v, v + 3, 1.0);
        g.addEdge(v + 3, v, 1.0);
      }
    }
  }
  return g;
}

/// Turning on the spot: none straight on, 0.5 s for a bend, 1 s to go back the way it came.
Sipp::TurnTime quarterTurns(const Graph& g) {
  return [&g](NodeId prev, NodeId at, NodeId next) {
    const Vec2 a = g.position(at) - g.position(prev);
    const Vec2 b = g.position(next) - g.position(at);
    const double c = a.dot(b) / (a.norm() * b.norm());
    return c > 0.99 ? 0.0 : (c < -0.99 ? 1.0 : 0.5);
  };
}

/// The earliest arrival by a plain search over every quarter second (waits of 0.25 s), with the
/// same occupancy rule: standing (and turning) on its node until it has arrived at the next, the
/// next occupied from the moment it starts into it. -1: not within `horizon` s.
double earliestByTimeSteps(const Graph& g, const ReservationTable& t, const Sipp::TurnTime& turn,
                           NodeId start, NodeId goal, double hold, double horizon) {
  constexpr double kStep = 0.25;
  const auto steps = static_cast<int>(horizon / kStep);
  // reached[k]: (node, from) states reached at step k.
  std::vector<std::map<std::pair<NodeId, NodeId>, bool>> reached(static_cast<std::size_t>(steps) + 64);
  if (t.safe(start, 0.0).front().from > 0.0)
    return -1.0;  // the start is not safe at first
  reached[0][{start, kNoNode}] = true;
  for (int k = 0; k <= steps; ++k) {
    const double now = k * kStep;
    for (const auto& [state, unused] : reached[static_cast<std::size_t>(k)]) {
      const auto [v, from] = state;
      if (v == goal && t.safeOver(goal, now, hold))
        return now;
      if (t.safeOver(v, now, now + kStep))
        reached[static_cast<std::size_t>(k) + 1][state] = true;
      for (const Edge& e : g.edges(v)) {
        const double tau = (turn && from != kNoNode) ? turn(from, v, e.to) : 0.0;
        const double depart = now + tau;
        const double arrive = depart + e.duration;
        if (!t.safeOver(v, now, arrive) || !t.safeOver(e.to, depart, arrive))
          continue;
        const auto at = static_cast<std::size_t>(std::lround(arrive / kStep));
        if (at < reached.size())
          reached[at][{e.to, v}] = true;
      }
    }
  }
  return -1.0;
}

/// Independent check of a multi-robot timed plan: no two robots occupy conflicting nodes at once
/// (open overlap; occupancy as safe_intervals.hpp defines it) before `until`. Empty: none.
std::string pairwiseConflict(const Graph& g, const std::vector<TimedPath>& paths, double until) {
  for (std::size_t a = 0; a < paths.size(); ++a) {
    const auto oa = occupancy(paths[a]);
    for (std::size_t b = a + 1; b < paths.size(); ++b) {
      const auto ob = occupancy(paths[b]);
      for (std::size_t i = 0; i < oa.size(); ++i) {
        for (std::size_t j = 0; j < ob.size(); ++j) {
          const NodeId u = paths[a][i].node;
          const NodeId v = paths[b][j].node;
          if (u != v && !g.conflicting(u, v))
            continue;
          const double from = std::max(oa[i].from, ob[j].from);
          const double to = std::min({oa[i].to, ob[j].to, until});
          if (from < to) {
            return "robots " + std::to_string(a) + " and " + std::to_string(b) + " on " + std::to_string(u) +
                   " / " + std::to_string(v) + " over [" + std::to_string(from) + ", " + std::to_string(to) +
                   "]";
          }
        }
      }
    }
  }
  return {};
}

}  // namespace

TEST(SafeIntervals, OccupancyRunsFromEnteringANodeToArrivingAtTheNext) {
  const TimedPath p{{0, 0.0, 0.0, 1.0}, {1, 1.0, 2.0, 2.5}, {2, 2.5, 3.5, kForever}};
  const auto occ = occupancy(p);
  ASSERT_EQ(occ.size(), 3U);
  EXPECT_EQ(occ[0].from, 0.0);
  EXPECT_EQ(occ[0].to, 2.0);  // until it has arrived at node 1
  EXPECT_EQ(occ[1].from, 1.0);
  EXPECT_EQ(occ[1].to, 3.5);
  EXPECT_EQ(occ[2].to, kForever);
}

TEST(SafeIntervals, AReservationSpreadsOverTheConflictsAndTheSafeIntervalsAreItsComplement) {
  Graph g = lineGraph(4);
  g.addConflict(1, 2);
  ReservationTable t(g);
  t.reserve(1, {2.0, 4.0}, 0);
  t.reserve(1, {4.0, 5.0}, 1);  // touching: merged
  t.reserve(1, {8.0, 9.0});
  const auto s2 = t.safe(2);
  ASSERT_EQ(s2.size(), 3U);
  EXPECT_EQ(s2[0].from, 0.0);
  EXPECT_EQ(s2[0].to, 2.0);
  EXPECT_EQ(s2[1].from, 5.0);
  EXPECT_EQ(s2[1].to, 8.0);
  EXPECT_EQ(s2[2].from, 9.0);
  EXPECT_EQ(s2[2].to, kForever);
  EXPECT_EQ(t.unsafe(2).size(), 2U);
  EXPECT_TRUE(t.safe(0).size() == 1 && t.safe(0)[0].from == 0.0);  // no conflict with 1
  EXPECT_TRUE(t.safeOver(2, 5.0, 8.0));                            // touching ends allowed
  EXPECT_FALSE(t.safeOver(2, 4.9, 5.5));
  EXPECT_EQ(t.safe(2, 6.0).front().from, 6.0);
  t.release(0);  // owner 0's [2, 4] goes, owner 1's and nobody's stay
  ASSERT_EQ(t.safe(2).size(), 3U);
  EXPECT_EQ(t.safe(2)[0].to, 4.0);
  EXPECT_EQ(t.firstConflict(TimedPath{{0, 0.0, 0.0, 7.0}, {1, 7.0, 8.5, kForever}}), 1);
  EXPECT_EQ(t.firstConflict(TimedPath{
                {0, 0.0, 0.0, 5.0}, {1, 5.0, 6.0, 6.0}, {2, 6.0, 7.0, 7.5}, {3, 7.5, 8.0, kForever}}),
            -1);
}

TEST(Sipp, AloneItDrivesTheShortestWayWithItsTurns) {
  // A 3 x 3 grid: from a corner to the opposite one, one bend (0.5 s) on the way.
  const Graph g = threeByThree();
  Sipp sipp(g, quarterTurns(g));
  ReservationTable t(g);
  const auto p = sipp.plan(t, {0, kNoNode, 0.0, 8});
  ASSERT_TRUE(p.has_value());
  EXPECT_DOUBLE_EQ(p->back().arrive, 4.5);
  EXPECT_EQ(p->front().node, 0);
  EXPECT_EQ(p->back().node, 8);
  EXPECT_EQ(p->back().leave, kForever);
  EXPECT_NEAR(sipp.drivingTime(0, 8), 4.5, 1e-4);  // the heuristic: its bend included
  EXPECT_LE(sipp.drivingTime(0, 8), 4.5);          // never above the real time
  // Having come from 0, it must turn round (1 s) to go back there.
  const auto back = sipp.plan(t, {1, 0, 0.0, 0});
  ASSERT_TRUE(back.has_value());
  EXPECT_DOUBLE_EQ(back->back().arrive, 2.0);
  EXPECT_DOUBLE_EQ(back->front().leave, 1.0);
}

// A node's cost (the risk map's, a yield's) is planned as time on the edges into it: the robot goes
// round a dear node when that is sooner, and through it as if slowly otherwise.
TEST(Sipp, ADearNodeIsGoneRoundWhenThatIsSoonerAndDrivenThroughAsTimeOtherwise) {
  // A 3 x 3 grid; from 0 to 2 along the bottom row through 1 (2 s), or round by 3, 4, 5 (4 edges and
  // two bends: 5 s).
  const Graph g = threeByThree();
  Sipp sipp(g, quarterTurns(g));
  ReservationTable t(g);
  const auto through = [](const TimedPath& p, NodeId v) {
    return std::any_of(p.begin(), p.end(), [&](const TimedNode& n) { return n.node == v; });
  };
  const auto plain = sipp.plan(t, {0, kNoNode, 0.0, 2});
  ASSERT_TRUE(plain.has_value());
  EXPECT_DOUBLE_EQ(plain->back().arrive, 2.0);
  EXPECT_TRUE(through(*plain, 1));
  std::vector<float> cost(9, 0.0F);
  cost[1] = 10.0F;
  EXPECT_TRUE(sipp.setNodeCost(cost));
  EXPECT_FALSE(sipp.setNodeCost(cost));            // the same costs change nothing
  EXPECT_NEAR(sipp.drivingTime(0, 2), 2.0, 1e-4);  // the goal's table is driving time alone
  const auto round = sipp.plan(t, {0, kNoNode, 0.0, 2});
  ASSERT_TRUE(round.has_value());
  EXPECT_DOUBLE_EQ(round->back().arrive, 5.0);
  EXPECT_FALSE(through(*round, 1));
  cost[1] = 2.0F;  // through it (1 + 2 s, then 1 s) is sooner than round
  EXPECT_TRUE(sipp.setNodeCost(cost));
  const auto slow = sipp.plan(t, {0, kNoNode, 0.0, 2});
  ASSERT_TRUE(slow.has_value());
  EXPECT_DOUBLE_EQ(slow->back().arrive, 4.0);
  ASSERT_TRUE(through(*slow, 1));
  EXPECT_DOUBLE_EQ((*slow)[1].arrive - (*slow)[1].enter, 3.0);  // its reservation the longer
  // No cost anywhere is no cost at all.
  EXPECT_TRUE(sipp.setNodeCost(std::vector<float>(9, 0.0F)));
  EXPECT_DOUBLE_EQ(sipp.plan(t, {0, kNoNode, 0.0, 2})->back().arrive, 2.0);
}

// Cross-check: costs searched as time find the same arrivals as a graph whose edges into each node
// take that much longer (random graphs with conflicts, reservations and turns; every other graph
// without costs, as a control), though their goals' tables leave the costs out.
TEST(Sipp, NodeCostsPlanAsAGraphWithLongerEdgesInto) {
  std::mt19937_64 rng(23);
  int found = 0;
  for (int trial = 0; trial < 60; ++trial) {
    Graph g = test::randomDigraph(14, 4, false, rng);
    std::uniform_int_distribution<int> node(0, 13);
    std::uniform_int_distribution<int> quarter(0, 12);
    std::vector<float> cost(14, 0.0F);
    for (auto& c : cost)
      c = trial % 2 == 0 ? 0.25F * static_cast<float>(quarter(rng)) : 0.0F;
    Graph longer;
    for (NodeId v = 0; v < 14; ++v)
      longer.addNode(g.position(v));
    for (NodeId v = 0; v < 14; ++v) {
      for (const Edge& e : g.edges(v))
        longer.addEdge(v, e.to, e.duration + static_cast<double>(cost[static_cast<std::size_t>(e.to)]));
    }
    for (int c = 0; c < 4; ++c) {
      const int a = node(rng);
      const int b = node(rng);
      if (a != b) {
        g.addConflict(a, b);
        longer.addConflict(a, b);
      }
    }
    const NodeId start = node(rng);
    const NodeId goal = (start + 1 + node(rng) % 13) % 14;
    ReservationTable t(g), tl(longer);
    for (int r = 0; r < 8; ++r) {
      const NodeId v = node(rng);
      const double from = 0.25 * quarter(rng);
      if (v == start || g.conflicting(v, start))
        continue;
      t.reserve(v, {from, from + 2.0});
      tl.reserve(v, {from, from + 2.0});
    }
    Sipp costed(g, quarterTurns(g));
    costed.setNodeCost(cost);
    Sipp plain(longer, quarterTurns(longer));
    const auto a = costed.plan(t, {start, kNoNode, 0.0, goal});
    const auto b = plain.plan(tl, {start, kNoNode, 0.0, goal});
    ASSERT_EQ(a.has_value(), b.has_value()) << "trial " << trial;
    if (a) {
      ++found;
      EXPECT_NEAR(a->back().arrive, b->back().arrive, 1e-6) << "trial " << trial;
    }
  }
  EXPECT_GT(found, 20);
}

TEST(Sipp, AloneOnALargeGridItSearchesAlongItsWayNotTheGrid) {
  // 120 x 120 nodes, no turning time, corner to corner: every staircase is a way of the same length.
  // With the exact heuristic a robot alone is searched along one of them: a few states per node of
  // its way. Ties must stay ties: the heuristic's float rounding once compounded step by step and
  // made states nearer the start look better, and f in steps fixed in time split ties whose f fell
  // on a step's edge (0.3 s and 0.1 s edges, or a start half a millisecond in).
  constexpr int n = 120;
  for (const double d : {0.5, 0.3, 0.1}) {
    for (const double start : {0.0, 0.0005}) {
      Graph g;
      for (int y = 0; y < n; ++y)
        for (int x = 0; x < n; ++x)
          g.addNode({0.5 * x, 0.5 * y});
      for (int y = 0; y < n; ++y) {
        for (int x = 0; x < n; ++x) {
          const int v = y * n + x;
          if (x + 1 < n) {
            g.addEdge(v, v + 1, d);
            g.addEdge(v + 1, v, d);
          }
          if (y + 1 < n) {
            g.addEdge(v, v + n, d);
            g.addEdge(v + n, v, d);
          }
        }
      }
      Sipp sipp(g);
      ReservationTable t(g);
      const auto p = sipp.plan(t, {0, kNoNode, start, n * n - 1});
      ASSERT_TRUE(p.has_value());
      EXPECT_NEAR(p->back().arrive, start + (2 * (n - 1)) * d, 1e-3);
      EXPECT_EQ(p->size(), static_cast<std::size_t>(2 * (n - 1) + 1));
      EXPECT_LE(sipp.stats().expanded, 4 * p->size()) << d << " s edges from " << start << " s";
    }
  }
}

TEST(Sipp, ItWaitsForARobotCrossingItsWayRatherThanDriveIntoIt) {
  const Graph g = lineGraph(4);
  ReservationTable t(g);
  t.reserve(2, {1.0, 3.0});  // someone stands on node 2 from 1 s to 3 s
  Sipp sipp(g);
  const auto p = sipp.plan(t, {0, kNoNode, 0.0, 3});
  ASSERT_TRUE(p.has_value());
  // 0 → 1 at once, then into 2 no sooner than 3 s: there at 4 s, at 3 at 5 s.
  EXPECT_DOUBLE_EQ(p->back().arrive, 5.0);
  EXPECT_EQ(t.firstConflict(*p), -1);
  // Node 1 must be free until it arrives at 2; with 1 taken from 3.5 s it waits on 0 instead.
  t.reserve(1, {3.5, 4.0});
  const auto q = sipp.plan(t, {0, kNoNode, 0.0, 3});
  ASSERT_TRUE(q.has_value());
  EXPECT_EQ(t.firstConflict(*q), -1);
  // Standing on 1 until 2 is free (3 s) would keep 1 until 4 s: it waits on 0 until 1 is free
  // again (4 s), then drives on: 1 at 5, 2 at 6, 3 at 7.
  EXPECT_DOUBLE_EQ(q->back().arrive, 7.0);
  EXPECT_DOUBLE_EQ(q->front().leave, 4.0);
}

TEST(Sipp, ARobotOnAClosedNodeOrArrivedByAClosedEdgeStillDrivesOff) {
  Graph g = lineGraph(4);
  Sipp sipp(g, quarterTurns(g));
  ReservationTable t(g);
  g.setOpen(0, false);  // closed under the robot: it may still leave
  sipp.graphChanged();
  const auto p = sipp.plan(t, {0, kNoNode, 0.0, 3});
  ASSERT_TRUE(p.has_value());
  EXPECT_DOUBLE_EQ(p->back().arrive, 3.0);
  g.setOpen(0, true);
  g.setEdgeOpen(0, 1, false);  // the edge it came by, closed behind it
  sipp.graphChanged();
  const auto q = sipp.plan(t, {1, 0, 0.0, 3});
  ASSERT_TRUE(q.has_value());
  EXPECT_DOUBLE_EQ(q->back().arrive, 2.0);
  // Nothing drives into a closed node.
  g.setOpen(2, false);
  sipp.graphChanged();
  EXPECT_FALSE(sipp.plan(t, {1, 0, 0.0, 3}).has_value());
}

TEST(Sipp, AGoalsTableIsThePlainFixedPointWhateverOrderItIsReadIn) {
  // A goal's table is searched only as far as the values read need. Read in a random order, a
  // little at a time, every value is the one a plain fixed point over (edge arrived by) gives:
  // t(u→v) = 0 at the goal, else the least turn + duration + t(next edge); a node's time the least
  // over its edges out. Durations and turns that are no binary fractions, so the floats round.
  std::mt19937_64 rng(5);
  for (int trial = 0; trial < 40; ++trial) {
    const Graph quarters = test::randomDigraph(60, 6, false, rng);
    Graph g;
    for (NodeId u = 0; static_cast<std::size_t>(u) < quarters.size(); ++u)
      g.addNode(quarters.position(u));
    for (NodeId u = 0; static_cast<std::size_t>(u) < quarters.size(); ++u)
      for (const Edge& e : quarters.edges(u))
        g.addEdge(u, e.to, 1.1 * e.duration);
    const auto quarter = quarterTurns(g);
    const Sipp::TurnTime turn = [&quarter](NodeId a, NodeId b, NodeId c) {
      return 0.7 * quarter(a, b, c) + (quarter(a, b, c) > 0.0 ? 0.1 : 0.0);
    };
    const NodeId goal = static_cast<NodeId>(trial % 60);
    struct E {
      NodeId from, to;
      double duration;
    };
    std::vector<E> edges;
    for (NodeId u = 0; static_cast<std::size_t>(u) < g.size(); ++u)
      for (const Edge& e : g.edges(u))
        edges.push_back({u, e.to, e.duration});
    std::vector<double> te(edges.size(), kForever);
    for (bool changed = true; changed;) {
      changed = false;
      for (std::size_t i = 0; i < edges.size(); ++i) {
        double best = edges[i].to == goal ? 0.0 : kForever;
        for (std::size_t j = 0; j < edges.size(); ++j) {
          if (edges[j].from == edges[i].to && te[j] < kForever)
            best = std::min(best, turn(edges[i].from, edges[i].to, edges[j].to) + edges[j].duration + te[j]);
        }
        if (best < te[i] - 1e-12) {
          te[i] = best;
          changed = true;
        }
      }
    }
    std::vector<NodeId> order(g.size());
    std::iota(order.begin(), order.end(), NodeId{0});
    std::shuffle(order.begin(), order.end(), rng);
    Sipp sipp(g, turn);
    for (const NodeId v : order) {
      double want = v == goal ? 0.0 : kForever;
      for (std::size_t j = 0; j < edges.size(); ++j) {
        if (edges[j].from == v && te[j] < kForever)
          want = std::min(want, edges[j].duration + te[j]);
      }
      const double got = sipp.drivingTime(v, goal);
      if (want == kForever) {
        EXPECT_EQ(got, kForever) << "trial " << trial << " node " << v;
      } else {
        // Kept as floats rounded down: within a float step per edge of the way (sipp.cpp).
        EXPECT_NEAR(got, want, 1e-4) << "trial " << trial << " node " << v;
      }
    }
    // The values by the edge arrived by, read through a lone robot's search from that heading.
    ReservationTable t(g);
    for (std::size_t j = 0; j < edges.size(); j += 7) {
      const auto p = sipp.plan(t, {edges[j].to, edges[j].from, 0.0, goal});
      ASSERT_EQ(p.has_value(), te[j] < kForever || edges[j].to == goal) << "trial " << trial << " edge " << j;
      if (p && edges[j].to != goal) {
        // (turns are kept as floats: a few 1e-8 s each)
        EXPECT_GE(p->back().arrive, te[j] - 1e-6) << "trial " << trial << " edge " << j;
        EXPECT_LE(p->back().arrive, te[j] + 1e-3) << "trial " << trial << " edge " << j;
      }
    }
  }
}

TEST(Sipp, EarliestArrivalMatchesAPlainSearchOverEveryQuarterSecond) {
  std::mt19937_64 rng(11);
  int compared = 0;
  int found = 0;
  for (int trial = 0; trial < 120; ++trial) {
    Graph g = test::randomDigraph(14, 4, false, rng);
    std::uniform_int_distribution<int> node(0, 13);
    for (int c = 0; c < 4; ++c) {
      const int a = node(rng);
      const int b = node(rng);
      if (a != b)
        g.addConflict(a, b);
    }
    const NodeId start = node(rng);
    NodeId goal = node(rng);
    if (goal == start)
      goal = (start + 1) % 14;
    ReservationTable t(g);
    std::uniform_int_distribution<int> quarter(0, 60);
    std::uniform_int_distribution<int> len(1, 12);
    for (int r = 0; r < 10; ++r) {
      const NodeId v = node(rng);
      const double from = 0.25 * quarter(rng);
      if (v == start || g.conflicting(v, start))
        continue;  // the start is free at first
      t.reserve(v, {from, from + 0.25 * len(rng)});
    }
    const double hold = trial % 3 == 0 ? kForever : 20.0;
    const auto turn = quarterTurns(g);
    Sipp sipp(g, turn);
    const auto p = sipp.plan(t, {start, kNoNode, 0.0, goal, hold});
    const double plain = earliestByTimeSteps(g, t, turn, start, goal, hold, 40.0);
    if (p && p->back().arrive > 40.0)
      continue;  // beyond the plain search's horizon
    ++compared;
    ASSERT_EQ(p.has_value(), plain >= 0.0)
        << "trial " << trial << " sipp " << (p ? p->back().arrive : -1.0) << " plain " << plain;
    if (p) {
      ++found;
      // Never before the earliest; at most a step of f (1 ms) after it.
      EXPECT_GE(p->back().arrive, plain - 1e-9) << "trial " << trial;
      EXPECT_LE(p->back().arrive, plain + 1e-3) << "trial " << trial;
      EXPECT_EQ(t.firstConflict(*p), -1) << "trial " << trial;
      EXPECT_EQ(p->front().node, start);
      EXPECT_EQ(p->back().node, goal);
      for (std::size_t i = 0; i + 1 < p->size(); ++i) {
        const Edge* e = g.edge((*p)[i].node, (*p)[i + 1].node);
        ASSERT_NE(e, nullptr);
        EXPECT_NEAR((*p)[i + 1].arrive - (*p)[i + 1].enter, e->duration, 1e-9);
        EXPECT_LE((*p)[i].arrive, (*p)[i].leave);
      }
    }
  }
  EXPECT_GT(compared, 80);
  EXPECT_GT(found, 30);
}

// A plan kept while on time is searched again once a node on it costs more (the risk map, a yield)
// or less: the robot then goes round, and back through once the cost is gone.
TEST(PrioritizedPlanner, APlanKeptThroughANodeWhoseCostChangedIsSearchedAgain) {
  const Graph g = threeByThree();
  PrioritizedPlanner planner(g, quarterTurns(g));
  std::vector<PlanRequest> rs(1);
  rs[0].at = 0;
  rs[0].goal = 2;
  const auto through = [](const TimedPath& p, NodeId v) {
    return std::any_of(p.begin(), p.end(), [&](const TimedNode& n) { return n.node == v; });
  };
  EXPECT_TRUE(through(planner.plan(rs)[0], 1));
  EXPECT_TRUE(through(planner.plan(rs)[0], 1));
  EXPECT_EQ(planner.stats().reused, 1U);
  std::vector<float> cost(9, 0.0F);
  cost[1] = 10.0F;
  planner.setNodeCost(cost);
  EXPECT_FALSE(through(planner.plan(rs)[0], 1));  // searched again: round by 3, 4, 5
  EXPECT_EQ(planner.stats().reused, 1U);
  planner.setNodeCost({});
  EXPECT_TRUE(through(planner.plan(rs)[0], 1));  // the way round is no longer the earliest
  EXPECT_EQ(planner.stats().reused, 1U);
  EXPECT_THROW(planner.setNodeCost(std::vector<float>(4, 1.0F)), std::invalid_argument);
  cost[1] = -1.0F;
  EXPECT_THROW(planner.setNodeCost(cost), std::invalid_argument);
}

TEST(PrioritizedPlanner, TwoRobotsMeetingInACorridorPassAtTheSiding) {
  // 0 - 1 - 2 - 3 - 4 with a siding 5 off node 2; robots at both ends swap.
  Graph g = lineGraph(5);
  const NodeId side = g.addNode({2.0, 1.0});
  g.addEdge(2, side, 1.0);
  g.addEdge(side, 2, 1.0);
  PrioritizedPlanner planner(g);
  std::vector<PlanRequest> rs(2);
  rs[0].at = 0;
  rs[0].goal = 4;
  rs[0].priority = 1;
  rs[1].at = 4;
  rs[1].goal = 0;
  const auto paths = planner.plan(rs);
  EXPECT_EQ(pairwiseConflict(g, paths, kForever), "");
  // Each stands on the other's way: the second inherits the first's priority and drives into the
  // siding, the first waits for it to get there (robot 1 leaves node 2 for the siding at 3 s) and
  // then drives through: 2 at 4 s, 4 at 6 s.
  EXPECT_EQ(paths[1].back().node, side);
  EXPECT_EQ(paths[0].back().node, 4);
  EXPECT_DOUBLE_EQ(paths[0].back().arrive, 6.0);
  EXPECT_EQ(planner.stats().yields, 1U);
  EXPECT_EQ(planner.stats().refuges, 1U);
  EXPECT_EQ(planner.stats().failures, 1U);  // robot 1, not at its goal in this plan
  // Planned again from the same place and time, robot 0 keeps the rest of its plan (no search).
  const auto again = planner.plan(rs);
  EXPECT_GE(planner.stats().reused, 1U);
  ASSERT_EQ(again[0].size(), paths[0].size());
  EXPECT_DOUBLE_EQ(again[0].back().arrive, 6.0);
  // The next plan, from where this one ends, takes robot 1 home.
  rs[0].at = 4;
  rs[0].cameFrom = 3;
  rs[0].ready = 6.0;
  rs[0].goal = kNoNode;
  rs[1].at = side;
  rs[1].cameFrom = 2;
  rs[1].ready = 3.0;
  const auto next = planner.plan(rs);
  EXPECT_EQ(next[1].back().node, 0);
  EXPECT_EQ(next[0].size(), 1U);
  EXPECT_EQ(pairwiseConflict(g, next, kForever), "");
}

TEST(PrioritizedPlanner, PlansOnTheSmallWarehouseAreFreeOfConflictsAndHeldRobotsStand) {
  const Roadmap roadmap = buildRoadmap(test::shipped("small_warehouse.site.json"));
  const Graph& g = roadmap.graph;
  std::mt19937_64 rng(5);
  std::uniform_int_distribution<NodeId> pick(0, static_cast<NodeId>(g.size()) - 1);
  for (int trial = 0; trial < 3; ++trial) {
    std::vector<PlanRequest> rs;
    std::vector<NodeId> taken;
    auto freeNode = [&] {
      for (;;) {
        const NodeId v = pick(rng);
        if (std::none_of(taken.begin(), taken.end(),
                         [&](NodeId u) { return u == v || g.conflicting(u, v); })) {
          taken.push_back(v);
          return v;
        }
      }
    };
    for (int i = 0; i < 20; ++i) {
      PlanRequest r;
      r.at = freeNode();
      r.ready = 0.5 * (i % 3);
      r.held = i == 7;
      rs.push_back(r);
    }
    for (auto& r : rs)
      r.goal = freeNode();
    PrioritizedPlanner planner(g, [&](NodeId a, NodeId b, NodeId c) { return roadmap.extraTurn(a, b, c); },
                               {.window = kForever});
    const auto paths = planner.plan(rs);
    // With the 5 s window: free of conflicts within it.
    PrioritizedPlanner windowed(g, [&](NodeId a, NodeId b, NodeId c) { return roadmap.extraTurn(a, b, c); });
    const auto near = windowed.plan(rs);
    EXPECT_DOUBLE_EQ(windowed.windowEnd(), 5.0);
    EXPECT_EQ(pairwiseConflict(g, near, windowed.windowEnd()), "") << "trial " << trial;
    ASSERT_EQ(paths.size(), rs.size());
    EXPECT_EQ(pairwiseConflict(g, paths, kForever), "") << "trial " << trial;
    EXPECT_EQ(paths[7].size(), 1U);  // held: stands
    std::size_t arrived = 0;
    for (std::size_t i = 0; i < rs.size(); ++i) {
      EXPECT_EQ(paths[i].front().node, rs[i].at);
      EXPECT_EQ(paths[i].front().arrive, rs[i].ready);
      arrived += paths[i].back().node == rs[i].goal ? 1 : 0;
    }
    EXPECT_GE(arrived, 15U) << "trial " << trial;
    EXPECT_EQ(arrived + planner.stats().failures, 19U) << "trial " << trial;  // the held one aside
  }
}
