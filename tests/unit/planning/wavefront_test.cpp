#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <set>

#include "fleet/planning/astar.hpp"
#include "fleet/planning/map_io.hpp"
#include "fleet/planning/wavefront.hpp"
#include "seed_map.hpp"

using namespace fleet;
using namespace fleet::planning;

namespace {

OccupancyGrid seedGrid() {
  return parseMovingAiMap(seed004MovingAi(), "seed004").value();
}

// The moving obstacle of Example 3 (Fig. 9): heading to (6,2) and (7,3) when the robot, at (7,2)
// after 3 moves, is about to take its 4th step.
CollisionPredictor example3Obstacle() {
  return [](Cell c, double t) { return t > 3.0 && t <= 4.5 && (c == seedCell(7, 3) || c == seedCell(6, 2)); };
}

}  // namespace

TEST(Wavefront, Seed004CostMatrix) {
  const OccupancyGrid g = seedGrid();
  const DistanceField f = computeDistanceField(g, seedCell(4, 11), Connectivity::Four);
  EXPECT_EQ(f.at(seedCell(4, 11)), 0.0);
  EXPECT_EQ(f.at(seedCell(10, 2)), 17.0);  // d(A)
  EXPECT_EQ(f.at(seedCell(7, 2)), 14.0);
  EXPECT_EQ(f.at(seedCell(7, 1)), 15.0);
  EXPECT_EQ(f.at(seedCell(6, 2)), 13.0);
  EXPECT_EQ(f.at(seedCell(7, 3)), 13.0);
  EXPECT_EQ(f.at(seedCell(11, 2)), 18.0);     // Fig. 7 prints 20 here; breadth-first gives 18
  EXPECT_FALSE(f.reachable(seedCell(2, 8)));  // an obstacle
}

TEST(Wavefront, Seed004StaticDescentIs17Moves) {
  const OccupancyGrid g = seedGrid();
  const DistanceField f = computeDistanceField(g, seedCell(4, 11), Connectivity::Four);
  const auto cells = descend(g, f, seedCell(10, 2));
  ASSERT_TRUE(cells.has_value());
  EXPECT_EQ(cells->size(), 18u);
  for (std::size_t k = 1; k < cells->size(); ++k) {
    const Cell a = (*cells)[k - 1], b = (*cells)[k];
    EXPECT_EQ(std::abs(a.x - b.x) + std::abs(a.y - b.y), 1);
    EXPECT_EQ(f.at(b), f.at(a) - 1.0);
  }
  EXPECT_EQ(cells->back(), seedCell(4, 11));
  // The route passes (7,2) after 3 moves (Fig. 8).
  EXPECT_EQ((*cells)[3], seedCell(7, 2));
}

TEST(Wavefront, Seed004Example3DetoursAt72And19Moves) {
  const OccupancyGrid g = seedGrid();
  const DistanceField f = computeDistanceField(g, seedCell(4, 11), Connectivity::Four);
  for (bool seedRule : {true, false}) {
    for (double dc : {4.0, 6.0}) {
      const auto ex = executeWaitOrDetour(g, f, seedCell(10, 2), example3Obstacle(),
                                          {.waitCost = dc, .scanRadius = 3.0, .seedComparison = seedRule});
      ASSERT_TRUE(ex.has_value()) << ex.error().message;
      EXPECT_EQ(ex->detours, 1);
      EXPECT_EQ(ex->waits, 0);
      EXPECT_EQ(ex->moves, 19);
      EXPECT_EQ(ex->cells[3], seedCell(7, 2));
      EXPECT_EQ(ex->cells[4], seedCell(7, 1));  // phi2 = d(7,1) = 15 < phi1 = 14 + dc
      EXPECT_EQ(ex->cells.back(), seedCell(4, 11));
      std::set<std::pair<int, int>> unique;
      for (const Cell& c : ex->cells) {
        unique.insert({c.x, c.y});
      }
      EXPECT_EQ(unique.size(), ex->cells.size());  // never revisits a cell
    }
  }
}

TEST(Wavefront, Seed004WaitWhenWaitingIsCheap) {
  const OccupancyGrid g = seedGrid();
  const DistanceField f = computeDistanceField(g, seedCell(4, 11), Connectivity::Four);
  // dc = 1: phi1 = 15 <= phi2 = 15 -> wait (both rules); the route is kept: 17 moves, time 18.
  for (bool seedRule : {true, false}) {
    const auto ex = executeWaitOrDetour(g, f, seedCell(10, 2), example3Obstacle(),
                                        {.waitCost = 1.0, .scanRadius = 3.0, .seedComparison = seedRule});
    ASSERT_TRUE(ex.has_value());
    EXPECT_EQ(ex->waits, 1);
    EXPECT_EQ(ex->detours, 0);
    EXPECT_EQ(ex->moves, 17);
    EXPECT_DOUBLE_EQ(ex->time, 18.0);
  }
  // dc = 2 is the tie the comparability fix changes: printed rule 16 > 15 detours (19 moves, time
  // 19); fixed rule 16 <= 15 + 1 waits (17 moves, time 19): equal times, so waiting keeps the route.
  const auto printed = executeWaitOrDetour(g, f, seedCell(10, 2), example3Obstacle(),
                                           {.waitCost = 2.0, .scanRadius = 3.0, .seedComparison = true});
  const auto fixed =
      executeWaitOrDetour(g, f, seedCell(10, 2), example3Obstacle(), {.waitCost = 2.0, .scanRadius = 3.0});
  ASSERT_TRUE(printed && fixed);
  EXPECT_EQ(printed->detours, 1);
  EXPECT_EQ(fixed->waits, 1);
  EXPECT_DOUBLE_EQ(printed->time, fixed->time);
  // A scan radius below one cell never sees the obstacle.
  const auto blind =
      executeWaitOrDetour(g, f, seedCell(10, 2), example3Obstacle(), {.waitCost = 4.0, .scanRadius = 0.5});
  ASSERT_TRUE(blind.has_value());
  EXPECT_EQ(blind->moves, 17);
  EXPECT_EQ(blind->detours + blind->waits, 0);
}

