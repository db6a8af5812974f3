#include "fleet/traffic/distance_table.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "pibt_test_support.hpp"

using namespace fleet;
using namespace fleet::traffic;
using fleet::traffic::test::gridOf;
using fleet::traffic::test::randomDigraph;

namespace {

constexpr float kInf = DistanceTable::kUnreachable;

/// Floyd-Warshall over open edges between open nodes, plus the way off a closed node: the slow,
/// obvious answer to compare with.
std::vector<std::vector<double>> allPairs(const Graph& g) {
  const std::size_t n = g.size();
  const double inf = std::numeric_limits<double>::infinity();
  std::vector<std::vector<double>> d(n, std::vector<double>(n, inf));
  for (std::size_t v = 0; v < n; ++v) {
    d[v][v] = 0.0;
    for (const Edge& e : g.edges(static_cast<NodeId>(v))) {
      if (e.open && g.isOpen(e.to) && g.isOpen(static_cast<NodeId>(v))) {
        d[v][static_cast<std::size_t>(e.to)] = std::min(d[v][static_cast<std::size_t>(e.to)], e.duration);
      }
    }
  }
  for (std::size_t k = 0; k < n; ++k) {
    for (std::size_t i = 0; i < n; ++i) {
      for (std::size_t j = 0; j < n; ++j) {
        d[i][j] = std::min(d[i][j], d[i][k] + d[k][j]);
      }
    }
  }
  // A closed node (not the goal) may still drive off along an open edge to an open node.
  for (std::size_t v = 0; v < n; ++v) {
    if (g.isOpen(static_cast<NodeId>(v))) {
      continue;
    }
    for (std::size_t j = 0; j < n; ++j) {
      d[v][j] = j == v ? 0.0 : inf;
      for (const Edge& e : g.edges(static_cast<NodeId>(v))) {
        if (e.open && g.isOpen(e.to)) {
          d[v][j] = std::min(d[v][j], e.duration + d[static_cast<std::size_t>(e.to)][j]);
        }
      }
    }
  }
  for (std::size_t j = 0; j < n; ++j) {
    if (!g.isOpen(static_cast<NodeId>(j))) {
      for (std::size_t i = 0; i < n; ++i) {
        d[i][j] = inf;
      }
    }
  }
  return d;
}

void expectSameAsAllPairs(const Graph& g, DistanceTable& t) {
  const auto ref = allPairs(g);
  for (std::size_t goal = 0; goal < g.size(); ++goal) {
    const auto d = t.to(static_cast<NodeId>(goal));
    for (std::size_t v = 0; v < g.size(); ++v) {
      if (std::isinf(ref[v][goal])) {
        EXPECT_EQ(d[v], kInf) << v << " -> " << goal;
      } else {
        EXPECT_NEAR(d[v], ref[v][goal], 1e-4) << v << " -> " << goal;
      }
    }
  }
}

}  // namespace

TEST(DistanceTable, BreadthFirstOnAGridMatchesManhattanAroundAWall) {
  const GridMap m = gridOf({
      ".....",
      ".@@@.",
      ".....",
  });
  DistanceTable t(m.graph);
  EXPECT_TRUE(t.unitDurations());
  const auto d = t.to(m.node(0, 1));
  EXPECT_EQ(d[static_cast<std::size_t>(m.node(0, 1))], 0.0F);
  EXPECT_EQ(d[static_cast<std::size_t>(m.node(4, 1))], 6.0F);  // around the wall
  EXPECT_EQ(d[static_cast<std::size_t>(m.node(2, 0))], 3.0F);
  EXPECT_EQ(t.distance(m.node(4, 1), m.node(0, 1)), 6.0F);
  expectSameAsAllPairs(m.graph, t);
}

