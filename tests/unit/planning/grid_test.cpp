#include <gtest/gtest.h>

#include <random>

#include "fleet/planning/occupancy_grid.hpp"
#include "fleet/planning/wavefront.hpp"

using namespace fleet;
using namespace fleet::planning;

TEST(OccupancyGrid, FrameIsYUpWithOriginAndResolution) {
  OccupancyGrid g(10, 5, 0.5, {-2.0, 1.0});
  EXPECT_EQ(g.cellAt({-2.0, 1.0}), (Cell{0, 0}));
  EXPECT_EQ(g.cellAt({-1.74, 1.26}), (Cell{0, 0}));
  EXPECT_EQ(g.cellAt({-1.74, 1.51}), (Cell{0, 1}));
  EXPECT_EQ(g.cellAt({2.99, 3.49}), (Cell{9, 4}));
  EXPECT_FALSE(g.cellAt({3.0, 1.0}).has_value());
  EXPECT_FALSE(g.cellAt({-2.01, 1.0}).has_value());
  // Far off the grid: no cell, and no int overflow on the way (fuzz.site_json found 4.4e14 m).
  EXPECT_FALSE(g.cellAt({4.4e14, 1.0}).has_value());
  EXPECT_FALSE(g.cellAt({-2.0, -1e300}).has_value());
  const Vec2 c = g.cellCenter({3, 2});
  EXPECT_DOUBLE_EQ(c.x, -2.0 + 3.5 * 0.5);
  EXPECT_DOUBLE_EQ(c.y, 1.0 + 2.5 * 0.5);
  EXPECT_TRUE(g.blocked({-1, 0}));
  EXPECT_FALSE(g.blocked({0, 0}));
}

TEST(OccupancyGrid, InflationStencilAndBruteForce) {
  OccupancyGrid g(11, 11, 0.1);
  g.setBlocked({5, 5});
  EXPECT_EQ(g.inflated(0.15).size() - g.inflated(0.15).freeCount(), 9u);
  EXPECT_EQ(g.inflated(0.2).size() - g.inflated(0.2).freeCount(), 13u);
  EXPECT_EQ(g.inflated(0.05).size() - g.inflated(0.05).freeCount(), 1u);

  std::mt19937 rng(3);
  std::bernoulli_distribution occ(0.03);
  OccupancyGrid r(40, 30, 0.25);
  for (int y = 0; y < 30; ++y) {
    for (int x = 0; x < 40; ++x) {
      r.setBlocked({x, y}, occ(rng));
    }
  }
  const double radius = 0.61;
  const OccupancyGrid inf = r.inflated(radius);
  for (int y = 0; y < 30; ++y) {
    for (int x = 0; x < 40; ++x) {
      bool near = false;
      for (int v = 0; v < 30 && !near; ++v) {
        for (int u = 0; u < 40 && !near; ++u) {
          near = r.blocked({u, v}) && distance(r.cellCenter({u, v}), r.cellCenter({x, y})) <= radius;
        }
      }
      EXPECT_EQ(inf.blocked({x, y}), near) << x << "," << y;
    }
  }
}

TEST(Warehouse, ProceduralMapMatchesTheBenchmarkShape) {
  const OccupancyGrid g = makeWarehouseGrid();
  EXPECT_EQ(g.width(), 340);
  EXPECT_EQ(g.height(), 164);
  EXPECT_EQ(g.freeCount(), 38756u);
  for (int x = 0; x < 340; ++x) {
    EXPECT_TRUE(g.blocked({x, 0}) && g.blocked({x, 163}));
  }
  // Every free cell is reachable from every other (one connected floor).
  const DistanceField f = computeDistanceField(g, {5, 5}, Connectivity::Four);
  std::size_t reach = 0;
  for (double c : f.cost) {
    reach += std::isfinite(c) ? 1 : 0;
  }
  EXPECT_EQ(reach, g.freeCount());
}