TEST(Wavefront, TypedErrorsNeverLoop) {
  const OccupancyGrid g = seedGrid();
  const DistanceField f = computeDistanceField(g, seedCell(4, 11), Connectivity::Four);
  // An obstacle that stays predicted everywhere around the robot: waiting forever is an error.
  const auto stuck =
      executeWaitOrDetour(g, f, seedCell(10, 2), [](Cell, double) { return true; }, {.waitCost = 4.0});
  ASSERT_FALSE(stuck.has_value());
  EXPECT_EQ(stuck.error().code, "no_admissible_neighbour");
  // Walled-in goal.
  OccupancyGrid walled = g;
  for (Cell c : {seedCell(3, 11), seedCell(5, 11), seedCell(4, 10)}) {
    walled.setBlocked(c);
  }
  const DistanceField w = computeDistanceField(walled, seedCell(4, 11), Connectivity::Four);
  EXPECT_EQ(descend(walled, w, seedCell(10, 2)).error().code, "unreachable");
  EXPECT_EQ(executeWaitOrDetour(walled, w, seedCell(10, 2), nullptr).error().code, "unreachable");
  WavefrontPlanner planner(Connectivity::Four);
  const auto p = planner.plan(walled, {1.5, 2.5, 0.0}, {10.5, 8.5, 0.0});
  ASSERT_FALSE(p.has_value());
  EXPECT_EQ(p.error().code, "unreachable");
  EXPECT_EQ(planner.plan(walled, {1.5, 2.5, 0.0}, {50.0, 8.5, 0.0}).error().code, "out_of_map");
  EXPECT_EQ(planner.plan(walled, {1.5, 2.5, 0.0}, {7.5, 10.5, 0.0}).error().code, "goal_blocked");
}

TEST(Wavefront, EightConnectedFieldIsConsistent) {
  std::mt19937 rng(8);
  std::bernoulli_distribution occ(0.25);
  OccupancyGrid g(30, 20);
  for (int y = 0; y < 20; ++y) {
    for (int x = 0; x < 30; ++x) {
      g.setBlocked({x, y}, occ(rng));
    }
  }
  g.setBlocked({3, 3}, false);
  const DistanceField f = computeDistanceField(g, {3, 3}, Connectivity::Eight);
  // Bellman optimality: every reachable cell but the goal has a neighbour exactly one move closer,
  // and no neighbour is more than one move closer.
  for (int y = 0; y < 20; ++y) {
    for (int x = 0; x < 30; ++x) {
      const Cell c{x, y};
      if (!f.reachable(c) || c == f.goal) {
        continue;
      }
      double best = 1e300;
      for (const Cell& o : neighbourOffsets(Connectivity::Eight)) {
        if (moveAllowed(g, c, o)) {
          best = std::min(best, f.at({x + o.x, y + o.y}) + moveCost(o));
        }
      }
      EXPECT_NEAR(best, f.at(c), 1e-9);
    }
  }
}

// The octile field reuses per-thread scratch sized for the last grid: alternate grid sizes, and
// check the warehouse field (the benchmark's map) for Bellman optimality and against A*.
TEST(Wavefront, OctileFieldExactOnWarehouseAndAcrossGridSizes) {
  const OccupancyGrid big = makeWarehouseGrid();
  OccupancyGrid small(7, 5);
  small.setBlocked({3, 1}, true);
  small.setBlocked({3, 2}, true);
  small.setBlocked({3, 3}, true);
  std::mt19937 rng(44);
  std::uniform_int_distribution<int> px(0, big.width() - 1), py(0, big.height() - 1);
  for (int round = 0; round < 3; ++round) {
    const DistanceField fs = computeDistanceField(small, {0, 2}, Connectivity::Eight);
    EXPECT_NEAR(fs.at({6, 2}), 2.0 + 4.0 * std::sqrt(2.0), 1e-12);  // around the wall x = 3
    EXPECT_FALSE(fs.reachable({3, 2}));
    Cell goal{px(rng), py(rng)};
    while (big.blocked(goal)) {
      goal = {px(rng), py(rng)};
    }
    const DistanceField f = computeDistanceField(big, goal, Connectivity::Eight);
    int checked = 0;
    for (int y = 0; y < big.height(); ++y) {
      for (int x = 0; x < big.width(); ++x) {
        const Cell c{x, y};
        if (!f.reachable(c) || c == goal) {
          continue;
        }
        double best = 1e300;
        for (const Cell& o : neighbourOffsets(Connectivity::Eight)) {
          if (moveAllowed(big, c, o)) {
            best = std::min(best, f.at({x + o.x, y + o.y}) + moveCost(o));
          }
        }
        ASSERT_NEAR(best, f.at(c), 1e-9) << x << "," << y;
        ++checked;
      }
    }
    EXPECT_GT(checked, 38000);
    for (int q = 0; q < 20; ++q) {
      Cell s{px(rng), py(rng)};
      if (big.blocked(s)) {
        continue;
      }
      const auto r = astar(big, s, goal);
      ASSERT_TRUE(r.has_value());
      EXPECT_NEAR(r->cost, f.at(s), 1e-9);
    }
  }
}