TEST(DistanceTable, RandomWeightedDirectedGraphsMatchFloydWarshall) {
  std::mt19937_64 rng(3);
  for (int round = 0; round < 20; ++round) {
    Graph g;
    const int n = 12 + round % 7;
    for (int i = 0; i < n; ++i) {
      g.addNode({static_cast<double>(i), 0.0});
    }
    std::uniform_int_distribution<int> node(0, n - 1);
    std::uniform_real_distribution<double> dur(0.5, 3.0);
    for (int e = 0; e < n * 3; ++e) {
      const int a = node(rng);
      const int b = node(rng);
      if (a != b) {
        // Unit durations in half the rounds: the breadth-first path.
        g.addEdge(a, b, round % 2 == 0 ? 1.0 : dur(rng));
      }
    }
    DistanceTable t(g);
    EXPECT_EQ(t.unitDurations(), round % 2 == 0);
    expectSameAsAllPairs(g, t);
    // Close some nodes and edges: routes avoid them, a robot on a closed node may still drive off.
    for (int k = 0; k < 3; ++k) {
      g.setOpen(node(rng), false);
      const int a = node(rng);
      if (!g.edges(a).empty()) {
        g.setEdgeOpen(a, g.edges(a)[0].to, false);
      }
    }
    t.invalidate();
    expectSameAsAllPairs(g, t);
  }
}

// A cost of driving into each node is the same as adding it to every edge into that node, except
// that arriving at the goal costs nothing: checked against Floyd-Warshall on such a graph.
TEST(DistanceTable, NodeCostsAreEdgesIntoTheNodeCostingMore) {
  std::mt19937_64 rng(5);
  for (int round = 0; round < 10; ++round) {
    Graph g;
    Graph costed;
    const int n = 10 + round;
    for (int i = 0; i < n; ++i) {
      g.addNode({static_cast<double>(i), 0.0});
      costed.addNode({static_cast<double>(i), 0.0});
    }
    std::uniform_int_distribution<int> node(0, n - 1);
    std::uniform_real_distribution<float> cost(0.0F, 2.0F);
    std::vector<float> c(static_cast<std::size_t>(n));
    for (auto& x : c) {
      x = cost(rng);
    }
    for (int e = 0; e < n * 3; ++e) {
      const int a = node(rng);
      const int b = node(rng);
      if (a != b) {
        g.addEdge(a, b, 1.0);  // unit durations: the costs must switch the search to Dijkstra's
        costed.addEdge(a, b, 1.0 + static_cast<double>(c[static_cast<std::size_t>(b)]));
      }
    }
    DistanceTable t(g);
    const auto plain = allPairs(g);
    EXPECT_TRUE(t.setNodeCost(c));
    EXPECT_FALSE(t.setNodeCost(c)) << "the same costs again change nothing";
    const auto expected = allPairs(costed);
    for (int goal = 0; goal < n; ++goal) {
      const auto d = t.to(goal);
      for (int from = 0; from < n; ++from) {
        const double want =
            from == goal ? 0.0
                         : expected[from][goal] - static_cast<double>(c[static_cast<std::size_t>(goal)]);
        if (std::isinf(expected[from][goal])) {
          EXPECT_EQ(d[from], kInf);
        } else {
          EXPECT_NEAR(d[from], want, 1e-4) << from << " -> " << goal;
          EXPECT_GE(static_cast<double>(d[from]) + 1e-4, plain[from][goal])
              << "a cost never makes a way shorter";
        }
      }
    }
    // All zero is no cost at all: the plain tables again.
    EXPECT_TRUE(t.setNodeCost(std::vector<float>(static_cast<std::size_t>(n), 0.0F)));
    expectSameAsAllPairs(g, t);
    EXPECT_TRUE(t.nodeCost().empty());
  }
}

TEST(DistanceTable, ClosingWithoutInvalidateKeepsOldTablesInvalidateDropsThem) {
  const GridMap m = gridOf({"....."});
  Graph g = m.graph;
  DistanceTable t(g);
  EXPECT_EQ(t.distance(0, 4), 4.0F);
  g.setOpen(2, false);
  EXPECT_EQ(t.distance(0, 4), 4.0F);  // cached: the caller has to say the graph changed
  t.invalidate();
  EXPECT_EQ(t.distance(0, 4), kInf);
  EXPECT_EQ(t.distance(2, 4), 2.0F);  // standing on the closed node: it may drive off
  EXPECT_EQ(t.distance(0, 2), kInf);  // a closed goal cannot be reached
  g.setOpen(2, true);
  g.setEdgeOpen(2, 3, false);  // one way: 3 -> 2 still open
  t.invalidate();
  EXPECT_EQ(t.distance(0, 4), kInf);
  EXPECT_EQ(t.distance(4, 0), 4.0F);
}

