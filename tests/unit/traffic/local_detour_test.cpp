// DistanceTable::detourAround (local_detour.cpp): a detour table searched in a disc round the agent.
// With the disc over the whole graph it is the whole detour search (checked against Bellman-Ford);
// with a smaller one it goes round what stands near the agent and values the way on from the rim at
// the goal table's distance, so what stands far off costs nothing.
#include <gtest/gtest.h>

#include <random>

#include "fleet/traffic/distance_table.hpp"
#include "pibt_test_support.hpp"

using namespace fleet;
using namespace fleet::traffic;
using fleet::traffic::test::gridOf;
using fleet::traffic::test::randomDigraph;

namespace {

constexpr float kInf = DistanceTable::kUnreachable;

/// Distances to `goal` with entering v costing extra[v] + cost[v] (nothing for the goal), closed
/// and blocked nodes entered by nobody but left by their robot: the slow, obvious answer.
std::vector<double> bellmanFord(const Graph& g, NodeId goal, const std::vector<float>& extra,
                                const std::vector<std::uint8_t>& blocked) {
  const std::size_t n = g.size();
  const double inf = std::numeric_limits<double>::infinity();
  std::vector<double> d(n, inf);
  if (!g.isOpen(goal)) {
    return d;
  }
  d[static_cast<std::size_t>(goal)] = 0.0;
  for (std::size_t round = 0; round < n; ++round) {
    for (std::size_t u = 0; u < n; ++u) {
      for (const Edge& e : g.edges(static_cast<NodeId>(u))) {
        const auto w = static_cast<std::size_t>(e.to);
        const bool enterable = e.to == goal || (g.isOpen(e.to) && blocked[w] == 0);
        if (e.open && enterable && d[w] != inf) {
          const double enter = e.to == goal ? 0.0 : static_cast<double>(extra[w]);
          d[u] = std::min(d[u], d[w] + e.duration + enter);
        }
      }
    }
  }
  return d;
}

TEST(LocalDetour, WithTheDiscOverTheWholeGraphItIsTheWholeDetourSearch) {
  std::mt19937_64 rng(5);
  for (int round = 0; round < 50; ++round) {
    const int n = 20 + round % 19;
    Graph g = randomDigraph(n, 7, round % 2 == 0, rng);
    std::uniform_int_distribution<int> node(0, n - 1);
    std::uniform_int_distribution<int> quarter(1, 8);
    for (int k = 0; k < round % 3; ++k) {
      g.setOpen(node(rng), false);
    }
    DistanceTable t(g);
    std::vector<std::uint8_t> blocked(static_cast<std::size_t>(n), 0);
    for (int k = 0; k < round % 4; ++k) {
      const NodeId v = node(rng);
      blocked[static_cast<std::size_t>(v)] = 1;
      t.setBlocked(v, true);
    }
    std::bernoulli_distribution dear(0.3);
    std::vector<float> extra(static_cast<std::size_t>(n), 0.0F);
    for (auto& x : extra) {
      x = dear(rng) ? 30.0F : 0.0F;
    }
    const NodeId goal = node(rng);
    const NodeId from = node(rng);
    PartialTable detour;
    t.detourAround(goal, from, 1000.0, extra, detour);
    const auto want = bellmanFord(g, goal, extra, blocked);
    // Only what `from` reaches is in the disc; there the values are the whole search's.
    std::vector<std::uint8_t> reach(static_cast<std::size_t>(n), 0);
    std::vector<NodeId> open{from};
    reach[static_cast<std::size_t>(from)] = 1;
    for (std::size_t h = 0; h < open.size(); ++h) {
      for (const Edge& e : g.edges(open[h])) {
        if (e.open && reach[static_cast<std::size_t>(e.to)] == 0) {
          reach[static_cast<std::size_t>(e.to)] = 1;
          open.push_back(e.to);
        }
      }
    }
    for (int v = 0; v < n; ++v) {
      const auto i = static_cast<std::size_t>(v);
      const float got = t.settle(detour, v);
      if (reach[i] == 0 || want[i] == std::numeric_limits<double>::infinity()) {
        EXPECT_EQ(got, kInf) << "round " << round << " node " << v;
      } else {
        EXPECT_NEAR(got, want[i], 1e-3) << "round " << round << " node " << v << " goal " << goal;
      }
    }
  }
}

TEST(LocalDetour, GoesRoundWhatStandsNearAndPaysNothingForWhatStandsFar) {
  const GridMap m = gridOf({
      "..............................",
      "..............................",
  });
  DistanceTable t(m.graph);
  const NodeId goal = m.node(29, 0);
  const NodeId from = m.node(2, 0);
  std::vector<float> extra(m.graph.size(), 0.0F);
  extra[static_cast<std::size_t>(m.node(4, 0))] = 30.0F;   // a robot standing just ahead
  extra[static_cast<std::size_t>(m.node(20, 0))] = 30.0F;  // two far off, across both lanes
  extra[static_cast<std::size_t>(m.node(20, 1))] = 30.0F;
  const std::vector<std::uint8_t> none(m.graph.size(), 0);
  EXPECT_EQ(bellmanFord(m.graph, goal, extra, none)[static_cast<std::size_t>(from)], 59.0)
      << "a whole search pays for the far ones";
  PartialTable detour;
  t.detourAround(goal, from, 6.0, extra, detour);
  EXPECT_EQ(t.settle(detour, from), 29.0F)
      << "round the near one through the other lane, the far ones ignored";
  EXPECT_EQ(t.settle(detour, m.node(3, 0)), 28.0F) << "beside the standing robot: down and round";
  EXPECT_EQ(t.settle(detour, m.node(2, 1)), 28.0F) << "the other lane: the way round";
  EXPECT_EQ(t.settle(detour, m.node(9, 0)), kInf) << "outside the disc: never read";
  EXPECT_EQ(t.distance(from, goal), 27.0F) << "the goal's own table is untouched";
  // Near the goal the disc holds it: the goal is 0 and the penalties inside count.
  t.detourAround(goal, m.node(25, 0), 6.0, extra, detour);
  EXPECT_EQ(t.settle(detour, goal), 0.0F);
  EXPECT_EQ(t.settle(detour, m.node(25, 0)), 4.0F);
  EXPECT_EQ(t.settle(detour, m.node(21, 1)), 9.0F);
}

}  // namespace
