#include "fleet/planning/lane_map.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <functional>
#include <memory>
#include <numbers>
#include <random>

#include "fleet/planning/astar.hpp"

using namespace fleet;
using namespace fleet::planning;

namespace {

// The lanes as the one A* sees them: a LaneCost layer, plus an optional cell price.
Expected<std::vector<Cell>> laneAstar(const OccupancyGrid& grid, const LaneMap& lanes, Cell s, Cell g,
                                      std::function<double(Cell)> price = {}) {
  CostLayers layers{std::make_shared<LaneCost>(std::make_shared<const LaneMap>(lanes))};
  if (price) {
    layers.push_back(std::make_shared<EnterCellCost>("price", std::move(price)));
  }
  auto r = astar(grid, s, g, layers);
  if (!r) {
    return unexpected(r.error());
  }
  return r->cells;
}

// The small warehouse of sim/scenarios/small_warehouse.json: 30 m x 20 m at 0.5 m, 1.5 m aisles.
OccupancyGrid smallWarehouse() {
  WarehouseParams p;
  p.width = 60;
  p.height = 40;
  p.margin = 5;
  p.shelfWidth = 8;
  p.shelfHeight = 2;
  p.aisleX = 3;
  p.aisleY = 3;
  p.resolution = 0.5;
  return makeWarehouseGrid(p);
}

int wrongWayMoves(const LaneMap& lanes, const std::vector<Cell>& cells) {
  int n = 0;
  for (std::size_t i = 1; i < cells.size(); ++i) {
    n += lanes.againstLane(cells[i - 1], cells[i]) ? 1 : 0;
  }
  return n;
}

}  // namespace

TEST(LaneMap, NarrowAislesAreOneWayAndAlternate) {
  const auto raw = smallWarehouse();
  const auto lanes = LaneMap::derive(raw);
  // Horizontal aisles between shelf rows: rows of shelves at y = 5..6, 10..11, ...; aisles at
  // y = 7..9, 12..14, ... The middle of each aisle, between two shelf blocks (x = 10).
  const LaneDir a1 = lanes.at({10, 8});
  const LaneDir a2 = lanes.at({10, 13});
  EXPECT_NE(a1.dx, 0);
  EXPECT_EQ(a1.dy, 0);
  EXPECT_EQ(a2.dx, -a1.dx) << "neighbouring aisles must run in opposite directions";
  // The whole aisle line has one direction, in every segment (x = 20 is past a cross aisle).
  EXPECT_EQ(lanes.at({20, 8}), a1);
  EXPECT_EQ(lanes.at({10, 7}), a1);
  EXPECT_EQ(lanes.at({10, 9}), a1);
  // Vertical cross aisles between block columns (x = 13..15) alternate as well.
  const LaneDir v1 = lanes.at({14, 6});
  const LaneDir v2 = lanes.at({25, 6});
  EXPECT_EQ(v1.dx, 0);
  EXPECT_NE(v1.dy, 0);
  EXPECT_EQ(v2.dy, -v1.dy);
  // Intersections are free in every direction.
  EXPECT_EQ(lanes.at({14, 8}), LaneDir{});
  // The bands along the walls have two lanes, keep right: the left band (x = 1..4) runs down on
  // its left half and up on its right half; the top band (y = 32..38) runs +x low and -x high; the
  // right band (x = 46..58) likewise down on the left, up on the right.
  EXPECT_EQ(lanes.at({2, 20}), (LaneDir{0, -1}));
  EXPECT_EQ(lanes.at({3, 20}), (LaneDir{0, 1}));
  EXPECT_EQ(lanes.at({30, 33}), (LaneDir{1, 0}));
  EXPECT_EQ(lanes.at({30, 37}), (LaneDir{-1, 0}));
  EXPECT_EQ(lanes.at({48, 20}), (LaneDir{0, -1}));
  EXPECT_EQ(lanes.at({56, 20}), (LaneDir{0, 1}));
  // Shelves have no lane.
  EXPECT_EQ(lanes.at({6, 5}), LaneDir{});
  EXPECT_GT(lanes.oneWayCells(), 100U);
}

TEST(LaneMap, OpenMapHasNoLanes) {
  OccupancyGrid open(40, 40, 0.1);
  EXPECT_EQ(LaneMap::derive(open).oneWayCells(), 0U);
}

TEST(LaneMap, AgainstLaneIsDirectional) {
  const auto lanes = LaneMap::derive(smallWarehouse());
  const LaneDir d = lanes.at({10, 8});
  const Cell a{10, 8};
  const Cell with{10 + d.dx, 8};
  const Cell against{10 - d.dx, 8};
  EXPECT_FALSE(lanes.againstLane(a, with));
  EXPECT_TRUE(lanes.againstLane(a, against));
  EXPECT_FALSE(lanes.againstLane(a, {10, 9})) << "crossing an aisle sideways is allowed";
}

TEST(LaneAstar, WithoutPenaltyEqualsPlainAstar) {
  const auto raw = smallWarehouse();
  const auto grid = raw.inflated(0.5);
  LaneParams p;
  p.wrong_way_factor = 1.0;
  const auto lanes = LaneMap::derive(raw, p);
  std::mt19937 rng(3);
  std::vector<Cell> free;
  for (std::size_t i = 0; i < grid.size(); ++i) {
    if (grid.cells()[i] == 0) {
      free.push_back(grid.cellOf(i));
    }
  }
  std::uniform_int_distribution<std::size_t> pick(0, free.size() - 1);
  for (int t = 0; t < 200; ++t) {
    const Cell s = free[pick(rng)];
    const Cell g = free[pick(rng)];
    const auto ref = astar(grid, s, g);
    const auto got = laneAstar(grid, lanes, s, g);
    ASSERT_EQ(ref.has_value(), got.has_value());
    if (!ref) {
      continue;
    }
    double len = 0.0;
    for (std::size_t i = 1; i < got->size(); ++i) {
      const int dx = std::abs((*got)[i].x - (*got)[i - 1].x);
      const int dy = std::abs((*got)[i].y - (*got)[i - 1].y);
      ASSERT_LE(dx + dy, 2);
      len += dx + dy == 2 ? std::numbers::sqrt2 : 1.0;
    }
    EXPECT_NEAR(len, ref->cost, 1e-9);
    EXPECT_EQ(got->front(), s);
    EXPECT_EQ(got->back(), g);
  }
}

