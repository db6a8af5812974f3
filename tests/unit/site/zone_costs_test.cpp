// The site's zones as cost layers of the one A*: one-way zones price a wrong-way move, speed zones
// price slow cells as travel time, and a route keeps to both.

#include "fleet/site/zone_costs.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <memory>

#include "fleet/planning/astar.hpp"
#include "fleet/site/site_loader.hpp"

namespace fleet::site {
namespace {

// A 10 m x 3 m hall at 0.5 m: the lower half (rows 0-2) one-way eastward, a slow patch (0.2 m/s)
// in the middle of rows 3-4, the top row free.
std::shared_ptr<const Site> hall() {
  auto s = std::make_shared<Site>();
  s->name = "hall";
  s->map = planning::OccupancyGrid(20, 6, 0.5);
  const std::size_t n = s->map.size();
  s->layers.noGo.assign(n, 0);
  s->layers.speedLimit.assign(n, std::numeric_limits<float>::infinity());
  s->layers.oneWay.assign(n, std::numeric_limits<float>::quiet_NaN());
  for (int x = 0; x < 20; ++x) {
    for (int y = 0; y < 3; ++y) {
      s->layers.oneWay[s->map.index({x, y})] = 0.0f;
    }
  }
  for (int x = 8; x < 12; ++x) {
    for (int y = 3; y < 5; ++y) {
      s->layers.speedLimit[s->map.index({x, y})] = 0.2f;
    }
  }
  return s;
}

}  // namespace

TEST(ZoneCosts, OneWayPricesOnlyMovesMoreThan90DegreesOff) {
  const OneWayCost c(hall(), 10.0);
  EXPECT_EQ(c.factor({4, 1}, {5, 1}), 1.0) << "with the zone";
  EXPECT_EQ(c.factor({5, 1}, {4, 1}), 10.0) << "against it";
  EXPECT_EQ(c.factor({5, 1}, {5, 2}), 1.0) << "across it";
  EXPECT_EQ(c.factor({5, 1}, {4, 2}), 10.0) << "diagonally back";
  EXPECT_EQ(c.factor({5, 4}, {4, 4}), 1.0) << "outside the zone";
  EXPECT_EQ(c.factor({5, 3}, {4, 2}), 10.0) << "entering the zone the wrong way";
  EXPECT_EQ(c.factor({-1, 1}, {-2, 1}), 1.0) << "off the map";
}

TEST(ZoneCosts, SpeedZonesCostTravelTimeAtCruise) {
  const SpeedZoneCost c(hall(), 0.8);
  EXPECT_EQ(c.factor({7, 4}, {8, 4}), 0.8 / static_cast<double>(0.2f));
  EXPECT_EQ(c.factor({8, 4}, {7, 4}), 1.0) << "leaving the slow patch costs the cell entered";
  const SpeedZoneCost fast(hall(), 0.1);
  EXPECT_EQ(fast.factor({7, 4}, {8, 4}), 1.0) << "a limit above the cruise speed changes nothing";
}

TEST(ZoneCosts, LayersOnlyForTheZonesASiteHas) {
  EXPECT_EQ(zoneCostLayers(hall(), 0.8).size(), 2u);
  EXPECT_EQ(zoneCostLayers(hall(), 0.1).size(), 1u);
  EXPECT_TRUE(zoneCostLayers(nullptr, 0.8).empty());
  const auto shipped =
      std::make_shared<const Site>(loadSite(FLEET_SOURCE_DIR "/sim/scenarios/small_warehouse.site.json"));
  EXPECT_TRUE(zoneCostLayers(shipped, 0.8).empty()) << "no zones, no layers: the plain fixed-point A*";
}

TEST(ZoneCosts, ARouteKeepsToTheOneWayZoneAndGoesRoundTheSlowPatch) {
  const auto s = hall();
  const auto layers = zoneCostLayers(s, 0.8);
  // Westward along the lower half: the route climbs to the upper half (the one-way runs east)...
  const auto west = planning::astar(s->map, {18, 1}, {1, 1}, layers);
  ASSERT_TRUE(west);
  int wrongWay = 0;
  int slow = 0;
  for (std::size_t i = 1; i < west->cells.size(); ++i) {
    wrongWay += layers[0]->factor(west->cells[i - 1], west->cells[i]) > 1.0 ? 1 : 0;
    slow += layers[1]->factor(west->cells[i - 1], west->cells[i]) > 1.0 ? 1 : 0;
  }
  EXPECT_EQ(wrongWay, 0);
  EXPECT_EQ(slow, 0) << "... and passes the slow patch on the top row";
  // ... eastward it stays in the lower half, the straight line.
  const auto east = planning::astar(s->map, {1, 1}, {18, 1}, layers);
  ASSERT_TRUE(east);
  EXPECT_NEAR(east->cost, 17.0, 1e-9);
}

}  // namespace fleet::site
