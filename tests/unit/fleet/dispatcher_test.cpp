#include "fleet/fleet/dispatcher.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <set>

#include "fleet/fleet/errors.hpp"
#include "fleet/fleet/sqlite_task_store.hpp"
#include "temp_dir.hpp"

namespace fleet {
namespace {

using S = TaskState;
constexpr std::int64_t kSec = 1'000'000'000;

StationMap stations() {
  StationMap m;
  EXPECT_TRUE(m.add({"P-1", {0, 0, 0}, static_cast<std::uint8_t>(StationKind::Pickup)}));
  EXPECT_TRUE(m.add({"D-1", {20, 0, 0}, static_cast<std::uint8_t>(StationKind::Dropoff)}));
  EXPECT_TRUE(m.add({"C-near", {0, 5, 0}, static_cast<std::uint8_t>(StationKind::Charging)}));
  EXPECT_TRUE(m.add({"C-far", {100, 100, 0}, static_cast<std::uint8_t>(StationKind::Charging)}));
  EXPECT_TRUE(m.add({"K-1", {50, 0, 0}, static_cast<std::uint8_t>(StationKind::Parking)}));
  return m;
}

/// Straight-line seconds at 1 m/s to the first station of the task.
TravelCost straightLine(const StationMap& m) {
  return [&m](const RobotInfo& r, const Task& t) {
    const std::string& first = t.kind == TaskKind::Transport ? t.pickup : t.station;
    const Station* s = m.find(first);
    if (s == nullptr) {
      return 0.0;
    }
    return std::hypot(r.pose.x - s->pose.x, r.pose.y - s->pose.y);
  };
}

Task transport(std::string id) {
  Task t;
  t.id = std::move(id);
  t.pickup = "P-1";
  t.dropoff = "D-1";
  return t;
}

class DispatcherTest : public ::testing::Test {
 protected:
  void SetUp() override { reopen(); }
  void reopen() {
    dispatcher.reset();
    store.reset();
    auto s = SqliteTaskStore::open({dir.file("tasks.db")});
    ASSERT_TRUE(s) << s.error().message;
    store = std::move(s).value();
    dispatcher = std::make_unique<Dispatcher>(*store, map, straightLine(map), cfg);
  }
  void robot(const std::string& id, double x, double battery, std::int64_t t) {
    dispatcher->onRobotState({id, {x, 0, 0}, battery, t});
  }
  void robotAt(const std::string& id, double x, double y, double battery, std::int64_t t) {
    dispatcher->onRobotState({id, {x, y, 0}, battery, t});
  }
  std::size_t chargeTasksIn(const DispatchResult& r) {
    return static_cast<std::size_t>(
        std::count_if(r.assignments.begin(), r.assignments.end(),
                      [](const auto& a) { return a.task.kind == TaskKind::Charge; }));
  }
  S stateOf(const std::string& id) { return store->get(id).value().state; }