TEST(DistanceTable, BoundedCacheRecomputesEvictedGoalsAndKeepsRecentOnes) {
  const GridMap m = gridOf({"........"});
  // A budget of two tables (8 nodes x 4 bytes each).
  DistanceTable t(m.graph, 2 * 8 * sizeof(float));
  EXPECT_EQ(t.capacity(), 2U);
  (void)t.to(0);
  (void)t.to(1);
  EXPECT_EQ(t.computed(), 2U);
  (void)t.to(0);  // hit; 1 is now the least recently used
  EXPECT_EQ(t.computed(), 2U);
  (void)t.to(2);  // evicts 1
  EXPECT_EQ(t.computed(), 3U);
  EXPECT_EQ(t.cached(), 2U);
  EXPECT_EQ(t.distance(7, 0), 7.0F);  // still cached
  EXPECT_EQ(t.computed(), 3U);
  EXPECT_EQ(t.distance(7, 1), 6.0F);  // recomputed, correctly
  EXPECT_EQ(t.computed(), 4U);
  t.reserve(5);  // a planner holding five goals at once overrides the budget
  for (NodeId g = 0; g < 5; ++g) {
    (void)t.to(g);
  }
  const std::uint64_t before = t.computed();
  for (NodeId g = 0; g < 5; ++g) {
    EXPECT_EQ(t.distance(7, g), static_cast<float>(7 - g));
  }
  EXPECT_EQ(t.computed(), before);
}

TEST(DistanceTable, ANodeBlockedAndUnblockedBetweenQueriesRestartsNoTable) {
  const GridMap m = gridOf({
      ".....",
      ".....",
  });
  DistanceTable t(m.graph);
  const NodeId goal = m.node(4, 0);
  const NodeId v = m.node(2, 0);
  (void)t.to(goal);  // settled everywhere, v included
  const auto before = t.computed();
  // A replan takes every fixed robot off its node and puts it back: no change to restart for.
  t.setBlocked(v, true);
  t.setBlocked(v, false);
  EXPECT_EQ(t.distance(m.node(0, 0), goal), 4.0F);
  EXPECT_EQ(t.computed(), before);
  EXPECT_EQ(t.repaired(), 0U);
  // A real change repairs the table that settled the node, and routes round it.
  t.setBlocked(v, true);
  EXPECT_EQ(t.distance(m.node(0, 0), goal), 6.0F);
  EXPECT_EQ(t.computed(), before);
  EXPECT_EQ(t.repaired(), 1U);
}

TEST(DistanceTable, BlockedNodesAreRoutedAroundButStayReachableAsGoals) {
  const GridMap m = gridOf({
      ".....",
      ".....",
  });
  DistanceTable t(m.graph);
  EXPECT_EQ(t.distance(m.node(0, 0), m.node(4, 0)), 4.0F);
  t.setBlocked(m.node(2, 0), true);                         // a stopped robot in the top lane
  EXPECT_EQ(t.distance(m.node(0, 0), m.node(4, 0)), 6.0F);  // round it through the bottom lane
  EXPECT_EQ(t.distance(m.node(0, 0), m.node(2, 0)), 2.0F);  // up to it, for whoever waits for it
  EXPECT_EQ(t.distance(m.node(2, 0), m.node(4, 0)), 2.0F);  // and off it
  t.setBlocked(m.node(2, 0), false);
  EXPECT_EQ(t.distance(m.node(0, 0), m.node(4, 0)), 4.0F);
}

