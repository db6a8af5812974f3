// Heading tables (heading_table.hpp) against a plain search over (node, heading) states, and the
// planner ranking its moves with them (PibtOptions::turnTime).

#include "fleet/traffic/heading_table.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>

#include "fleet/traffic/distance_table.hpp"
#include "fleet/traffic/pibt.hpp"
#include "pibt_test_support.hpp"

using namespace fleet;
using namespace fleet::traffic;
using fleet::traffic::test::gridOf;
using fleet::traffic::test::randomMap;
using fleet::traffic::test::turnsAlong;
using fleet::traffic::test::walkToGoal;

namespace {

/// Turning on the spot by the angle between prev→at and at→next: 1 s a right angle, 2.5 s back.
HeadingTable::TurnTime squareTurns(const Graph& g) {
  return [&g](NodeId prev, NodeId at, NodeId next) {
    const Vec2 a = g.position(at) - g.position(prev);
    const Vec2 b = g.position(next) - g.position(at);
    const double c = a.dot(b) / (a.norm() * b.norm());
    return c > 0.99 ? 0.0 : (c > -0.99 ? 1.0 : 2.5);
  };
}

constexpr float kInf = std::numeric_limits<float>::infinity();

/// The reference: cost-to-go per arriving edge by relaxing every edge until nothing changes
/// (Bellman-Ford over the edges), then minus the node distance of DistanceTable::to().
std::vector<float> referenceSurcharge(const Graph& g, const HeadingTable::TurnTime& turn, NodeId goal) {
  struct E {
    NodeId from, to;
    float cost;
  };
  std::vector<E> es;
  for (std::size_t u = 0; u < g.size(); ++u)
    for (const Edge& e : g.edges(static_cast<NodeId>(u)))
      es.push_back({static_cast<NodeId>(u), e.to, static_cast<float>(e.cost())});
  std::vector<float> h(es.size(), kInf);
  for (std::size_t f = 0; f < es.size(); ++f)
    if (es[f].to == goal)
      h[f] = 0.0F;
  for (bool changed = true; changed;) {
    changed = false;
    for (std::size_t f = 0; f < es.size(); ++f) {
      if (es[f].to == goal)
        continue;
      for (std::size_t e = 0; e < es.size(); ++e) {
        if (es[e].from != es[f].to || h[e] == kInf)
          continue;
        const float c = es[e].cost + h[e] + static_cast<float>(turn(es[f].from, es[f].to, es[e].to));
        if (c < h[f] - 1e-6F) {
          h[f] = c;
          changed = true;
        }
      }
    }
  }
  DistanceTable table(g);
  const auto d = table.to(goal);
  std::vector<float> s(es.size(), 0.0F);
  for (std::size_t f = 0; f < es.size(); ++f) {
    const float dv = d[static_cast<std::size_t>(es[f].to)];
    s[f] = (h[f] == kInf || dv == kInf) ? 0.0F : h[f] - dv;
  }
  return s;
}

}  // namespace

TEST(HeadingTable, MatchesRelaxingEveryEdgeOnRandomMaps) {
  std::mt19937_64 rng(7);
  for (int trial = 0; trial < 4; ++trial) {
    const GridMap m = randomMap(9, 7, 0.2, rng);
    const auto turn = squareTurns(m.graph);
    HeadingTable table(m.graph, turn);
    for (int k = 0; k < 3; ++k) {
      const auto goal = static_cast<NodeId>(rng() % m.graph.size());
      const float* s = table.compute(goal);
      ASSERT_NE(s, nullptr);
      const auto want = referenceSurcharge(m.graph, turn, goal);
      ASSERT_EQ(want.size(), table.edges());
      double most = 0.0;
      for (std::size_t f = 0; f < want.size(); ++f) {
        EXPECT_NEAR(s[f], want[f], 1e-4) << "trial " << trial << " goal " << goal << " edge " << f;
        EXPECT_GE(s[f], 0.0F);
        most = std::max(most, static_cast<double>(s[f]));
      }
      EXPECT_GE(most, 2.5) << "somewhere a robot faces away from its way";
    }
  }
}

