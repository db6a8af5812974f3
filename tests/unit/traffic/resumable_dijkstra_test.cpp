// DistanceTable::startWithExtraCost / settle (resumable_dijkstra.cpp): a detour table searched only
// as far as it is read gives, where settled, bit for bit what the whole search (withExtraCost)
// gives, keeps the graph's state of when it started, and visits little when read near the goal.
#include <gtest/gtest.h>

#include <random>

#include "fleet/traffic/distance_table.hpp"
#include "pibt_test_support.hpp"

using namespace fleet;
using namespace fleet::traffic;
using fleet::traffic::test::gridOf;

namespace {

// Random directed graphs (unit, quarter and random durations, so that shortest ways tie), closed
// and blocked nodes, closed edges, with and without a node cost, nodes settled in random order.
TEST(ResumableDijkstra, SettledNodesHoldTheWholeSearchsValuesExactly) {
  std::mt19937_64 rng(11);
  for (int round = 0; round < 60; ++round) {
    Graph g;
    const int n = 20 + round % 23;
    for (int i = 0; i < n; ++i) {
      g.addNode({static_cast<double>(i), 0.0});
    }
    std::uniform_int_distribution<int> node(0, n - 1);
    std::uniform_real_distribution<double> dur(0.25, 3.0);
    std::uniform_int_distribution<int> quarter(1, 8);
    for (int e = 0; e < n * 3; ++e) {
      const int a = node(rng);
      const int b = node(rng);
      if (a != b) {
        const int kind = round % 3;
        g.addEdge(a, b, kind == 0 ? 1.0 : kind == 1 ? 0.25 * quarter(rng) : dur(rng));
      }
    }
    for (int k = 0; k < round % 4; ++k) {
      g.setOpen(node(rng), false);
      const int a = node(rng);
      if (!g.edges(a).empty()) {
        g.setEdgeOpen(a, g.edges(a)[0].to, false);
      }
    }
    DistanceTable t(g);
    for (int k = 0; k < round % 3; ++k) {
      t.setBlocked(node(rng), true);
    }
    if (round % 5 == 4) {
      std::vector<float> cost(static_cast<std::size_t>(n));
      for (auto& c : cost) {
        c = static_cast<float>(quarter(rng)) * 0.5F;
      }
      t.setNodeCost(cost);
    }
    std::bernoulli_distribution dear(round % 2 == 0 ? 0.15 : 0.5);
    for (int q = 0; q < 6; ++q) {
      std::vector<float> extra(static_cast<std::size_t>(n), 0.0F);
      for (auto& x : extra) {
        x = dear(rng) ? (q % 2 == 0 ? 30.0F : static_cast<float>(quarter(rng))) : 0.0F;
      }
      const NodeId goal = node(rng);
      std::vector<float> whole;
      t.withExtraCost(goal, extra, whole);
      PartialTable part;
      t.startWithExtraCost(goal, extra, part);
      for (int k = 0; k < n; ++k) {
        const NodeId v = node(rng);
        // Exact: the planner ranks moves by these values, so plans stay the same only if they are.
        EXPECT_EQ(t.settle(part, v), whole[static_cast<std::size_t>(v)]) << "node " << v << " goal " << goal;
        EXPECT_TRUE(part.isSettled(v));
      }
      for (int v = 0; v < n; ++v) {
        t.settle(part, v);
      }
      EXPECT_EQ(part.dist, whole);
    }
  }
}

// Read beside the goal, the search stops there; read again further off, it goes on from there.
TEST(ResumableDijkstra, SearchesOnlyAsFarAsItIsRead) {
  const GridMap m = gridOf({
      "....................",
      "....................",
      "....................",
      "....................",
  });
  DistanceTable t(m.graph);
  const std::vector<float> none(m.graph.size(), 0.0F);
  PartialTable part;
  t.startWithExtraCost(m.node(0, 0), none, part);
  EXPECT_EQ(t.settle(part, m.node(1, 0)), 1.0F);
  EXPECT_LE(part.settledCount, 4U);  // (0, 0), then at most the three at distance 1
  t.settleAround(part, m.node(1, 0), 1);
  EXPECT_TRUE(part.isSettled(m.node(2, 0)));
  EXPECT_TRUE(part.isSettled(m.node(1, 1)));
  EXPECT_FALSE(part.isSettled(m.node(19, 3)));
  EXPECT_EQ(t.settle(part, m.node(19, 3)), 22.0F);
  EXPECT_EQ(part.settledCount, m.graph.size());  // the far corner is the last node settled
}

// What is blocked after the search started does not change it: a table taken then would not
// change either.
TEST(ResumableDijkstra, KeepsTheStateOfWhenItStarted) {
  const GridMap m = gridOf({"......", "......"});
  DistanceTable t(m.graph);
  std::vector<float> extra(m.graph.size(), 0.0F);
  extra[static_cast<std::size_t>(m.node(2, 0))] = 30.0F;
  std::vector<float> whole;
  t.withExtraCost(m.node(0, 0), extra, whole);
  PartialTable part;
  t.startWithExtraCost(m.node(0, 0), extra, part);
  t.settle(part, m.node(1, 0));
  t.setBlocked(m.node(2, 1), true);
  t.setBlocked(m.node(3, 0), true);
  t.to(m.node(5, 1));  // the table rebuilds its state after the change
  for (NodeId v = 0; v < static_cast<NodeId>(m.graph.size()); ++v) {
    EXPECT_EQ(t.settle(part, v), whole[static_cast<std::size_t>(v)]) << v;
  }
  // A closed goal: nothing reachable, nothing to search.
  Graph g = m.graph;
  g.setOpen(0, false);
  DistanceTable closed(g);
  closed.startWithExtraCost(0, extra, part);
  EXPECT_EQ(closed.settle(part, 1), DistanceTable::kUnreachable);
}

}  // namespace
