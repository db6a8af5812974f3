// Admission by predicted arrival in the dispatcher (StationLoad::Arrival): a robot bound for a
// station holds a place in its line from when it will get there, not from when it was given the
// task. Times here are straight lines at 1 m/s along x; every dock cycle's motion is 2 s.

#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "fleet/fleet/dispatcher.hpp"
#include "fleet/fleet/sqlite_task_store.hpp"
#include "line_world.hpp"
#include "temp_dir.hpp"

namespace fleet {
namespace {

using S = TaskState;

StationMap stations() {
  StationMap m;
  EXPECT_TRUE(m.add({"P-1", {0, 0, 0}, static_cast<std::uint8_t>(StationKind::Pickup)}));
  EXPECT_TRUE(m.add({"D-1", {20, 0, 0}, static_cast<std::uint8_t>(StationKind::Dropoff)}));
  EXPECT_TRUE(m.add({"D-2", {40, 0, 0}, static_cast<std::uint8_t>(StationKind::Dropoff)}));
  return m;
}

Task transport(std::string id, std::string dropoff = "D-1") {
  return test::transportTask(std::move(id), "P-1", std::move(dropoff));
}

class DispatcherArrivalTest : public ::testing::Test {
 protected:
  void SetUp() override {
    cfg.stationLoad = StationLoad::Arrival;
    cfg.stationCapacities = {{"P-1", 1}, {"D-1", 1}, {"D-2", 1}};
    cfg.stationTimes = test::straightLineTimes(map);
    auto s = SqliteTaskStore::open({dir.file("tasks.db")});
    ASSERT_TRUE(s) << s.error().message;
    store = std::move(s).value();
    dispatcher = std::make_unique<Dispatcher>(*store, map, test::distanceToPickup(map), cfg);
  }
  void robot(const std::string& id, double x, std::int64_t t) {
    dispatcher->onRobotState({id, {x, 0, 0}, 0.9, t});
  }
  std::string reasonOf(const std::string& id) { return store->get(id).value().reason; }
  /// r1 stands at P-1 with t1 (to D-1); r2 is 1 s away and t2 (to D-2) is held: its robot would
  /// find r1 still loading, and P-1's line holds one.
  void t2WaitsBehindT1AtP1() {
    robot("r1", 0, 0);
    dispatcher->submit({transport("t1", "D-1")}, 0);
    ASSERT_EQ(dispatcher->tick(1).assignments.size(), 1u);
    robot("r2", 1, 2);
    dispatcher->submit({transport("t2", "D-2")}, 2);
    EXPECT_TRUE(dispatcher->tick(3).assignments.empty());
  }

  test::TempDir dir;
  StationMap map = stations();
  DispatcherConfig cfg;
  std::unique_ptr<SqliteTaskStore> store;
  std::unique_ptr<Dispatcher> dispatcher;
};

TEST_F(DispatcherArrivalTest, ARobotFarFromItsPickupLeavesTheLineToOneThatWillBeThereFirst) {
  // r-far is 100 s from P-1 with t1; r-near is at P-1. By slots counted now t2 would wait for t1
  // to load; by arrival r-near loads (4 s) and leaves long before r-far comes.
  robot("r-far", 100, 0);
  dispatcher->submit({transport("t1", "D-1")}, 0);
  const auto first = dispatcher->tick(1);
  ASSERT_EQ(first.assignments.size(), 1u);
  robot("r-near", 0, 2);
  dispatcher->submit({transport("t2", "D-2")}, 2);
  const auto second = dispatcher->tick(3);
  ASSERT_EQ(second.assignments.size(), 1u) << reasonOf("t2");
  EXPECT_EQ(second.assignments[0].robotId, "r-near");
}

TEST_F(DispatcherArrivalTest, ARobotThatWouldMeetTheLineFullWaitsAndSaysWhy) {
  // r1 stands at P-1 with t1; r2 is 1 s away: its robot would find r1 still loading, and the line
  // holds one. t2 waits with a reason naming the station, and goes once t1 has loaded and left.
  t2WaitsBehindT1AtP1();
  EXPECT_EQ(reasonOf("t2"),
            "waiting for a place in station P-1's line (it holds 1, all taken when a robot "
            "could get there)");
  ASSERT_TRUE(dispatcher->onTaskStatus("r1", "t1", S::Delivering, "", 4));
  robot("r1", 15, 5);  // 5 s from D-1
  const auto next = dispatcher->tick(6);
  ASSERT_EQ(next.assignments.size(), 1u);
  EXPECT_EQ(next.assignments[0].task.id, "t2");
}

TEST_F(DispatcherArrivalTest, ALoadThatWouldMeetItsDropOffsLineFullIsHeld) {
  // r1 carries t1 to D-1 from 25 s away (there at 25, served until 29). A robot at P-1 with t2 for
  // D-1 would load (4 s) and be there at 24, still unloading when r1 comes: held, naming D-1. t3
  // for D-2 goes.
  robot("r1", 0, 0);
  dispatcher->submit({transport("t1", "D-1")}, 0);
  ASSERT_EQ(dispatcher->tick(1).assignments.size(), 1u);
  ASSERT_TRUE(dispatcher->onTaskStatus("r1", "t1", S::Delivering, "", 2));
  robot("r1", -5, 3);
  robot("r2", 0, 3);
  dispatcher->submit({transport("t2", "D-1"), transport("t3", "D-2")}, 3);
  const auto out = dispatcher->tick(4);
  ASSERT_EQ(out.assignments.size(), 1u);
  EXPECT_EQ(out.assignments[0].task.id, "t3");
  EXPECT_NE(reasonOf("t2").find("station D-1's line"), std::string::npos) << reasonOf("t2");
}

TEST_F(DispatcherArrivalTest, NoMoreTasksAreAdmittedThanThereAreIdleRobots) {
  // One idle robot at P-1 (a line of one) and two tasks: t1 takes the robot. t2 is not looked at
  // this dispatch, so it is not said to wait for a place in P-1's line, which t1's booking would
  // otherwise fill (it waits for a robot).
  robot("r1", 0, 0);
  dispatcher->submit({transport("t1", "D-1"), transport("t2", "D-2")}, 0);
  const auto out = dispatcher->tick(1);
  ASSERT_EQ(out.assignments.size(), 1u);
  EXPECT_EQ(out.assignments[0].task.id, "t1");
  EXPECT_EQ(reasonOf("t2").find("waiting for a place"), std::string::npos) << reasonOf("t2");
}

TEST_F(DispatcherArrivalTest, ATaskNoRobotIsLeftForNoLongerSaysItWaitsForAPlace) {
  // t2 waits for a place in P-1's line; when P-1 is free again an urgent t3 takes the only idle
  // robot, so t2 is not looked at. Its reason must not still name P-1's line.
  t2WaitsBehindT1AtP1();
  ASSERT_NE(reasonOf("t2").find("for a place in station P-1"), std::string::npos) << reasonOf("t2");
  ASSERT_TRUE(dispatcher->onTaskStatus("r1", "t1", S::Delivering, "", 4));
  robot("r1", 15, 5);
  Task urgent = transport("t3", "D-2");
  urgent.priority = 5;
  dispatcher->submit({urgent}, 5);
  const auto out = dispatcher->tick(6);
  ASSERT_EQ(out.assignments.size(), 1u);
  EXPECT_EQ(out.assignments[0].task.id, "t3");
  EXPECT_EQ(reasonOf("t2"), "waiting for a robot (every idle one has an older or more urgent task)");
}

}  // namespace
}  // namespace fleet