TEST(HeadingTable, ACorridorChargesTheTurnOnlyToTheRobotFacingAway) {
  const GridMap m = gridOf({"......"});
  HeadingTable table(m.graph, squareTurns(m.graph));
  const float* s = table.compute(m.node(5, 0));
  const auto east = table.edgeBetween(m.node(1, 0), m.node(2, 0));
  const auto west = table.edgeBetween(m.node(3, 0), m.node(2, 0));
  ASSERT_GE(east, 0);
  ASSERT_GE(west, 0);
  EXPECT_FLOAT_EQ(s[east], 0.0F) << "facing the goal";
  EXPECT_FLOAT_EQ(s[west], 2.5F) << "facing away: the way back starts with a reversal";
  // Arriving westward at (2,0): going on west is straight, going back east a reversal.
  const NodeId at = m.node(2, 0);
  const auto outWest = static_cast<std::size_t>(table.edgeBetween(at, m.node(1, 0))) - table.outEdge(at, 0);
  const auto outEast = static_cast<std::size_t>(table.edgeBetween(at, m.node(3, 0))) - table.outEdge(at, 0);
  EXPECT_FLOAT_EQ(table.turn(static_cast<std::size_t>(west), at, outWest), 0.0F);
  EXPECT_FLOAT_EQ(table.turn(static_cast<std::size_t>(west), at, outEast), 2.5F);
  EXPECT_FLOAT_EQ(table.turn(static_cast<std::size_t>(east), at, outEast), 0.0F);
  EXPECT_FLOAT_EQ(table.turn(static_cast<std::size_t>(east), at, outWest), 2.5F);
}

TEST(HeadingTable, SlicedSearchesGiveTheWholeSearchsTablesAndSkipWhatIsNoLongerWanted) {
  std::mt19937_64 rng(3);
  const GridMap m = randomMap(12, 10, 0.15, rng);
  const auto turn = squareTurns(m.graph);
  HeadingTable whole(m.graph, turn);
  HeadingTable sliced(m.graph, turn);
  const std::vector<NodeId> goals{0, static_cast<NodeId>(m.graph.size() / 2),
                                  static_cast<NodeId>(m.graph.size() - 1)};
  sliced.want(goals);
  EXPECT_EQ(sliced.find(goals[0]), nullptr) << "nothing before the search has run";
  int calls = 0;
  while (sliced.pending() > 0 || sliced.find(goals.back()) == nullptr) {
    sliced.work(40);
    ASSERT_LT(++calls, 100000);
  }
  EXPECT_GT(calls, 10) << "in many slices";
  for (const NodeId g : goals) {
    const float* a = sliced.find(g);
    const float* b = whole.compute(g);
    ASSERT_NE(a, nullptr);
    for (std::size_t f = 0; f < whole.edges(); ++f)
      ASSERT_EQ(a[f], b[f]) << "goal " << g << " edge " << f;
  }
  // A goal queued and then no longer wanted is not searched; the search under way is finished.
  HeadingTable dropped(m.graph, turn);
  dropped.want(std::vector<NodeId>{1, 2, 3});
  dropped.work(40);  // starts 1's
  dropped.want(std::vector<NodeId>{3});
  EXPECT_EQ(dropped.pending(), 1U);
  dropped.work(std::numeric_limits<std::size_t>::max());
  EXPECT_NE(dropped.find(1), nullptr);
  EXPECT_EQ(dropped.find(2), nullptr);
  EXPECT_NE(dropped.find(3), nullptr);
  EXPECT_EQ(dropped.computed(), 2U);
}

TEST(HeadingTable, KeepsItsByteBudgetAndForgetsTheLeastRecentlyUsed) {
  const GridMap m = gridOf({"......", "......", "......"});
  const std::size_t edges = HeadingTable(m.graph, squareTurns(m.graph)).edges();
  HeadingTable table(m.graph, squareTurns(m.graph), 2 * sizeof(float) * edges);  // room for two
  table.compute(0);
  table.compute(1);
  EXPECT_NE(table.find(0), nullptr);  // 0 used last
  table.compute(2);
  EXPECT_EQ(table.cached(), 2U);
  EXPECT_NE(table.find(0), nullptr);
  EXPECT_EQ(table.find(1), nullptr);
  EXPECT_NE(table.find(2), nullptr);
}

