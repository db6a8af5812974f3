// The expected queue wait in the assignment's cost (DispatcherConfig::stationTimes known): a
// transport task costs a robot its travel plus its wait in the task's pickup and drop-off lines
// behind the robots booked there at their predicted arrival. Times are straight lines at 1 m/s
// along x; every dock cycle's motion is 2 s and every dwell 2 s, so a robot at a dock leaves its
// line 4 s after it got there.

#include <gtest/gtest.h>

#include <cmath>
#include <memory>
#include <string>

#include "fleet/fleet/dispatcher.hpp"
#include "fleet/fleet/sqlite_task_store.hpp"
#include "line_world.hpp"
#include "temp_dir.hpp"

namespace fleet {
namespace {

StationMap stations() {
  StationMap m;
  EXPECT_TRUE(m.add({"P-1", {0, 0, 0}, static_cast<std::uint8_t>(StationKind::Pickup)}));
  EXPECT_TRUE(m.add({"P-2", {2, 0, 0}, static_cast<std::uint8_t>(StationKind::Pickup)}));
  EXPECT_TRUE(m.add({"D-1", {20, 0, 0}, static_cast<std::uint8_t>(StationKind::Dropoff)}));
  EXPECT_TRUE(m.add({"D-2", {24, 0, 0}, static_cast<std::uint8_t>(StationKind::Dropoff)}));
  return m;
}

class DispatcherQueueWaitTest : public ::testing::Test {
 protected:
  /// A dispatcher admitting by phase with no capacity (every task admissible), its travel the
  /// distance to the pickup; with `lines` the roadmap's times are known, so queues are priced.
  void start(bool lines) {
    DispatcherConfig cfg;
    cfg.stationLoad = StationLoad::Phase;
    if (lines) {
      cfg.stationTimes = test::straightLineTimes(map);
    }
    auto s = SqliteTaskStore::open({dir.file(lines ? "lines.db" : "plain.db")});
    ASSERT_TRUE(s) << s.error().message;
    store = std::move(s).value();
    dispatcher = std::make_unique<Dispatcher>(*store, map, test::distanceToPickup(map), cfg);
  }
  void robot(const std::string& id, double x, std::int64_t t) {
    dispatcher->onRobotState({id, {x, 0, 0}, 0.9, t});
  }
  /// r1 stands at P-1 with t1 (to D-1): P-1's line is busy until 4 s from now, D-1's from 24 to 28.
  void p1Busy() {
    robot("r1", 0, 0);
    dispatcher->submit({test::transportTask("t1", "P-1", "D-1")}, 0);
    const auto out = dispatcher->tick(1);
    ASSERT_EQ(out.assignments.size(), 1u);
    ASSERT_EQ(out.assignments[0].robotId, "r1");
  }
  /// The task an idle robot at `x` is given of tA (P-1 → D-1) and tB (P-2 → D-2), posted together.
  std::string taskFor(double x) {
    p1Busy();
    robot("r2", x, 2);
    dispatcher->submit({test::transportTask("tA", "P-1", "D-1"), test::transportTask("tB", "P-2", "D-2")}, 2);
    const auto out = dispatcher->tick(3);
    EXPECT_EQ(out.assignments.size(), 1u);
    return out.assignments.empty() ? "" : out.assignments[0].task.id;
  }

  test::TempDir dir;
  StationMap map = stations();
  std::unique_ptr<SqliteTaskStore> store;
  std::unique_ptr<Dispatcher> dispatcher;
};

TEST_F(DispatcherQueueWaitTest, ANearTaskBehindABusyLineGoesAfterAFreeOneABitFurther) {
  // r2 at x = 0.5: tA's pickup is 0.5 s away but r1 holds it until 4 s (a 3.5 s wait, then D-1 is
  // free when it comes at 28): 0.5 + 3.5 = 4 s. tB's is 1.5 s away and free: 1.5 s. Travel alone
  // picks tA.
  start(false);
  EXPECT_EQ(taskFor(0.5), "tA");
  dispatcher.reset();
  start(true);
  EXPECT_EQ(taskFor(0.5), "tB");
}

TEST_F(DispatcherQueueWaitTest, ARobotThatGetsThereAfterTheLineHasClearedPaysNoWait) {
  // r2 at x = -10: 10 s from P-1 (clear from 4 s on, so no wait there, and at D-1 at 34 after r1
  // left at 28) against 12 s from P-2: any wait of 2 s or more charged to tA would give it tB.
  // Counting robots bound for a station would charge tA for r1 (4 s).
  start(true);
  EXPECT_EQ(taskFor(-10.0), "tA");
}

}  // namespace
}  // namespace fleet
