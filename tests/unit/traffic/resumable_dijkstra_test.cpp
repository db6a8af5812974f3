// DistanceTable::distance / settleAround (resumable_dijkstra.cpp): a goal's table searched only as
// far as it is read gives, where settled, bit for bit what the whole search (to()) gives, and
// visits little when read near the goal.
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
    DistanceTable whole(g);
    for (int v = 0; v < n; ++v) {
      whole.setBlocked(v, t.blocked(v));
    }
    whole.setNodeCost(std::vector<float>(t.nodeCost().begin(), t.nodeCost().end()));
    for (int q = 0; q < 6; ++q) {
      const NodeId goal = node(rng);
      const std::vector<float> all(whole.to(goal).begin(), whole.to(goal).end());
      for (int k = 0; k < n; ++k) {
        const NodeId v = node(rng);
        // Exact: the planner ranks moves by these values, so plans stay the same only if they are.
        EXPECT_EQ(t.distance(v, goal), all[static_cast<std::size_t>(v)]) << "node " << v << " goal " << goal;
      }
      for (int v = 0; v < n; ++v) {
        EXPECT_EQ(t.distance(v, goal), all[static_cast<std::size_t>(v)]) << "node " << v << " goal " << goal;
      }
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
  const NodeId goal = m.node(0, 0);
  EXPECT_EQ(t.distance(m.node(1, 0), goal), 1.0F);
  const float* part = t.partialTo(goal);
  EXPECT_EQ(part[static_cast<std::size_t>(m.node(19, 3))], DistanceTable::kUnreachable) << "not searched yet";
  t.settleAround(goal, m.node(1, 0), 1);
  EXPECT_EQ(part[static_cast<std::size_t>(m.node(2, 0))], 2.0F);
  EXPECT_EQ(part[static_cast<std::size_t>(m.node(1, 1))], 2.0F);
  EXPECT_EQ(t.distance(m.node(19, 3), goal), 22.0F);
  EXPECT_EQ(t.computed(), 1U) << "one search, resumed";
}

}  // namespace