TEST(HeadingTable, AClosedEdgeIsRoutedRoundAfterInvalidate) {
  GridMap m = gridOf({"...", "...", "..."});
  HeadingTable table(m.graph, squareTurns(m.graph));
  const NodeId goal = m.node(2, 1);
  const auto in = table.edgeBetween(m.node(0, 1), m.node(1, 1));  // heading east, straight on
  ASSERT_GE(in, 0);
  EXPECT_FLOAT_EQ(table.compute(goal)[in], 0.0F);
  m.graph.setEdgeOpen(m.node(1, 1), m.node(2, 1), false);
  table.invalidate();
  EXPECT_EQ(table.find(goal), nullptr);
  // Now round by (1,0) or (1,2): a right angle off, one onto the goal's column, one onto it.
  EXPECT_FLOAT_EQ(table.compute(goal)[in], 3.0F);
}

TEST(Pibt, WithTurnTimesALoneAgentTakesTheWayWithTheFewestTurns) {
  const GridMap m = gridOf({
      "......",
      "......",
      "......",
      "......",
      "......",
      "......",
  });
  for (std::uint64_t seed = 1; seed <= 8; ++seed) {
    PibtOptions o;
    o.seed = seed;
    o.turnTime = squareTurns(m.graph);
    const std::vector<NodeId> start = {m.node(0, 5)};
    Pibt p(m.graph, start, o);
    p.setGoal(0, m.node(5, 0));
    const auto path = walkToGoal(m.graph, p, 20);
    EXPECT_EQ(path.size(), 11U) << "seed " << seed << ": a shortest way";
    const int turns = turnsAlong(path);
    // The first move has no heading to turn from; after it the table knows the one-turn way.
    EXPECT_LE(turns, 1) << "seed " << seed;
  }
  ASSERT_NE(
      Pibt(m.graph, std::vector<NodeId>{0}, PibtOptions{.turnTime = squareTurns(m.graph)}).headingTables(),
      nullptr);
  EXPECT_EQ(Pibt(m.graph, std::vector<NodeId>{0}).headingTables(), nullptr) << "no turn times, no tables";
}

TEST(Pibt, AnAgentOnItsGoalStaysThereWithOrWithoutAHeading) {
  const GridMap m = gridOf({"......"});
  PibtOptions o;
  o.turnTime = squareTurns(m.graph);
  Pibt p(m.graph, std::vector<NodeId>{m.node(2, 0)}, o);  // no heading yet
  p.setGoal(0, m.node(2, 0));
  for (int k = 0; k < 5; ++k)
    EXPECT_EQ(p.step()[0], m.node(2, 0)) << "step " << k;
  p.reset(std::vector<NodeId>{m.node(2, 0)}, std::vector<NodeId>{m.node(3, 0)});  // facing west
  for (int k = 0; k < 5; ++k)
    EXPECT_EQ(p.step()[0], m.node(2, 0)) << "facing west, step " << k;
}

TEST(Pibt, AResetKeepsTheHeadingItIsGiven) {
  // A ring round a wall: from the middle of the left side the goal, the middle of the right side,
  // is as far round the top as round the bottom. The agent goes on the way it faces.
  const GridMap m = gridOf({
      "...",
      ".@.",
      "...",
  });
  for (const int fromY : {0, 2}) {
    PibtOptions o;
    o.turnTime = squareTurns(m.graph);
    Pibt p(m.graph, std::vector<NodeId>{m.node(0, 0)}, o);
    p.setGoal(0, m.node(2, 1));
    p.reset(std::vector<NodeId>{m.node(0, 1)}, std::vector<NodeId>{m.node(0, fromY)});
    const NodeId ahead = m.node(0, 2 - fromY);  // facing away from where it came from
    EXPECT_EQ(p.step()[0], ahead) << "came from y=" << fromY;
  }
  // A node it cannot have come from (not a neighbour) gives no heading: it is refused quietly and
  // the agent still reaches its goal.
  PibtOptions o;
  o.turnTime = squareTurns(m.graph);
  Pibt p(m.graph, std::vector<NodeId>{m.node(0, 0)}, o);
  p.setGoal(0, m.node(2, 1));
  p.reset(std::vector<NodeId>{m.node(0, 1)}, std::vector<NodeId>{m.node(2, 2)});
  EXPECT_EQ(walkToGoal(m.graph, p, 10).size(), 5U);
}