  test::TempDir dir;
  StationMap map = stations();
  DispatcherConfig cfg;
  std::unique_ptr<SqliteTaskStore> store;
  std::unique_ptr<Dispatcher> dispatcher;
};

TEST_F(DispatcherTest, SubmitValidatesAgainstStations) {
  Task bad = transport("t2");
  bad.pickup = "P-404";
  DispatchResult out;
  auto rs = dispatcher->submit({transport("t1"), bad, transport("t1")}, 1, &out);
  ASSERT_EQ(rs.size(), 3u);
  EXPECT_TRUE(rs[0] && rs[0]->created);
  ASSERT_FALSE(rs[1]);
  EXPECT_EQ(rs[1].error().code, errc::kUnknownStation);
  EXPECT_EQ(rs[1].error().message, "pickup: unknown station 'P-404'");
  EXPECT_TRUE(rs[2] && !rs[2]->created);
  ASSERT_EQ(out.events.size(), 1u);
  EXPECT_EQ(out.events[0].state, S::Queued);
  EXPECT_EQ(dispatcher->waitingCount(), 1u);
}

TEST_F(DispatcherTest, AssignsNearestAndTracksProgress) {
  robot("far", 40, 0.9, 0);
  robot("near", 3, 0.9, 0);
  dispatcher->submit({transport("t1")}, 0);
  auto out = dispatcher->tick(kSec / 10);
  ASSERT_EQ(out.assignments.size(), 1u);
  EXPECT_EQ(out.assignments[0].robotId, "near");
  EXPECT_EQ(stateOf("t1"), S::Assigned);
  EXPECT_TRUE(dispatcher->tick(kSec / 5).assignments.empty()) << "never assigned twice";

  EXPECT_EQ(dispatcher->onTaskStatus("far", "t1", S::EnRoute, "", 1).error().code, errc::kWrongRobot);
  auto r = dispatcher->onTaskStatus("near", "t1", S::Delivering, "", 1);
  ASSERT_TRUE(r) << r.error().message;
  ASSERT_EQ(r->events.size(), 3u) << "en_route and loading are filled in";
  EXPECT_EQ(r->events[0].state, S::EnRoute);
  EXPECT_EQ(r->events[2].state, S::Delivering);
  EXPECT_EQ(dispatcher->onTaskStatus("near", "t1", S::Loading, "", 1).error().code, errc::kIllegalTransition);
  ASSERT_TRUE(dispatcher->onTaskStatus("near", "t1", S::Done, "", 2));
  EXPECT_EQ(stateOf("t1"), S::Done);
  EXPECT_TRUE(dispatcher->robots().find("near")->idle());
  EXPECT_EQ(dispatcher->counters().done, 1);
  EXPECT_EQ(dispatcher->onTaskStatus("near", "t1", S::Done, "", 3).error().code, errc::kNotFound);
}

// Every transition states when the task is expected to be done (TaskEta): at its robot's travel
// once assigned, behind the queue while it waits, stretched by the pace of the tasks done.
TEST_F(DispatcherTest, EveryTransitionStatesTheTasksEta) {
  robot("r1", 10, 0.9, 0);  // 10 s from P-1 at 1 m/s (the test's travel: to the first station)
  Task a = transport("a");
  a.loadNs = 2 * kSec;
  a.unloadNs = 3 * kSec;
  DispatchResult submitted;
  dispatcher->submit({a, transport("b")}, 0, &submitted);
  ASSERT_EQ(submitted.events.size(), 2u);
  // A free robot: a is due after its own way (10 s) and dwell (5 s); b, behind a on a fleet of
  // one that has done nothing yet, after a's whole task and its own.
  EXPECT_EQ(submitted.events[0].etaNs, 15 * kSec);
  EXPECT_GT(submitted.events[1].etaNs, submitted.events[0].etaNs);
  auto out = dispatcher->tick(kSec);
  ASSERT_EQ(out.events.size(), 1u);
  EXPECT_EQ(out.events[0].state, S::Assigned);
  EXPECT_EQ(out.events[0].etaNs, (1 + 15) * kSec);
  auto r = dispatcher->onTaskStatus("r1", "a", S::EnRoute, "", 2 * kSec);
  ASSERT_TRUE(r);
  EXPECT_EQ(r->events[0].etaNs, 16 * kSec) << "the estimate made at assignment stands";
  // Done 30 s after its assignment: twice its prediction. The next estimate is stretched by it.
  r = dispatcher->onTaskStatus("r1", "a", S::Done, "", 31 * kSec);
  ASSERT_TRUE(r);
  EXPECT_EQ(r->events.back().state, S::Done);
  EXPECT_EQ(r->events.back().etaNs, 31 * kSec);
  robot("r1", 0, 0.9, 31 * kSec);  // at P-1 now: its own way 0 s
  out = dispatcher->tick(32 * kSec);
  ASSERT_EQ(out.events.size(), 1u);
  EXPECT_EQ(out.events[0].etaNs, 32 * kSec) << "predicted 0 s (no dwell) x pace 2";
  // Cancelled: no estimate.
  auto c = dispatcher->cancel("b", "no longer needed", 33 * kSec);
  ASSERT_TRUE(c);
  EXPECT_EQ(c->events.back().etaNs, 0);
}

// A held robot is given no task, so it counts for no waiting task's estimate: with the only robot
// held a new task has none (0), and once it is let go the next one has one again.
TEST_F(DispatcherTest, AWaitingTaskHasNoEtaWhileEveryRobotIsHeld) {
  robot("r1", 10, 0.9, 0);
  ASSERT_TRUE(dispatcher->setRobotHeld("r1", true, 0));
  DispatchResult held;
  dispatcher->submit({transport("a")}, kSec, &held);
  ASSERT_EQ(held.events.size(), 1u);
  EXPECT_EQ(held.events[0].etaNs, 0) << "no robot may take it";
  ASSERT_TRUE(dispatcher->setRobotHeld("r1", false, 2 * kSec));
  DispatchResult free;
  dispatcher->submit({transport("b")}, 3 * kSec, &free);
  ASSERT_EQ(free.events.size(), 1u);
  EXPECT_GT(free.events[0].etaNs, 3 * kSec);
}

// A station closed at run time holds back the waiting tasks that need it, with a stated reason and
// no estimate, while others are assigned; reopened, it says so and its task is assigned.
TEST_F(DispatcherTest, AWaitingTaskToAClosedStationIsHeldWithItsReasonUntilItReopens) {
  robot("r1", 10, 0.9, 0);
  robot("r2", 12, 0.9, 0);
  dispatcher->submit({transport("closed")}, 0);
  auto held = dispatcher->setClosedStations({{"D-1", "closure 'spill': wet floor"}}, kSec / 10);
  ASSERT_EQ(held.events.size(), 1u);
  EXPECT_EQ(held.events[0].taskId, "closed");
  EXPECT_EQ(held.events[0].reason, "station D-1 closed: closure 'spill': wet floor");
  EXPECT_EQ(held.events[0].etaNs, 0) << "no estimate while held";
  Task other;
  other.id = "other";
  other.kind = TaskKind::Goto;
  other.station = "K-1";
  dispatcher->submit({other}, 2 * kSec / 10);
  auto out = dispatcher->tick(3 * kSec / 10);
  ASSERT_EQ(out.assignments.size(), 1u);
  EXPECT_EQ(out.assignments[0].task.id, "other") << "the closed station's task waits";
  EXPECT_EQ(stateOf("closed"), S::Queued);
  EXPECT_TRUE(dispatcher->tick(4 * kSec / 10).events.empty()) << "the reason is stated once";

  auto reopened = dispatcher->setClosedStations({}, 5 * kSec / 10);
  ASSERT_EQ(reopened.events.size(), 1u);
  EXPECT_EQ(reopened.events[0].reason, "station D-1 open again; waiting for a robot");
  out = dispatcher->tick(6 * kSec / 10);
  ASSERT_EQ(out.assignments.size(), 1u);
  EXPECT_EQ(out.assignments[0].task.id, "closed");
}

/// A task the store holds but the dispatcher never took in: an earlier attempt's commit went
/// through but its answer was lost (the connection to PostgreSQL broke after the commit, as in a
/// database fail-over, DatabaseFailover.APromotionWithinTheLeaseLosesNothingEither). Its retry is
/// a duplicate, and the dispatcher adopts it: else nothing assigns it until the next rebuild.
TEST_F(DispatcherTest, ARetriedTaskStoredWithoutItsAnswerIsAdoptedAndAssigned) {
  ASSERT_TRUE(store->submit(transport("t1"), 0));  // behind the dispatcher's back
  robot("r1", 3, 0.9, 0);
  EXPECT_TRUE(dispatcher->tick(kSec / 10).assignments.empty()) << "not known yet";
  DispatchResult out;
  auto rs = dispatcher->submit({transport("t1")}, 1, &out);
  ASSERT_EQ(rs.size(), 1u);
  ASSERT_TRUE(rs[0]);
  EXPECT_FALSE(rs[0]->created) << "a duplicate";
  EXPECT_EQ(out.events.size(), 1u);
  EXPECT_EQ(dispatcher->counters().submitted, 0);
  auto tick = dispatcher->tick(kSec / 5);
  ASSERT_EQ(tick.assignments.size(), 1u);
  EXPECT_EQ(tick.assignments[0].robotId, "r1");
  DispatchResult again;
  dispatcher->submit({transport("t1")}, 2, &again);
  EXPECT_TRUE(again.events.empty()) << "a task it knows is not adopted twice";
}

/// A robot in fault mode fails whatever it is given at once; offering it tasks only burned their
/// attempts until it was held back after three failures.
TEST_F(DispatcherTest, ARobotInFaultModeIsOfferedNoTaskUntilItRecovers) {
  dispatcher->onRobotState({"near", {3, 0, 0}, 0.9, 0, true});
  robot("far", 40, 0.9, 0);
  dispatcher->submit({transport("t1")}, 0);
  auto out = dispatcher->tick(kSec / 10);
  ASSERT_EQ(out.assignments.size(), 1u);
  EXPECT_EQ(out.assignments[0].robotId, "far");
  EXPECT_FALSE(dispatcher->robots().find("near")->idle());
  dispatcher->submit({transport("t2")}, kSec / 5);
  EXPECT_TRUE(dispatcher->tick(kSec / 4).assignments.empty());
  robot("near", 3, 0.9, kSec / 2);  // out of fault mode
  out = dispatcher->tick(kSec);
  ASSERT_EQ(out.assignments.size(), 1u);
  EXPECT_EQ(out.assignments[0].robotId, "near");
}

TEST_F(DispatcherTest, LostRobotTaskIsRequeuedAndReassigned) {
  robot("a", 1, 0.9, 0);
  robot("b", 30, 0.9, 0);
  dispatcher->submit({transport("t1")}, 0);
  auto first = dispatcher->tick(kSec / 10);
  ASSERT_EQ(first.assignments.size(), 1u);
  ASSERT_EQ(first.assignments[0].robotId, "a");
  ASSERT_TRUE(dispatcher->onTaskStatus("a", "t1", S::EnRoute, "", kSec / 5));
  // b keeps publishing, a falls silent; its lease (1 s) expires.
  robot("b", 30, 0.9, kSec);
  robot("b", 30, 0.9, 2 * kSec);
  auto out = dispatcher->tick(2 * kSec);
  ASSERT_EQ(out.assignments.size(), 1u);
  EXPECT_EQ(out.assignments[0].robotId, "b");
  ASSERT_GE(out.events.size(), 2u);
  EXPECT_EQ(out.events[0].state, S::Requeued);
  EXPECT_EQ(out.events[0].reason, "robot a lost");
  EXPECT_EQ(out.events[1].state, S::Assigned);
  auto rec = store->get("t1").value();
  EXPECT_EQ(rec.robotId, "b");
  EXPECT_EQ(rec.attempts, 2);
  // The lost robot's late report is refused, and when it returns it is idle.
  EXPECT_EQ(dispatcher->onTaskStatus("a", "t1", S::Loading, "", 3 * kSec).error().code, errc::kWrongRobot);
  robot("a", 1, 0.9, 3 * kSec);
  EXPECT_TRUE(dispatcher->robots().find("a")->idle());
}

TEST_F(DispatcherTest, LivelinessLossRequeuesAtOnce) {
  robot("a", 1, 0.9, 0);
  dispatcher->submit({transport("t1")}, 0);
  ASSERT_EQ(dispatcher->tick(1).assignments.size(), 1u);
  auto out = dispatcher->onRobotLost("a", 2);
  ASSERT_EQ(out.events.size(), 1u);
  EXPECT_EQ(stateOf("t1"), S::Requeued);
  EXPECT_TRUE(dispatcher->tick(3).assignments.empty()) << "no robot left";
  EXPECT_EQ(dispatcher->waitingCount(), 1u);
}

TEST_F(DispatcherTest, FailedTaskRetriesThenFails) {
  cfg.maxAttempts = 2;
  reopen();
  robot("a", 1, 0.9, 0);
  dispatcher->submit({transport("t1")}, 0);
  ASSERT_EQ(dispatcher->tick(1).assignments.size(), 1u);
  auto f1 = dispatcher->onTaskStatus("a", "t1", S::Failed, "blocked", 2);
  ASSERT_TRUE(f1);
  EXPECT_EQ(stateOf("t1"), S::Requeued);
  ASSERT_EQ(dispatcher->tick(3).assignments.size(), 1u);
  auto f2 = dispatcher->onTaskStatus("a", "t1", S::Failed, "blocked again", 4);
  ASSERT_TRUE(f2);
  EXPECT_EQ(stateOf("t1"), S::Failed);
  EXPECT_EQ(dispatcher->counters().failed, 1);
  EXPECT_TRUE(dispatcher->openTasks().empty());
}

TEST_F(DispatcherTest, LowBatteryRobotGoesToNearestChargerNotToWork) {
  robot("low", 0, 0.1, 0);
  dispatcher->submit({transport("t1")}, 0);
  auto out = dispatcher->tick(1);
  ASSERT_EQ(out.assignments.size(), 1u);
  EXPECT_EQ(out.assignments[0].robotId, "low");
  EXPECT_EQ(out.assignments[0].task.kind, TaskKind::Charge);
  EXPECT_EQ(out.assignments[0].task.station, "C-near");
  EXPECT_EQ(out.assignments[0].task.robot, "low");
  EXPECT_EQ(stateOf("t1"), S::Queued) << "no transport for a low robot";
  // Charged: it reports done, then takes the transport.
  const std::string chargeId = out.assignments[0].task.id;
  ASSERT_TRUE(dispatcher->onTaskStatus("low", chargeId, S::Done, "", 2));
  robot("low", 0, 0.95, 3);
  auto next = dispatcher->tick(4);
  ASSERT_EQ(next.assignments.size(), 1u);
  EXPECT_EQ(next.assignments[0].task.id, "t1");
  EXPECT_TRUE(dispatcher->tick(5).assignments.empty()) << "no second charge task";
}

// The robot stays on its charge task (no transport for it, no second charge task) until it
// stands at the charger with battery >= chargeUntil; then the dispatcher ends the task and the
// waiting transport goes to it in the same tick (not withdrawn again by the release).
TEST_F(DispatcherTest, ChargeTaskEndsWhenTheRobotAtTheChargerReachesTheTarget) {
  robotAt("low", 0, 0, 0.1, 0);
  auto out = dispatcher->tick(1);
  ASSERT_EQ(out.assignments.size(), 1u);
  const std::string chargeId = out.assignments[0].task.id;
  ASSERT_EQ(out.assignments[0].task.station, "C-near");  // at (0, 5)
  ASSERT_TRUE(dispatcher->onTaskStatus("low", chargeId, S::EnRoute, "", 2));
  dispatcher->submit({transport("t1")}, 3);
  // Driving there, then charging: a tick every 0.2 s for 60 s, the battery climbing to 0.89.
  std::int64_t now = 4;
  for (int i = 0; i < 300; ++i, now += kSec / 5) {
    const bool there = i >= 20;
    robotAt("low", 0, there ? 4.9 : 0.25 * i, there ? 0.1 + 0.79 * (i - 20) / 279.0 : 0.1, now);
    out = dispatcher->tick(now);
    ASSERT_TRUE(out.assignments.empty()) << "tick " << i << ": " << out.assignments[0].task.id;
    ASSERT_TRUE(out.revoked.empty());
  }
  EXPECT_EQ(stateOf(chargeId), S::EnRoute);
  EXPECT_EQ(stateOf("t1"), S::Queued) << "a charging robot is not dispatched";
  EXPECT_EQ(dispatcher->counters().submitted, 2) << "one charge task, no thrash";
  // Charged, but somewhere else (the sample of a robot pushed off the charger): not done.
  robotAt("low", 3, 5, 0.95, now + 1);
  EXPECT_TRUE(dispatcher->tick(now + 1).events.empty());
  robotAt("low", 0.1, 5, 0.9, now + 2);
  out = dispatcher->tick(now + 3);
  EXPECT_EQ(stateOf(chargeId), S::Done);
  EXPECT_EQ(store->get(chargeId)->reason, "charged to 0.90");
  EXPECT_EQ(dispatcher->counters().charged, 1);
  ASSERT_EQ(out.assignments.size(), 1u);
  EXPECT_EQ(out.assignments[0].task.id, "t1");
  EXPECT_EQ(out.assignments[0].robotId, "low");
  EXPECT_TRUE(out.revoked.empty()) << "the new order replaces the charge order; no empty one after it";
}

TEST_F(DispatcherTest, ChargedRobotWithNoWorkIsReleasedOnce) {
  robotAt("low", 0, 5, 0.15, 0);  // already at C-near
  auto out = dispatcher->tick(1);
  ASSERT_EQ(out.assignments.size(), 1u);
  const std::string chargeId = out.assignments[0].task.id;
  // No report from the robot at all (lost status samples): the steps are filled in.
  robotAt("low", 0, 5, 0.93, 2);
  out = dispatcher->tick(3);
  EXPECT_EQ(stateOf(chargeId), S::Done);
  ASSERT_EQ(out.events.size(), 2u);
  EXPECT_EQ(out.events[0].state, S::EnRoute);
  EXPECT_EQ(out.events[1].state, S::Done);
  EXPECT_EQ(out.revoked, std::vector<std::string>{"low"}) << "told to stop dwelling";
  EXPECT_TRUE(dispatcher->robots().find("low")->idle());
  // Its late report on the finished task is refused; no new charge task follows.
  EXPECT_FALSE(dispatcher->onTaskStatus("low", chargeId, S::EnRoute, "", 4));
  for (std::int64_t t = 5; t < 10; ++t) {
    robotAt("low", 0, 5, 0.93, t);
    out = dispatcher->tick(t);
    EXPECT_TRUE(out.assignments.empty() && out.revoked.empty() && out.events.empty());
  }
}

TEST_F(DispatcherTest, RobotThatRunsLowMidTaskFinishesItThenCharges) {
  robot("r", 0, 0.25, 0);
  dispatcher->submit({transport("t1")}, 0);
  auto out = dispatcher->tick(1);
  ASSERT_EQ(out.assignments.size(), 1u);
  ASSERT_EQ(out.assignments[0].task.id, "t1");
  ASSERT_TRUE(dispatcher->onTaskStatus("r", "t1", S::Delivering, "", 2));
  for (std::int64_t t = 3; t < 20; ++t) {
    robot("r", 10, 0.15, t);  // below the threshold while delivering
    EXPECT_EQ(chargeTasksIn(dispatcher->tick(t)), 0u) << "the task comes first";
  }
  ASSERT_TRUE(dispatcher->onTaskStatus("r", "t1", S::Done, "", 20));
  out = dispatcher->tick(21);
  ASSERT_EQ(out.assignments.size(), 1u);
  EXPECT_EQ(out.assignments[0].task.kind, TaskKind::Charge);
  EXPECT_EQ(out.assignments[0].robotId, "r");
}

TEST_F(DispatcherTest, BacklogCapKeepsTheMostUrgentTasks) {
  cfg.maxCandidates = 2;
  reopen();
  robot("a", 1, 0.9, 0);
  robot("b", 2, 0.9, 0);
  robot("c", 3, 0.9, 0);
  Task urgent = transport("urgent");
  urgent.priority = 5;
  Task soon = transport("soon");
  soon.deadlineNs = 100 * kSec;
  dispatcher->submit({transport("t1"), transport("t2"), urgent, soon}, 0);
  auto out = dispatcher->tick(1);
  ASSERT_EQ(out.assignments.size(), 2u) << "only two candidates enter one allocation";
  std::set<std::string> ids;
  for (const auto& a : out.assignments) {
    ids.insert(a.task.id);
  }
  EXPECT_EQ(ids, (std::set<std::string>{"urgent", "soon"}));
  EXPECT_EQ(dispatcher->tick(2).assignments.size(), 1u) << "the rest follow on later ticks";
}

TEST_F(DispatcherTest, StationCapacityHoldsTasksBackOldestFirst) {
  cfg.stationCapacity = 2;
  reopen();
  for (int i = 0; i < 5; ++i) {
    robot("r" + std::to_string(i), i, 0.9, 0);
  }
  // Four tasks to D-1 (two of them submitted first) and one charge trip elsewhere.
  dispatcher->submit({transport("t1"), transport("t2")}, 0);
  dispatcher->submit({transport("t3"), transport("t4")}, 1);
  Task park;
  park.id = "park";
  park.kind = TaskKind::Park;
  park.station = "K-1";
  dispatcher->submit({park}, 2);
  auto out = dispatcher->tick(3);
  std::set<std::string> ids;
  for (const auto& a : out.assignments) {
    ids.insert(a.task.id);
  }
  EXPECT_EQ(ids, (std::set<std::string>{"t1", "t2", "park"})) << "two robots per station, oldest first";
  EXPECT_TRUE(dispatcher->tick(4).assignments.empty()) << "the station is still full";
  const std::string holder =
      out.assignments[0].task.id == "park" ? out.assignments[1].robotId : out.assignments[0].robotId;
  const std::string done =
      out.assignments[0].task.id == "park" ? out.assignments[1].task.id : out.assignments[0].task.id;
  ASSERT_TRUE(dispatcher->onTaskStatus(holder, done, S::Done, "", 5));
  const auto next = dispatcher->tick(6);
  ASSERT_EQ(next.assignments.size(), 1u) << "a place freed: one more task goes";
  EXPECT_EQ(next.assignments[0].task.id, "t3");
}

/// A task held back by a full line says so in its reason (one event, no repeat while nothing
/// changes), and once its deadline has passed, that too: the WMS sees why it waits and that it is
/// late, and the task stays queued (nothing is dropped).
TEST_F(DispatcherTest, ATaskHeldByAFullLineSaysWhereAndWhenItIsPastItsDeadline) {
  cfg.stationCapacity = 1;
  reopen();
  robot("r1", 0, 0.9, 0);
  robot("r2", 1, 0.9, 0);
  Task late = transport("late");
  late.deadlineNs = 10 * kSec;
  dispatcher->submit({transport("first"), late}, 0);
  const auto reasonIn = [](const DispatchResult& r, const std::string& id) {
    for (const auto& e : r.events) {
      if (e.taskId == id) {
        return e.reason;
      }
    }
    return std::string("(no event)");
  };
  auto out = dispatcher->tick(1 * kSec);
  ASSERT_EQ(out.assignments.size(), 1U);
  EXPECT_EQ(out.assignments[0].task.id, "first");
  EXPECT_EQ(reasonIn(out, "late"),
            "waiting for a place in station P-1's line (it holds 1, all taken by other tasks)");
  EXPECT_EQ(reasonIn(dispatcher->tick(2 * kSec), "late"), "(no event)") << "said once";
  robot("r1", 0, 0.9, 11 * kSec);  // both still there: r1 on "first", r2 idle
  robot("r2", 1, 0.9, 11 * kSec);
  out = dispatcher->tick(11 * kSec);
  EXPECT_EQ(reasonIn(out, "late"),
            "past its deadline and still waiting for a place in station P-1's line "
            "(it holds 1, all taken by other tasks)");
  for (const auto& a : out.assignments) {
    EXPECT_NE(a.task.id, "late") << "still held";
  }
  const auto rec = store->get("late");
  ASSERT_TRUE(rec);
  EXPECT_EQ(rec->state, S::Queued);
  EXPECT_EQ(rec->reason, reasonIn(out, "late")) << "stored: a restarted manager says the same";
}

/// Per-station capacities (a station's line on the roadmap in reserved traffic) override the
/// global one, and 0 there means no limit at that station.
TEST_F(DispatcherTest, AStationsOwnCapacityOverridesTheGlobalOne) {
  cfg.stationCapacity = 1;
  cfg.stationCapacities = {{"P-1", 3}, {"D-1", 3}};
  reopen();
  for (int i = 0; i < 5; ++i) {
    robot("r" + std::to_string(i), i, 0.9, 0);
  }
  dispatcher->submit({transport("t1"), transport("t2"), transport("t3"), transport("t4")}, 0);
  auto out = dispatcher->tick(1);
  EXPECT_EQ(out.assignments.size(), 3u) << "P-1 and D-1 each hold three";
  EXPECT_TRUE(dispatcher->tick(2).assignments.empty());
}

/// The admission governor's factor scales the lines' places (floor(k × places)), never below them,
/// and leaves the global capacity of stations without a line alone.
TEST_F(DispatcherTest, TheLineScaleWidensEachLinesPlacesFromTheNextTick) {
  cfg.stationCapacity = 1;
  cfg.stationCapacities = {{"P-1", 2}, {"D-1", 2}};
  reopen();
  for (int i = 0; i < 6; ++i) {
    robot("r" + std::to_string(i), i, 0.9, 0);
  }
  std::vector<Task> tasks;
  for (int i = 1; i <= 5; ++i) {
    tasks.push_back(transport("t" + std::to_string(i)));
  }
  dispatcher->submit(tasks, 0);
  EXPECT_EQ(dispatcher->tick(1).assignments.size(), 2u) << "two places in each line";
  EXPECT_EQ(dispatcher->heldInLines(), 3u) << "three held for a place, robots idle";
  dispatcher->setLineScale(1.75);  // floor(1.75 × 2) = 3
  EXPECT_EQ(dispatcher->tick(2).assignments.size(), 1u);
  dispatcher->setLineScale(2.0);
  const auto third = dispatcher->tick(3);
  EXPECT_EQ(third.assignments.size(), 1u);
  EXPECT_EQ(dispatcher->heldInLines(), 1u);
  EXPECT_NE(store->get("t5")->reason.find("(it holds 2,"), std::string::npos)
      << store->get("t5")->reason << ": the line's own places, not the scaled slots";
  dispatcher->setLineScale(0.2);  // below the lines' own places: 1
  EXPECT_EQ(dispatcher->lineScale(), 1.0);
  dispatcher->setLineScale(std::numeric_limits<double>::quiet_NaN());
  EXPECT_EQ(dispatcher->lineScale(), 1.0);
  EXPECT_TRUE(dispatcher->tick(4).assignments.empty()) << "four active, two places again";
}

TEST_F(DispatcherTest, AStationCapacityOfZeroIsNoLimitThere) {
  cfg.stationCapacity = 1;
  cfg.stationCapacities = {{"P-1", 0}, {"D-1", 0}};
  reopen();
  for (int i = 0; i < 5; ++i) {
    robot("r" + std::to_string(i), i, 0.9, 0);
  }
  dispatcher->submit({transport("t1"), transport("t2"), transport("t3"), transport("t4")}, 0);
  EXPECT_EQ(dispatcher->tick(1).assignments.size(), 4u);
}

/// Counted by phase, a task loads its pickup until it has loaded and its drop-off for the whole
/// task: a robot delivering elsewhere no longer holds a place at the pickup it has left, and a task
/// whose drop-off's line is full waits.
TEST_F(DispatcherTest, StationLoadByPhaseFreesThePickupOnceLoaded) {
  cfg.stationCapacity = 1;
  cfg.stationCapacities = {{"D-1", 2}};
  cfg.stationLoad = StationLoad::Phase;
  reopen();
  for (int i = 0; i < 4; ++i) {
    robot("r" + std::to_string(i), i, 0.9, 0);
  }
  dispatcher->submit({transport("t1"), transport("t2"), transport("t3")}, 0);
  const auto out = dispatcher->tick(1);
  ASSERT_EQ(out.assignments.size(), 1u) << "one robot per pickup";
  EXPECT_EQ(out.assignments[0].task.id, "t1");
  const std::string holder = out.assignments[0].robotId;
  EXPECT_TRUE(dispatcher->tick(2).assignments.empty()) << "P-1 is taken until t1 has loaded";
  ASSERT_TRUE(dispatcher->onTaskStatus(holder, "t1", S::Delivering, "", 3));
  const auto next = dispatcher->tick(4);
  ASSERT_EQ(next.assignments.size(), 1u) << "t1 left P-1 for its drop-off: t2 goes";
  EXPECT_EQ(next.assignments[0].task.id, "t2");
  ASSERT_TRUE(dispatcher->onTaskStatus(next.assignments[0].robotId, "t2", S::Delivering, "", 5));
  EXPECT_TRUE(dispatcher->tick(6).assignments.empty())
      << "P-1 is free but D-1's two places are held by t1 and t2 until they are done";
}

TEST_F(DispatcherTest, StationLoadByTaskHoldsThePickupUntilTheTaskEnds) {
  cfg.stationCapacity = 1;
  reopen();
  for (int i = 0; i < 3; ++i) {
    robot("r" + std::to_string(i), i, 0.9, 0);
  }
  dispatcher->submit({transport("t1"), transport("t2")}, 0);
  const auto first = dispatcher->tick(1);
  ASSERT_EQ(first.assignments.size(), 1u);
  ASSERT_TRUE(dispatcher->onTaskStatus(first.assignments[0].robotId, "t1", S::Delivering, "", 3));
  EXPECT_TRUE(dispatcher->tick(4).assignments.empty());
}

TEST_F(DispatcherTest, ARobotThatFailsEveryTaskIsHeldBackForAWhile) {
  robot("broken", 1, 0.9, 0);
  robot("far", 30, 0.9, 0);
  for (int i = 0; i < 20; ++i) {
    dispatcher->submit({transport("t" + std::to_string(i))}, 0);
  }
  auto taskOf = [&](const char* id) { return dispatcher->robots().find(id)->taskId; };
  // The nearer robot fails each task it gets at once, three times in a row; the other delivers.
  auto alive = [&](std::int64_t t) {  // states keep both robots within their lease
    robot("broken", 1, 0.9, t);
    robot("far", 30, 0.9, t);
  };
  for (int k = 0; k < 3; ++k) {
    alive(kSec * (k + 1));
    (void)dispatcher->tick(kSec * (k + 1));
    const std::string mine = taskOf("broken");
    ASSERT_FALSE(mine.empty()) << "round " << k;
    ASSERT_TRUE(
        dispatcher->onTaskStatus("broken", mine, S::Failed, "no path: start cell blocked", kSec * (k + 1)));
    if (const std::string other = taskOf("far"); !other.empty()) {
      ASSERT_TRUE(dispatcher->onTaskStatus("far", other, S::Done, "", kSec * (k + 1)));
    }
  }
  EXPECT_EQ(dispatcher->counters().robotsHeld, 1);
  for (int k = 4; k < 30; ++k) {
    alive(kSec * k);
    (void)dispatcher->tick(kSec * k);
    EXPECT_TRUE(taskOf("broken").empty()) << "held back after three failures in a row (t = " << k << " s)";
    if (const std::string other = taskOf("far"); !other.empty() && k % 5 == 0) {
      ASSERT_TRUE(dispatcher->onTaskStatus("far", other, S::Done, "", kSec * k));
    }
  }
  alive(70 * kSec);
  (void)dispatcher->tick(70 * kSec);
  EXPECT_FALSE(taskOf("broken").empty()) << "after the hold it gets work again";
}

TEST_F(DispatcherTest, WithoutStationCapacityEveryRobotIsSent) {
  for (int i = 0; i < 4; ++i) {
    robot("r" + std::to_string(i), i, 0.9, 0);
  }
  dispatcher->submit({transport("t1"), transport("t2"), transport("t3"), transport("t4")}, 0);
  EXPECT_EQ(dispatcher->tick(1).assignments.size(), 4u);
}

TEST_F(DispatcherTest, CancelWithdrawsActiveTask) {
  robot("a", 1, 0.9, 0);
  dispatcher->submit({transport("t1"), transport("t2")}, 0);
  auto out = dispatcher->tick(1);
  ASSERT_EQ(out.assignments.size(), 1u);
  const std::string held = out.assignments[0].task.id;
  auto c = dispatcher->cancel(held, "operator", 2);
  ASSERT_TRUE(c);
  EXPECT_EQ(c->revoked, std::vector<std::string>{"a"});
  EXPECT_EQ(stateOf(held), S::Cancelled);
  EXPECT_EQ(dispatcher->cancel(held, "again", 3).error().code, errc::kIllegalTransition);
  EXPECT_EQ(dispatcher->cancel("nope", "", 3).error().code, errc::kNotFound);
  EXPECT_EQ(dispatcher->tick(4).assignments.size(), 1u) << "the robot is free for the other task";
}

TEST_F(DispatcherTest, PausedTaskIsNotDispatchedAndAnActiveOneIsHeldDurably) {
  robot("a", 1, 0.9, 0);
  dispatcher->submit({transport("t1")}, 0);
  auto p = dispatcher->setPaused("t1", true, 1);
  ASSERT_TRUE(p) << p.error().message;
  EXPECT_TRUE(p->assignments.empty()) << "a waiting task has no robot to tell";
  EXPECT_TRUE(dispatcher->tick(2).assignments.empty()) << "a paused task is not dispatched";
  ASSERT_TRUE(dispatcher->setPaused("t1", false, 3));
  auto out = dispatcher->tick(4);
  ASSERT_EQ(out.assignments.size(), 1u);
  EXPECT_FALSE(out.assignments[0].paused);
  // Active: the order is re-sent with `paused`, and the hold survives a manager restart.
  p = dispatcher->setPaused("t1", true, 5);
  ASSERT_TRUE(p);
  ASSERT_EQ(p->assignments.size(), 1u);
  EXPECT_EQ(p->assignments[0].robotId, "a");
  EXPECT_TRUE(p->assignments[0].paused);
  EXPECT_EQ(stateOf("t1"), S::Assigned) << "pausing is no transition";
  reopen();
  auto rec = dispatcher->recover(6);
  ASSERT_TRUE(rec);
  ASSERT_EQ(rec->assignments.size(), 1u);
  EXPECT_TRUE(rec->assignments[0].paused);
  ASSERT_TRUE(dispatcher->onTaskStatus("a", "t1", S::Done, "", 7));
  EXPECT_EQ(dispatcher->setPaused("t1", false, 8).error().code, errc::kIllegalTransition);
  EXPECT_EQ(dispatcher->setPaused("nope", true, 8).error().code, errc::kNotFound);
}

TEST_F(DispatcherTest, AFailedTaskIsRetriedByAnotherRobotWhenOneIsIdle) {
  robot("a", 1, 0.9, 0);
  robot("b", 9, 0.9, 0);
  dispatcher->submit({transport("t1")}, 0);
  auto out = dispatcher->tick(1);
  ASSERT_EQ(out.assignments.size(), 1u);
  ASSERT_EQ(out.assignments[0].robotId, "a") << "the nearer robot first";
  ASSERT_TRUE(dispatcher->onTaskStatus("a", "t1", S::Failed, "blocked by r5 for 60 s", 2));
  out = dispatcher->tick(3);
  ASSERT_EQ(out.assignments.size(), 1u);
  EXPECT_EQ(out.assignments[0].robotId, "b") << "the retry went back to the robot that failed it";
  // Alone, the robot that failed it may take it again.
  ASSERT_TRUE(dispatcher->onTaskStatus("b", "t1", S::Failed, "", 4));
  robot("b", 9, 0.05, 5);  // b is low now and goes to charge: a is the only candidate
  out = dispatcher->tick(6);
  bool aGotIt = false;
  for (const auto& o : out.assignments) {
    aGotIt = aGotIt || (o.robotId == "a" && o.task.id == "t1");
  }
  EXPECT_TRUE(aGotIt);
}

TEST_F(DispatcherTest, RecoverRebuildsOpenStateAfterRestart) {
  robot("a", 1, 0.9, 0);
  dispatcher->submit({transport("t1"), transport("t2"), transport("t3")}, 0);
  auto out = dispatcher->tick(1);
  ASSERT_EQ(out.assignments.size(), 1u);
  const std::string held = out.assignments[0].task.id;
  ASSERT_TRUE(dispatcher->onTaskStatus("a", held, S::Loading, "", 2));
  reopen();  // the manager restarts: new store connection, new dispatcher
  auto rec = dispatcher->recover(10 * kSec);
  ASSERT_TRUE(rec) << rec.error().message;
  ASSERT_EQ(rec->assignments.size(), 1u) << "the active assignment is re-published";
  EXPECT_EQ(rec->assignments[0].robotId, "a");
  EXPECT_EQ(rec->assignments[0].task.id, held);
  EXPECT_EQ(dispatcher->openTasks().size(), 3u);
  EXPECT_EQ(dispatcher->waitingCount(), 2u);
  EXPECT_EQ(dispatcher->activeCount(), 1u);
  // The robot carries on where it was.
  ASSERT_TRUE(dispatcher->onTaskStatus("a", held, S::Delivering, "", 11 * kSec));
  // If it never speaks again its lease, started at the restart, expires and the task is requeued.
  auto later = dispatcher->tick(12 * kSec);
  EXPECT_EQ(stateOf(held), S::Requeued);
  EXPECT_TRUE(later.assignments.empty());
}

// Charge and park tasks without a station: the dispatcher chooses one when it assigns the task.
class StationChoiceTest : public DispatcherTest {
 protected:
  void SetUp() override {
    // Three parking places in a row at y = 10 (none at the origin), two chargers far apart.
    map = StationMap();
    for (const auto& [name, x] : {std::pair{"K-1", 10.0}, std::pair{"K-2", 20.0}, std::pair{"K-3", 30.0}}) {
      EXPECT_TRUE(map.add({name, {x, 10, 0}, static_cast<std::uint8_t>(StationKind::Parking)}));
    }
    EXPECT_TRUE(map.add({"C-1", {5, -10, 0}, static_cast<std::uint8_t>(StationKind::Charging)}));
    EXPECT_TRUE(map.add({"C-2", {40, -10, 0}, static_cast<std::uint8_t>(StationKind::Charging)}));
    EXPECT_TRUE(map.add({"P-1", {0, 0, 0}, static_cast<std::uint8_t>(StationKind::Pickup)}));
    EXPECT_TRUE(map.add({"D-1", {50, 0, 0}, static_cast<std::uint8_t>(StationKind::Dropoff)}));
    reopen();
  }
  static Task stationless(std::string id, TaskKind kind) {
    Task t;
    t.id = std::move(id);
    t.kind = kind;
    return t;
  }
  /// Robot `robot` near x = 29 takes the stationless park task `park-1` and is given K-3.
  void parkAtK3(const std::string& robot) {
    robotAt(robot, 29, 0, 0.9, 0);
    dispatcher->submit({stationless("park-1", TaskKind::Park)}, 0);
    const auto out = dispatcher->tick(1);
    ASSERT_EQ(out.assignments.size(), 1u);
    ASSERT_EQ(out.assignments[0].task.station, "K-3");
  }
  /// Every order names a station of the site; none is at the origin.
  void expectRealStations(const DispatchResult& out) {
    for (const auto& a : out.assignments) {
      const Station* s = map.find(a.task.station);
      ASSERT_NE(s, nullptr) << a.task.id << " goes to '" << a.task.station << "'";
      EXPECT_FALSE(s->pose.x == 0 && s->pose.y == 0) << a.task.id;
    }
  }
};

TEST_F(StationChoiceTest, AParkTaskWithoutAStationGetsTheNearestFreeParking) {
  robotAt("r", 19, 0, 0.9, 0);  // K-2 is 10 m away, K-1 and K-3 about 14 m
  auto rs = dispatcher->submit({stationless("park-1", TaskKind::Park)}, 0);
  ASSERT_TRUE(rs[0]) << rs[0].error().message;
  EXPECT_TRUE(rs[0]->record.task.station.empty()) << "chosen at assignment, not at submission";
  auto out = dispatcher->tick(1);
  expectRealStations(out);
  ASSERT_EQ(out.assignments.size(), 1u);
  EXPECT_EQ(out.assignments[0].robotId, "r");
  EXPECT_EQ(out.assignments[0].task.station, "K-2");
  const auto rec = store->get("park-1");
  ASSERT_TRUE(rec);
  EXPECT_EQ(rec->task.station, "K-2");
  EXPECT_TRUE(rec->stationChosen);
  EXPECT_EQ(rec->reason, "allocated to the nearest free parking station K-2");
  ASSERT_FALSE(out.events.empty());
  EXPECT_EQ(out.events.back().state, S::Assigned);
  EXPECT_EQ(out.events.back().station, "K-2") << "the event names the chosen station";
}

TEST_F(StationChoiceTest, TwoParkTasksWithoutAStationGetDifferentStations) {
  robotAt("a", 19, 0, 0.9, 0);
  robotAt("b", 21, 0, 0.9, 0);  // both nearest to K-2
  dispatcher->submit({stationless("park-a", TaskKind::Park), stationless("park-b", TaskKind::Park)}, 0);
  auto out = dispatcher->tick(1);
  expectRealStations(out);
  ASSERT_EQ(out.assignments.size(), 2u);
  std::set<std::string> chosen;
  for (const auto& a : out.assignments) {
    chosen.insert(a.task.station);
  }
  EXPECT_EQ(chosen.size(), 2u) << "two robots sent to one parking place";
  EXPECT_TRUE(chosen.contains("K-2"));
  // A third one, later, does not get a station an active task targets either.
  robotAt("c", 20, 0, 0.9, 2);
  dispatcher->submit({stationless("park-c", TaskKind::Park)}, 2);
  out = dispatcher->tick(3);
  expectRealStations(out);
  ASSERT_EQ(out.assignments.size(), 1u);
  EXPECT_FALSE(chosen.contains(out.assignments[0].task.station));
}

TEST_F(StationChoiceTest, AStationARobotStandsOnIsChosenOnlyWhenNoOtherIsFree) {
  // A robot in fault mode stands on K-2 (it takes no task, but it is in the way).
  dispatcher->onRobotState({"stuck-2", {20, 10.2, 0}, 0.9, 0, true});
  robotAt("r", 20, 0, 0.9, 0);
  dispatcher->submit({stationless("park-1", TaskKind::Park)}, 0);
  auto out = dispatcher->tick(1);
  ASSERT_EQ(out.assignments.size(), 1u);
  EXPECT_EQ(out.assignments[0].robotId, "r");
  EXPECT_NE(out.assignments[0].task.station, "K-2") << "sent onto a robot standing there";
  // With a robot on every free parking place, the nearest of them is still better than none.
  dispatcher->onRobotState({"stuck-1", {10, 10, 0}, 0.9, 2, true});
  dispatcher->onRobotState({"stuck-3", {30, 10, 0}, 0.9, 2, true});
  robotAt("q", 21, 0, 0.9, 2);
  dispatcher->submit({stationless("park-2", TaskKind::Park)}, 2);
  out = dispatcher->tick(3);
  ASSERT_EQ(out.assignments.size(), 1u);
  EXPECT_EQ(out.assignments[0].robotId, "q");
  EXPECT_EQ(out.assignments[0].task.station, "K-2");
}

TEST_F(StationChoiceTest, AChargeTaskWithoutAStationGetsAFreeCharger) {
  robotAt("a", 10, -10, 0.9, 0);
  robotAt("b", 12, -10, 0.9, 0);  // both nearest to C-1
  dispatcher->submit({stationless("charge-a", TaskKind::Charge), stationless("charge-b", TaskKind::Charge)},
                     0);
  auto out = dispatcher->tick(1);
  expectRealStations(out);
  ASSERT_EQ(out.assignments.size(), 2u);
  std::map<std::string, std::string> chargerOf;
  for (const auto& a : out.assignments) {
    chargerOf[a.robotId] = a.task.station;
  }
  EXPECT_EQ(chargerOf["a"], "C-1") << "the nearer robot keeps the nearer charger";
  EXPECT_EQ(chargerOf["b"], "C-2");
}

TEST_F(StationChoiceTest, ALowRobotIsSentToAFreeChargerNotToOneInUse) {
  robotAt("a", 5, -9, 0.9, 0);
  dispatcher->submit({stationless("charge-a", TaskKind::Charge)}, 0);
  auto out = dispatcher->tick(1);
  ASSERT_EQ(out.assignments.size(), 1u);
  ASSERT_EQ(out.assignments[0].task.station, "C-1");
  robotAt("low", 6, -9, 0.1, 2);  // right next to C-1, which a is charging at
  out = dispatcher->tick(3);
  expectRealStations(out);
  ASSERT_EQ(out.assignments.size(), 1u);
  EXPECT_EQ(out.assignments[0].robotId, "low");
  EXPECT_EQ(out.assignments[0].task.kind, TaskKind::Charge);
  EXPECT_EQ(out.assignments[0].task.station, "C-2");
}

TEST_F(StationChoiceTest, WhenEveryStationIsTakenTheTaskWaitsAndSaysWhy) {
  robotAt("a", 5, -8, 0.9, 0);
  robotAt("b", 40, -8, 0.9, 0);
  dispatcher->submit({stationless("charge-a", TaskKind::Charge), stationless("charge-b", TaskKind::Charge)},
                     0);
  ASSERT_EQ(dispatcher->tick(1).assignments.size(), 2u);
  robotAt("c", 20, -9, 0.9, 2);
  dispatcher->submit({stationless("charge-c", TaskKind::Charge)}, 2);
  auto out = dispatcher->tick(3);
  EXPECT_TRUE(out.assignments.empty()) << "sent to a charger in use (or to nowhere)";
  EXPECT_EQ(stateOf("charge-c"), S::Queued);
  const std::string why = "waiting for a free charging station: all 2 are taken by other tasks";
  EXPECT_EQ(store->get("charge-c")->reason, why) << "durable";
  ASSERT_EQ(out.events.size(), 1u);
  EXPECT_EQ(out.events[0].reason, why);
  EXPECT_TRUE(dispatcher->tick(4).events.empty()) << "said once";
  // A charger frees up: the waiting task gets it.
  ASSERT_TRUE(dispatcher->onTaskStatus("b", "charge-b", S::Done, "", 5));
  out = dispatcher->tick(6);
  expectRealStations(out);
  ASSERT_EQ(out.assignments.size(), 1u);
  EXPECT_EQ(out.assignments[0].task.id, "charge-c");
  EXPECT_EQ(out.assignments[0].task.station, "C-2");
}

TEST_F(StationChoiceTest, ASiteWithoutParkingRefusesAStationlessParkTaskAtSubmission) {
  map = StationMap();
  EXPECT_TRUE(map.add({"P-1", {0, 0, 0}, static_cast<std::uint8_t>(StationKind::Pickup)}));
  EXPECT_TRUE(map.add({"C-1", {5, 5, 0}, static_cast<std::uint8_t>(StationKind::Charging)}));
  reopen();
  std::vector<std::vector<FieldError>> fields;
  auto rs =
      dispatcher->submit({stationless("park-1", TaskKind::Park), stationless("charge-1", TaskKind::Charge)},
                         0, nullptr, &fields);
  ASSERT_FALSE(rs[0]);
  EXPECT_EQ(rs[0].error().code, errc::kInvalid);
  EXPECT_EQ(fields[0],
            (std::vector<FieldError>{{"station", "no parking station on this site to choose from"}}));
  EXPECT_TRUE(rs[1]) << "a charger exists";
  EXPECT_FALSE(store->get("park-1")) << "nothing stored";
}

TEST_F(StationChoiceTest, TheChosenStationSurvivesARestartAndARetryIsStillTheSameRequest) {
  parkAtK3("r");
  reopen();  // the manager restarts
  auto rec = dispatcher->recover(10 * kSec);
  ASSERT_TRUE(rec) << rec.error().message;
  ASSERT_EQ(rec->assignments.size(), 1u);
  EXPECT_EQ(rec->assignments[0].task.station, "K-3") << "re-published with the station chosen before";
  expectRealStations(*rec);
  const auto stored = store->get("park-1");
  ASSERT_TRUE(stored);
  EXPECT_EQ(stored->task.station, "K-3");
  EXPECT_TRUE(stored->stationChosen);
  EXPECT_EQ(toJson(*stored)["station_chosen"], true);
  // The WMS retries its original request (no station): the same request, not a conflict.
  auto retry = dispatcher->submit({stationless("park-1", TaskKind::Park)}, 11 * kSec);
  ASSERT_TRUE(retry[0]) << retry[0].error().message;
  EXPECT_FALSE(retry[0]->created);
  Task other = stationless("park-1", TaskKind::Park);
  other.station = "K-1";
  auto conflict = dispatcher->submit({other}, 11 * kSec);
  ASSERT_FALSE(conflict[0]);
  EXPECT_EQ(conflict[0].error().code, errc::kConflict);
}

TEST_F(StationChoiceTest, ARequeuedTaskGetsAStationForItsNextRobot) {
  parkAtK3("a");
  // a is lost; b, near K-1, takes the task over and parks there, not at a's choice.
  auto out = dispatcher->onRobotLost("a", 2);
  EXPECT_EQ(stateOf("park-1"), S::Requeued);
  EXPECT_TRUE(store->get("park-1")->task.station.empty()) << "back in the queue, the choice is dropped";
  robotAt("b", 9, 0, 0.9, 3);
  out = dispatcher->tick(4);
  expectRealStations(out);
  ASSERT_EQ(out.assignments.size(), 1u);
  EXPECT_EQ(out.assignments[0].robotId, "b");
  EXPECT_EQ(out.assignments[0].task.station, "K-1");
}

TEST_F(StationChoiceTest, ATaskNamingItsStationKeepsIt) {
  robotAt("r", 9, 0, 0.9, 0);
  Task t = stationless("park-1", TaskKind::Park);
  t.station = "K-3";
  dispatcher->submit({t}, 0);
  auto out = dispatcher->tick(1);
  ASSERT_EQ(out.assignments.size(), 1u);
  EXPECT_EQ(out.assignments[0].task.station, "K-3");
  EXPECT_FALSE(store->get("park-1")->stationChosen);
  EXPECT_EQ(out.events.back().station, "") << "nothing chosen";
}

}  // namespace
}  // namespace fleet
