// Held robots and the distance tables: who the routes go round, and what that costs the tables.

#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "fleet/site/site_loader.hpp"
#include "fleet/traffic/distance_table.hpp"
#include "fleet/traffic/pibt.hpp"
#include "fleet/traffic/roadmap.hpp"
#include "fleet/traffic/traffic_control.hpp"
#include "pibt_test_support.hpp"

namespace fleet::traffic {
namespace {

using test::gridOf;

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
  // A real change does restart the table that settled the node, and routes round it.
  t.setBlocked(v, true);
  EXPECT_EQ(t.distance(m.node(0, 0), goal), 6.0F);
  EXPECT_EQ(t.computed(), before + 1);
}

TEST(Pibt, AnAgentOutOfControlIsRoutedRoundOnlyWhenAsked) {
  const GridMap m = gridOf({
      ".....",
      ".....",
  });
  const std::vector<NodeId> starts{m.node(0, 0), m.node(2, 0)};
  Pibt p(m.graph, starts, PibtOptions{.detourAfter = 4});
  p.setGoal(0, m.node(4, 0));
  p.setControlled(1, false, false);  // fixed, but the routes still pass its node
  EXPECT_FALSE(p.controlled(1));
  EXPECT_FALSE(p.routedAround(1));
  EXPECT_FALSE(p.distances().blocked(starts[1]));
  EXPECT_EQ(p.distances().distance(starts[0], m.node(4, 0)), 4.0F);
  p.setControlled(1, false, true);  // only adds the blocking
  EXPECT_TRUE(p.routedAround(1));
  EXPECT_TRUE(p.distances().blocked(starts[1]));
  EXPECT_EQ(p.distances().distance(starts[0], m.node(4, 0)), 6.0F);
  p.reset(p.positions());  // a replan keeps it blocked, once
  EXPECT_TRUE(p.distances().blocked(starts[1]));
  p.setControlled(1, true);
  EXPECT_FALSE(p.routedAround(1));
  EXPECT_FALSE(p.distances().blocked(starts[1]));
  // Not routed round, the fixed agent is stood behind, then detoured round as any agent standing
  // that long; the one on its way never steps onto its node.
  p.setControlled(1, false, false);
  for (int s = 0; s < 16; ++s) {
    p.step();
    EXPECT_EQ(p.positions()[1], starts[1]);
    EXPECT_NE(p.positions()[0], starts[1]);
  }
  EXPECT_EQ(p.positions()[0], m.node(4, 0));
}

TEST(TrafficControl, ARobotHeldAtItsGoalIsNotRoutedRoundOneHeldOnItsWayIs) {
  const auto site =
      site::loadSite(std::string(FLEET_SOURCE_DIR) + "/sim/scenarios/small_warehouse.site.json");
  const Roadmap map = buildRoadmap(site);
  const NodeId docked = map.station("PARK-1")->dock;
  const NodeId onItsWay = map.station("PARK-5")->dock;
  const std::vector<NodeId> starts{docked, onItsWay};
  TrafficControl tc(map.graph, starts);
  tc.setStations(stationLines(map));
  tc.setGoal(0, docked);  // there: docking, dwelling
  tc.setGoal(1, map.station("P-3")->dock);
  ASSERT_TRUE(tc.arrived(0));
  ASSERT_FALSE(tc.arrived(1));
  tc.setHeld(0, true);
  tc.setHeld(1, true);
  EXPECT_FALSE(tc.planner().routedAround(0));
  EXPECT_FALSE(tc.planner().distances().blocked(docked));
  EXPECT_TRUE(tc.planner().routedAround(1));
  EXPECT_TRUE(tc.planner().distances().blocked(onItsWay));
  tc.setHeld(1, false);
  EXPECT_FALSE(tc.planner().routedAround(1));
  EXPECT_FALSE(tc.planner().distances().blocked(onItsWay));
}

}  // namespace
}  // namespace fleet::traffic