// Blocking, unblocking and node costs repair only the tables that have read a changed node
// (applyChanges, distance_repair.cpp): after any sequence of changes (several at once, raising and
// lowering costs together) and partial reads, every value a cached table gives is the one a table
// built afresh with the same state gives, to the bit, and no change restarts a table. The simple
// reference (OnChange::kRestart) run side by side gives the same values and does restart.
TEST(DistanceTable, ChangesRepairOnlyTheTablesThatReadThemAndLeaveEveryValueExact) {
  std::mt19937_64 rng(23);
  std::uint64_t repairs = 0;
  std::uint64_t restarts = 0;
  for (int round = 0; round < 120; ++round) {
    const int n = 25 + round % 37;
    const Graph g = randomDigraph(n, 6 + round % 5, round % 2 == 0, rng);
    std::uniform_int_distribution<int> node(0, n - 1);
    std::uniform_int_distribution<int> quarter(1, 8);
    std::uniform_int_distribution<int> some(1, 4);
    DistanceTable cached(g);
    DistanceTable restarted(g);
    restarted.setOnChange(DistanceTable::OnChange::kRestart);
    std::vector<std::uint8_t> blocked(static_cast<std::size_t>(n), 0);
    std::vector<float> cost;
    std::vector<NodeId> goals;
    for (int q = 0; q < 40; ++q) {
      // Read a few nodes of a few goals: tables settled part of the way, some whole (to()).
      for (int k = 0; k < 4; ++k) {
        const NodeId goal = node(rng);
        goals.push_back(goal);
        if (k == 0 && q % 3 == 0) {
          (void)cached.to(goal);
          (void)restarted.to(goal);
        } else {
          const NodeId from = node(rng);
          (void)cached.distance(from, goal);
          (void)restarted.distance(from, goal);
        }
      }
      const std::uint64_t before = cached.computed();
      const std::uint64_t restartedBefore = restarted.computed();
      const int what = q % 4;
      if (what < 2) {
        for (int k = some(rng); k > 0; --k) {  // robots stopping and leaving in one update
          const NodeId v = node(rng);
          blocked[static_cast<std::size_t>(v)] ^= 1U;
          cached.setBlocked(v, blocked[static_cast<std::size_t>(v)] != 0);
          restarted.setBlocked(v, blocked[static_cast<std::size_t>(v)] != 0);
        }
      } else if (what == 2) {
        if (cost.empty()) {
          cost.assign(static_cast<std::size_t>(n), 0.0F);
        }
        for (int k = some(rng); k > 0; --k) {
          cost[static_cast<std::size_t>(node(rng))] = static_cast<float>(quarter(rng)) * 0.5F;
          cost[static_cast<std::size_t>(node(rng))] = 0.0F;
        }
        cached.setNodeCost(cost);
        restarted.setNodeCost(cost);
      } else if (q % 8 == 7) {
        cost.clear();
        cached.setNodeCost(cost);
        restarted.setNodeCost(cost);
      }
      // The reference restarts what the change reached (computed on the first read after it).
      (void)restarted.distance(0, goals.back());
      restarts += restarted.computed() - restartedBefore;
      DistanceTable fresh(g);
      for (int v = 0; v < n; ++v) {
        fresh.setBlocked(v, blocked[static_cast<std::size_t>(v)] != 0);
      }
      fresh.setNodeCost(cost);
      // Goals read before (repaired tables) and a few new ones; most nodes read one by one.
      for (int k = 0; k < 6; ++k) {
        const NodeId goal = k < 4 ? goals[goals.size() - 1 - static_cast<std::size_t>(k)] : node(rng);
        const auto want = fresh.to(goal);
        const bool all = q % 5 == 4;
        for (int v = 0; v < n; ++v) {
          if (all || v % 3 == q % 3) {
            ASSERT_EQ(cached.distance(v, goal), want[static_cast<std::size_t>(v)])
                << "round " << round << " query " << q << ": " << v << " -> " << goal;
            ASSERT_EQ(restarted.distance(v, goal), want[static_cast<std::size_t>(v)])
                << "reference, round " << round << " query " << q << ": " << v << " -> " << goal;
          }
        }
      }
      if (what != 3 || q % 8 == 7) {
        // No table was restarted by the change (only goals not cached were computed).
        EXPECT_LE(cached.computed() - before, 2U) << "round " << round << " query " << q;
      }
    }
    repairs += cached.repaired();
  }
  EXPECT_GT(repairs, 500U) << "changes reached tables";
  EXPECT_GT(restarts, 500U) << "the reference restarted them";
}

