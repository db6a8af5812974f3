// The fleet bound on a tiny hand-made site whose answer is known by hand: an empty walled room,
// so every way is a straight line.

#include "fleet_bound.hpp"

#include <gtest/gtest.h>

namespace fleet::ctl {
namespace {

using planning::OccupancyGrid;

/// A walled room of 6 m × 4 m at 0.1 m cells (the walls are its border cells).
OccupancyGrid room() {
  OccupancyGrid g(60, 40, 0.1);
  for (int x = 0; x < 60; ++x) {
    g.setBlocked({x, 0});
    g.setBlocked({x, 39});
  }
  for (int y = 0; y < 40; ++y) {
    g.setBlocked({0, y});
    g.setBlocked({59, y});
  }
  return g;
}

// A at (1, 1) with its approach 1 m up and its queue head 1 m beyond; B at (4, 1), bare. Disc
// radius 0.2 m (diameter 0.4), cruise 1 m/s, load 1 s, unload 2 s.
FleetBoundInput twoTasks(std::vector<Vec2> starts) {
  FleetBoundInput in;
  in.stations = {{"A", {{1.0, 1.0}, Vec2{1.0, 2.0}, {{1.0, 3.0}}, std::nullopt}},
                 {"B", {{4.0, 1.0}, std::nullopt, {}, std::nullopt}}};
  in.tasks = {ListTask::transport("A", "B", 1.0, 2.0), ListTask::transport("A", "B", 1.0, 2.0)};
  in.starts = std::move(starts);
  in.radius = 0.2;
  in.cruise = 1.0;
  return in;
}

TEST(StationCycle, LegOutWaitOrDiameterAndLegInAtCruise) {
  // |dock − approach| = 1, |queue head − approach| = 1 > 2r: (1 + 1 + 1) / 1 m/s.
  EXPECT_DOUBLE_EQ(dockMoveSeconds({{1, 1}, Vec2{1, 2}, {{1, 3}}, std::nullopt}, 0.2, 1.0), 3.0);
  // A queue head closer than a diameter to the approach point: the diameter counts.
  EXPECT_DOUBLE_EQ(dockMoveSeconds({{1, 1}, Vec2{1, 2}, {{1, 2.1}}, std::nullopt}, 0.2, 1.0), 2.4);
  // No approach, no queue: a diameter at 0.5 m/s.
  EXPECT_DOUBLE_EQ(dockMoveSeconds({{4, 1}, std::nullopt, {}, std::nullopt}, 0.2, 0.5), 0.8);
  // A server (an exit of its own): the next robot drives in from the queue head as the last one
  // leaves, so only its own way in counts: 1 + 1 m at 1 m/s, whatever the exit.
  EXPECT_DOUBLE_EQ(dockMoveSeconds({{1, 1}, Vec2{1, 2}, {{1, 3}}, Vec2{2, 2}}, 0.2, 1.0), 2.0);
  EXPECT_DOUBLE_EQ(dockMoveSeconds({{4, 1}, std::nullopt, {}, Vec2{5, 1}}, 0.2, 0.5), 0.8);
  EXPECT_EQ(dockMoveSeconds({{4, 1}, std::nullopt, {}, std::nullopt}, 0.2, 0.0), 0.0);
}

TEST(FleetBound, LoneRobotChainsTheListInPostingOrder) {
  const auto b = fleetBound(room(), twoTasks({{1.0, 3.0}}));
  ASSERT_TRUE(b) << b.error().message;
  // start→A 2 m, A→B 3, B→A 3, A→B 3 = 11 m at 1 m/s, plus 2 × (1 + 2) s of dwell = 17 s for 2 tasks.
  EXPECT_NEAR(b->chainDriveM, 11.0, 1e-6);
  EXPECT_NEAR(b->chainS, 17.0, 1e-6);
  EXPECT_NEAR(b->lonePerH, 7200.0 / 17.0, 1e-3);
  EXPECT_NEAR(b->robotPerH, 7200.0 / 17.0, 1e-3);
  // A: c = 3 s of motion + 1 s of loading, two visits in two tasks (f = 1): 900 tasks/h.
  // B: c = 0.4 s + 2 s of unloading, f = 1: 1,500 tasks/h.
  ASSERT_EQ(b->stations.size(), 2u);
  EXPECT_EQ(b->stations[0].name, "A");
  EXPECT_NEAR(b->stations[0].cycleS, 4.0, 1e-9);
  EXPECT_NEAR(b->stations[0].share, 1.0, 1e-12);
  EXPECT_NEAR(b->stations[0].boundPerH, 900.0, 1e-9);
  EXPECT_NEAR(b->stations[1].boundPerH, 1500.0, 1e-9);
  EXPECT_EQ(b->bindingStation, "A");
  EXPECT_TRUE(b->robotsBind());
  EXPECT_NEAR(b->perH(), 7200.0 / 17.0, 1e-3);
}

TEST(FleetBound, ManyRobotsAreBoundByTheBusiestStationAndTheBestStartCounts) {
  // Four robots; the best start is 0.5 m from A: 9.5 m + 6 s = 15.5 s for the lone robot.
  const auto b = fleetBound(room(), twoTasks({{1.0, 3.0}, {1.0, 1.5}, {5.0, 3.0}, {3.0, 3.0}}));
  ASSERT_TRUE(b) << b.error().message;
  EXPECT_NEAR(b->chainS, 15.5, 1e-6);
  EXPECT_NEAR(b->robotPerH, 4.0 * 7200.0 / 15.5, 1e-3);
  EXPECT_FALSE(b->robotsBind());
  EXPECT_NEAR(b->perH(), 900.0, 1e-9);
  EXPECT_EQ(b->bindingStation, "A");
}

TEST(FleetBound, BadInputIsNamed) {
  auto in = twoTasks({{1.0, 3.0}});
  in.tasks[1].stops[1].station = "C";
  auto b = fleetBound(room(), in);
  ASSERT_FALSE(b);
  EXPECT_EQ(b.error().code, "unknown_station");
  EXPECT_NE(b.error().message.find("'C'"), std::string::npos);

  EXPECT_EQ(fleetBound(room(), twoTasks({})).error().code, "bad_input");
  in = twoTasks({{1.0, 3.0}});
  in.cruise = 0.0;
  EXPECT_EQ(fleetBound(room(), in).error().code, "bad_input");
  in = twoTasks({{1.0, 3.0}});
  in.tasks[0].stops[0].dwellS = -1.0;
  EXPECT_EQ(fleetBound(room(), in).error().code, "bad_input");
  in = twoTasks({{1.0, 3.0}});
  in.tasks[1].stops.clear();  // a task without a stop
  EXPECT_EQ(fleetBound(room(), in).error().code, "bad_input");
  in = twoTasks({{1.0, 3.0}});
  in.tasks = {ListTask{{{"", 5.0}}}};  // only waits: no station to go to
  EXPECT_EQ(fleetBound(room(), in).error().code, "bad_input");
  EXPECT_EQ(fleetBound(OccupancyGrid(), twoTasks({{1.0, 3.0}})).error().code, "bad_input");
}

// A multi-stop task is its stops in order: each one a leg of the chain and a visit of its station,
// a wait where the robot stands only dwell.
TEST(FleetBound, AMultiStopTaskChainsEveryStopAndVisitsEachStation) {
  auto in = twoTasks({{1.0, 3.0}});
  // A (pick, 1 s) → B (drop, 2 s) → wait 4 s where it stands → A (goto, 0 s), then A → B as before.
  in.tasks[0] = ListTask{{{"A", 1.0}, {"B", 2.0}, {"", 4.0}, {"A", 0.0}}};
  const auto b = fleetBound(room(), in);
  ASSERT_TRUE(b) << b.error().message;
  // start→A 2 m, A→B 3, B→A 3 (the goto), A→A 0 (the next task's pickup), A→B 3 = 11 m; dwell
  // 1 + 2 + 4 + 0 + 1 + 2 = 10 s: 21 s for 2 tasks.
  EXPECT_NEAR(b->chainDriveM, 11.0, 1e-6);
  EXPECT_NEAR(b->chainS, 21.0, 1e-6);
  // A visited 3 times in 2 tasks, B twice.
  ASSERT_EQ(b->stations.size(), 2U);
  for (const auto& s : b->stations) {
    EXPECT_EQ(s.visits, s.name == "A" ? 3U : 2U) << s.name;
    EXPECT_NEAR(s.share, s.name == "A" ? 1.5 : 1.0, 1e-12) << s.name;
  }
}

TEST(FleetBound, AStationBehindAWallIsUnreachable) {
  OccupancyGrid g = room();
  for (int y = 0; y < 40; ++y) {
    g.setBlocked({30, y});  // a wall across at x = 3 m: B is cut off
  }
  const auto b = fleetBound(g, twoTasks({{1.0, 3.0}}));
  ASSERT_FALSE(b);
  EXPECT_EQ(b.error().code, "unreachable");
  // The first leg found cut off is named: back from B's dock to A (legs are taken goal by goal).
  EXPECT_NE(b.error().message.find("to A from (4.0"), std::string::npos) << b.error().message;
}

}  // namespace
}  // namespace fleet::ctl
