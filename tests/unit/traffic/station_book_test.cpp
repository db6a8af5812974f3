// The virtual fleet's station book (admission by predicted arrival) on the small warehouse: from a
// node its travel times are the roadmap's dock-to-dock ones, each line's cycle is the dwell plus
// the fleet bound's least dock motion, and a booked robot's leave agrees with the line's arithmetic
// (fleet/core/station_slots).

#include "fleet/traffic/station_book.hpp"

#include <gtest/gtest.h>

#include <filesystem>
#include <random>

#include "fleet/site/site_loader.hpp"
#include "fleet/traffic/roadmap_travel.hpp"
#include "fleet/traffic/station_cycle.hpp"

namespace fleet::traffic {
namespace {

std::shared_ptr<const Roadmap> smallWarehouse() {
  const auto site = site::loadSite(
      (std::filesystem::path(FLEET_SOURCE_DIR) / "sim/scenarios/small_warehouse.site.json").string());
  return std::make_shared<const Roadmap>(buildRoadmap(site));
}

std::vector<NodeId> served(const Roadmap& r) {
  std::vector<NodeId> out;
  for (const auto& s : r.stations) {
    if (s.dock != kNoNode && (s.kind == site::StationKind::Pickup || s.kind == site::StationKind::Dropoff)) {
      out.push_back(s.dock);
    }
  }
  return out;
}

TEST(StationBook, TravelAndCycleAreTheRoadmapsAndTheFleetBoundsAndLinesAsLongAsTheQueues) {
  const auto map = smallWarehouse();
  const RoadmapTravel roads(map);
  const StationBook book(roads, served(*map), 2.0);
  for (const auto& s : map->stations) {
    if (s.dock == kNoNode || (s.kind != site::StationKind::Pickup && s.kind != site::StationKind::Dropoff)) {
      continue;
    }
    SCOPED_TRACE(s.name);
    EXPECT_EQ(book.slots(s.dock), 1 + s.queue.size());
    EXPECT_EQ(book.slots(s.dock), roads.lineCapacity(s.name));
    EXPECT_DOUBLE_EQ(book.cycle(s.dock), 2.0 + roads.dockMoveSeconds(s.name));
    EXPECT_GT(roads.dockMoveSeconds(s.name), 0.0);
    for (const auto& t : map->stations) {
      if (t.dock != kNoNode) {
        EXPECT_NEAR(book.travel(t.dock, s.dock), *roads.between(t.name, s.name), 1e-4);
      }
    }
  }
  EXPECT_THROW((void)book.cycle(map->stations.front().dock), std::out_of_range)
      << "a parking place is not served";
  EXPECT_EQ(StationBook(roads, served(*map), 2.0, 1).slots(served(*map).front()), 1U);
}

TEST(StationBook, ABookedRobotLeavesWhenTheLinesArithmeticSays) {
  const auto map = smallWarehouse();
  const RoadmapTravel roads(map);
  StationBook book(roads, served(*map), 2.0);
  const NodeId dock = served(*map).front();
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> when(-5.0, 60.0);
  for (int trial = 0; trial < 50; ++trial) {
    book.clear();
    std::vector<double> arrivals(1 + rng() % 6);
    for (double& a : arrivals) {
      a = when(rng);
      (void)book.book(dock, a);
    }
    for (std::size_t k = 0; k < arrivals.size(); ++k) {
      std::vector<double> others = arrivals;
      others.erase(others.begin() + static_cast<std::ptrdiff_t>(k));
      // Distinct random arrivals: the order among equal ones does not arise.
      EXPECT_NEAR(book.leave(dock, k), offerSlot(others, arrivals[k], book.cycle(dock), 0).leave, 1e-9);
    }
    const auto o = book.offer(dock, 30.0);
    EXPECT_EQ(o.admitted, offerSlot(arrivals, 30.0, book.cycle(dock), book.slots(dock)).admitted);
  }
}

}  // namespace
}  // namespace fleet::traffic