TEST(LaneAstar, StationToStationRoutesKeepToTheLanes) {
  // Between the wide bands (parking at the bottom, pickups at the top, drop-offs on the right) a
  // legal route always exists; the planner takes it in every direction.
  const auto raw = smallWarehouse();
  const auto grid = raw.inflated(0.5);
  const auto lanes = LaneMap::derive(raw);
  const std::vector<Cell> stations = {{8, 2},   {20, 2}, {7, 34},  {29, 34},
                                      {51, 34}, {56, 8}, {56, 20}, {3, 14}};
  int routes = 0;
  for (const Cell a : stations) {
    for (const Cell b : stations) {
      if (a == b) {
        continue;
      }
      const auto path = laneAstar(grid, lanes, a, b);
      ASSERT_TRUE(path) << path.error().message;
      EXPECT_EQ(wrongWayMoves(lanes, *path), 0)
          << "(" << a.x << "," << a.y << ") -> (" << b.x << "," << b.y << ")";
      ++routes;
    }
  }
  EXPECT_EQ(routes, 56);
}

TEST(LaneAstar, OppositeTripsUseDifferentAisles) {
  // Left band to right band and back through the shelf rows: the two trips must not share a
  // one-way aisle in opposite directions (no head-on encounter possible).
  const auto raw = smallWarehouse();
  const auto grid = raw.inflated(0.5);
  const auto lanes = LaneMap::derive(raw);
  const auto there = laneAstar(grid, lanes, {3, 13}, {50, 13});
  const auto back = laneAstar(grid, lanes, {50, 13}, {3, 13});
  ASSERT_TRUE(there && back);
  EXPECT_EQ(wrongWayMoves(lanes, *there), 0);
  EXPECT_EQ(wrongWayMoves(lanes, *back), 0);
}

TEST(LaneAstar, DeadEndIsStillReachable) {
  // A one-way aisle closed at its far end: the way in and out is against the lane for one leg, and
  // the planner must still find it rather than report the goal unreachable.
  OccupancyGrid g(30, 9, 0.5);
  for (int x = 0; x < 30; ++x) {
    g.setBlocked({x, 0});
    g.setBlocked({x, 8});
    if (x > 5) {
      g.setBlocked({x, 1});
      g.setBlocked({x, 2});
      g.setBlocked({x, 6});
      g.setBlocked({x, 7});
    }
  }
  for (int y = 0; y < 9; ++y) {
    g.setBlocked({0, y});
    g.setBlocked({29, y});
  }
  const auto lanes = LaneMap::derive(g);
  ASSERT_NE(lanes.at({15, 4}), LaneDir{});
  const auto in = laneAstar(g, lanes, {2, 4}, {27, 4});
  const auto out = laneAstar(g, lanes, {27, 4}, {2, 4});
  ASSERT_TRUE(in && out);
  EXPECT_GT(wrongWayMoves(lanes, *in) + wrongWayMoves(lanes, *out), 0);
  const auto blockedGoal = laneAstar(g, lanes, {2, 4}, {15, 1});
  EXPECT_FALSE(blockedGoal);
}

TEST(LaneAstar, CellsOffTheLaneMapAreTwoWay) {
  // A layer asked about cells its map does not cover (another map's) adds nothing: no lane there.
  const auto lanes = std::make_shared<const LaneMap>(LaneMap::derive(smallWarehouse()));
  EXPECT_EQ(lanes->at({-1, 3}), LaneDir{});
  EXPECT_EQ(lanes->at({500, 3}), LaneDir{});
  EXPECT_EQ(LaneCost(lanes).factor({499, 3}, {500, 3}), 1.0);
}

TEST(LaneAstar, CellCostFactorSteersAroundCostlyCells) {
  // A costly band across the direct route between the left and right bands: with the factor the
  // route goes through another aisle, without it straight through; factors below 1 change nothing.
  const auto raw = smallWarehouse();
  const auto grid = raw.inflated(0.5);
  const auto lanes = LaneMap::derive(raw);
  const Cell from{3, 18};
  const Cell to{50, 18};
  const auto plain = laneAstar(grid, lanes, from, to);
  ASSERT_TRUE(plain);
  auto crosses = [](const std::vector<Cell>& cells, int y0, int y1) {
    return std::any_of(cells.begin(), cells.end(),
                       [&](Cell c) { return c.x == 30 && c.y >= y0 && c.y <= y1; });
  };
  ASSERT_TRUE(crosses(*plain, 15, 21));
  const auto costly = laneAstar(grid, lanes, from, to,
                                [](Cell c) { return c.x == 30 && c.y >= 15 && c.y <= 21 ? 50.0 : 1.0; });
  ASSERT_TRUE(costly);
  EXPECT_FALSE(crosses(*costly, 15, 21));
  const auto cheap = laneAstar(grid, lanes, from, to, [](Cell) { return 0.1; });
  ASSERT_TRUE(cheap);
  EXPECT_EQ(cheap->size(), plain->size());
}
