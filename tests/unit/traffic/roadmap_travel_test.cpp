// Travel times on the roadmap (the fleet manager's costs in reserved traffic): exact against a
// search of their own, bounded below by the straight line, a triangle inequality over stations,
// and station lines as long as the roadmap's queues.

#include "fleet/traffic/roadmap_travel.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <limits>
#include <queue>

#include "fleet/site/site_loader.hpp"
#include "roadmap_test_support.hpp"

namespace fleet::traffic {
namespace {

namespace fs = std::filesystem;

// Unguided: travel is then the shortest time. On a guided roadmap it is the seconds of the guided
// way (Guidance.TravelTimesAreTheSecondsOfTheGuidedWay).
std::shared_ptr<const Roadmap> smallWarehouse() {
  const auto site =
      site::loadSite((fs::path(FLEET_SOURCE_DIR) / "sim/scenarios/small_warehouse.site.json").string());
  return std::make_shared<const Roadmap>(buildRoadmap(site, {.guidance = 0.0}));
}

// The shortest time over open edges, searched forward apart from DistanceTable's backward one.
double forward(const Roadmap& r, NodeId from, NodeId to) {
  return test::shortestTime(r.graph, from, to);
}

TEST(RoadmapTravel, StationToStationIsTheShortestRouteOnTheRoadmap) {
  const auto roadmap = smallWarehouse();
  const RoadmapTravel travel(roadmap);
  std::size_t pairs = 0;
  for (const auto& a : roadmap->stations) {
    for (const auto& b : roadmap->stations) {
      if (a.dock == kNoNode || b.dock == kNoNode || (pairs++ % 7) != 0) {
        continue;  // every 7th pair: the search is the slow part of the test
      }
      const auto t = travel.between(a.name, b.name);
      ASSERT_TRUE(t) << a.name << " → " << b.name;
      EXPECT_NEAR(*t, forward(*roadmap, a.dock, b.dock), 1e-3) << a.name << " → " << b.name;
      // Never faster than the straight line at cruise speed.
      const double line = distance(roadmap->graph.position(a.dock), roadmap->graph.position(b.dock));
      EXPECT_GE(*t + 1e-6, line / roadmap->options.cruiseSpeed) << a.name << " → " << b.name;
    }
  }
  EXPECT_GT(pairs, 100U);
}

TEST(RoadmapTravel, ThroughAThirdStationIsNeverShorter) {
  const auto roadmap = smallWarehouse();
  const RoadmapTravel travel(roadmap);
  const auto& s = roadmap->stations;
  for (std::size_t i = 0; i < s.size(); i += 3) {
    for (std::size_t j = 1; j < s.size(); j += 5) {
      for (std::size_t k = 2; k < s.size(); k += 7) {
        const auto ik = travel.between(s[i].name, s[k].name);
        const auto ij = travel.between(s[i].name, s[j].name);
        const auto jk = travel.between(s[j].name, s[k].name);
        if (ik && ij && jk) {
          EXPECT_LE(*ik, *ij + *jk + 1e-3) << s[i].name << " " << s[j].name << " " << s[k].name;
        }
      }
    }
  }
}

TEST(RoadmapTravel, FromAPointIsTheLegToItsNodeAndOnFromThere) {
  const auto roadmap = smallWarehouse();
  const RoadmapTravel travel(roadmap);
  const auto& p1 = *roadmap->station("P-1");
  const auto& d1 = *roadmap->station("D-1");
  const Vec2 dock = roadmap->graph.position(p1.dock);
  EXPECT_NEAR(*travel.toStation(dock, "D-1"), *travel.between("P-1", "D-1"), 1e-6);
  EXPECT_NEAR(*travel.toStation(roadmap->graph.position(d1.dock), "D-1"), 0.0, 1e-9);
  // A few centimetres off the dock: the leg back onto it at cruise speed comes on top.
  const Vec2 off = dock + Vec2{0.0, 0.04};
  ASSERT_EQ(roadmap->nearest(off), p1.dock);
  EXPECT_NEAR(*travel.toStation(off, "D-1"),
              *travel.between("P-1", "D-1") + 0.04 / roadmap->options.cruiseSpeed, 1e-6);
}

TEST(RoadmapTravel, UnknownStationsHaveNoTimeAndLinesAreDockPlusQueue) {
  const auto roadmap = smallWarehouse();
  const RoadmapTravel travel(roadmap);
  EXPECT_FALSE(travel.toStation({1.0, 1.0}, "NOWHERE"));
  EXPECT_FALSE(travel.between("P-1", "NOWHERE"));
  EXPECT_EQ(travel.lineCapacity("NOWHERE"), 0U);
  std::size_t withQueue = 0;
  for (const auto& st : roadmap->stations) {
    if (st.dock == kNoNode) {
      EXPECT_EQ(travel.lineCapacity(st.name), 0U) << st.name;
      continue;
    }
    EXPECT_EQ(travel.lineCapacity(st.name), 1 + st.queue.size()) << st.name;
    withQueue += st.queue.empty() ? 0 : 1;
  }
  EXPECT_GT(withQueue, 4U) << "the pickups and drop-offs have queues";
}

}  // namespace
}  // namespace fleet::traffic