TEST(DistanceTable, ABlockedNodeTheSearchHasNotReachedKeepsTheTable) {
  const GridMap m = gridOf({"........................"});
  DistanceTable t(m.graph);
  EXPECT_EQ(t.distance(m.node(2, 0), m.node(0, 0)), 2.0F);  // settled round the goal only
  const std::uint64_t before = t.computed();
  t.setBlocked(m.node(20, 0), true);  // far past what was read
  EXPECT_EQ(t.distance(m.node(3, 0), m.node(0, 0)), 3.0F);
  EXPECT_EQ(t.computed(), before) << "the table went on where it was";
  EXPECT_EQ(t.distance(m.node(23, 0), m.node(0, 0)), kInf) << "and honours the block it reaches";
  t.setBlocked(m.node(1, 0), true);  // settled: the table is repaired
  EXPECT_EQ(t.distance(m.node(3, 0), m.node(0, 0)), kInf);
  EXPECT_EQ(t.computed(), before);
  EXPECT_EQ(t.repaired(), 1U);
}

// A change repairs the tables read since the change before it; a table nobody read since then (a
// goal no robot drives to any more, kept by the cache) is dropped and searched again only when
// asked for, exactly as before.
TEST(DistanceTable, ATableNobodyReadSinceTheLastChangeIsDroppedNotRepaired) {
  const GridMap m = gridOf({
      "..........",
      "..........",
      "..........",
  });
  DistanceTable t(m.graph);
  const NodeId a = m.node(9, 0);
  const NodeId b = m.node(9, 2);
  (void)t.to(a);
  (void)t.to(b);
  const auto computed = t.computed();
  t.setBlocked(m.node(5, 1), true);
  EXPECT_EQ(t.distance(m.node(0, 1), b), 10.0F);  // both were read: both repaired
  EXPECT_EQ(t.repaired(), 2U);
  t.setBlocked(m.node(5, 0), true);
  EXPECT_EQ(t.distance(m.node(0, 0), b), 11.0F);  // only b was read since: a is dropped
  EXPECT_EQ(t.repaired(), 3U);
  EXPECT_EQ(t.computed(), computed);
  EXPECT_EQ(t.distance(m.node(0, 0), a), 13.0F);  // searched again when asked for: round both
  EXPECT_EQ(t.computed(), computed + 1);
  DistanceTable fresh(m.graph);
  fresh.setBlocked(m.node(5, 1), true);
  fresh.setBlocked(m.node(5, 0), true);
  for (NodeId v = 0; v < static_cast<NodeId>(m.graph.size()); ++v) {
    EXPECT_EQ(t.distance(v, a), fresh.distance(v, a)) << v;
    EXPECT_EQ(t.distance(v, b), fresh.distance(v, b)) << v;
  }
}

// A change of more than kRepairMaxChanges nodes at once (the risk map's costs moving with many
// people) restarts the tables it reaches instead of repairing them: exact all the same.
TEST(DistanceTable, AWideChangeRestartsTheTablesItReaches) {
  std::vector<std::string> rows(10, std::string(20, '.'));
  const GridMap m = gridOf(rows);
  DistanceTable t(m.graph);
  const NodeId a = m.node(19, 0);
  const NodeId b = m.node(0, 9);
  (void)t.to(a);
  (void)t.to(b);
  const auto computed = t.computed();
  std::vector<float> cost(m.graph.size(), 0.0F);
  std::mt19937_64 rng(5);
  std::uniform_int_distribution<std::size_t> any(0, cost.size() - 1);
  for (std::size_t k = 0; k < 3 * DistanceTable::kRepairMaxChanges / 2; ++k) {
    cost[any(rng)] = 0.5F;
  }
  t.setNodeCost(cost);
  DistanceTable fresh(m.graph);
  fresh.setNodeCost(cost);
  for (NodeId v = 0; v < static_cast<NodeId>(m.graph.size()); ++v) {
    EXPECT_EQ(t.distance(v, a), fresh.distance(v, a)) << v;
    EXPECT_EQ(t.distance(v, b), fresh.distance(v, b)) << v;
  }
  EXPECT_EQ(t.repaired(), 0U);
  EXPECT_EQ(t.computed(), computed + 2);
}
