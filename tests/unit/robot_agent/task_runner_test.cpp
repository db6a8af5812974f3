// The task runner alone: orders in, phases and the task states reported out.

#include "task_runner.hpp"

#include <gtest/gtest.h>

#include <string>
#include <vector>

using namespace fleet;
using agent::GoalAction;
using agent::Order;
using agent::Phase;
using agent::TaskGoal;
using agent::TaskRunner;
using agent::TaskTick;

namespace {

constexpr std::int64_t kSec = 1'000'000'000;

Order transport(std::uint32_t revision = 1, bool paused = false) {
  return Order{"t1",
               revision,
               {TaskGoal{{5.0, 1.0, 0.0}, "P-1", GoalAction::Load, 2.0},
                TaskGoal{{5.0, 6.0, 1.57}, "D-1", GoalAction::Unload, 1.0}},
               paused};
}

std::vector<TaskState> stages(TaskRunner& r) {
  std::vector<TaskState> out;
  while (auto rep = r.takeReport()) {
    out.push_back(rep->stage);
  }
  return out;
}

}  // namespace

TEST(TaskRunner, ATransportGoesThroughItsStatesOnceEach) {
  TaskRunner r;
  EXPECT_EQ(r.accept(transport()), TaskRunner::OrderChange::kNewTask);
  EXPECT_TRUE(r.busy());
  EXPECT_EQ(r.phase(), Phase::Idle) << "started on the next step";
  EXPECT_FALSE(r.takeReport()) << "Assigned is the manager's to say";
  EXPECT_EQ(r.tick(1 * kSec), TaskTick::kLegBegan);
  auto rep = r.takeReport();
  ASSERT_TRUE(rep);
  EXPECT_EQ(rep->stage, TaskState::EnRoute);
  EXPECT_EQ(rep->task, "t1");
  EXPECT_EQ(rep->revision, 1u);
  EXPECT_EQ(rep->progress, 0.0f);
  EXPECT_EQ(rep->stampNs, 1 * kSec);
  EXPECT_EQ(r.tick(2 * kSec), TaskTick::kNone) << "driving: nothing changes";
  EXPECT_FALSE(r.takeReport());
  r.arrive(3 * kSec);
  EXPECT_EQ(r.phase(), Phase::Dwelling);
  EXPECT_EQ(stages(r), std::vector<TaskState>{TaskState::Loading});
  EXPECT_EQ(r.tick(4 * kSec), TaskTick::kNone) << "dwelling 2 s";
  EXPECT_EQ(r.phase(), Phase::Dwelling);
  EXPECT_EQ(r.tick(5 * kSec), TaskTick::kLegBegan) << "the dwell is over: on to the next goal";
  EXPECT_EQ(r.phase(), Phase::Driving);
  EXPECT_EQ(r.goal().station, "D-1");
  rep = r.takeReport();
  ASSERT_TRUE(rep);
  EXPECT_EQ(rep->stage, TaskState::Delivering);
  EXPECT_EQ(rep->progress, 0.5f);
  r.arrive(9 * kSec);
  EXPECT_EQ(stages(r), std::vector<TaskState>{TaskState::Unloading});
  EXPECT_EQ(r.tick(9 * kSec + kSec / 2), TaskTick::kNone);
  EXPECT_EQ(r.tick(10 * kSec), TaskTick::kDone) << "the last dwell is over";
  EXPECT_EQ(r.tick(11 * kSec), TaskTick::kNone) << "ended once";
  rep = r.takeReport();
  ASSERT_TRUE(rep);
  EXPECT_EQ(rep->stage, TaskState::Done);
  EXPECT_EQ(rep->progress, 1.0f);
  EXPECT_FALSE(r.busy());
  EXPECT_EQ(r.phase(), Phase::Idle);
}

TEST(TaskRunner, RepeatsPausesAndCancels) {
  TaskRunner r;
  ASSERT_EQ(r.accept(transport(1)), TaskRunner::OrderChange::kNewTask);
  (void)r.tick(0);
  (void)r.takeReport();
  EXPECT_EQ(r.accept(transport(1)), TaskRunner::OrderChange::kSame) << "transient-local re-delivery";
  EXPECT_EQ(r.accept(transport(2, true)), TaskRunner::OrderChange::kPause);
  EXPECT_TRUE(r.paused());
  EXPECT_EQ(r.phase(), Phase::Driving) << "a pause keeps the task where it was";
  EXPECT_EQ(r.accept(transport(3, false)), TaskRunner::OrderChange::kPause);
  EXPECT_FALSE(r.paused());
  Order other = transport(4);
  other.goals.pop_back();
  EXPECT_EQ(r.accept(other), TaskRunner::OrderChange::kNewTask) << "new goals: a new task";
  EXPECT_EQ(r.goalIndex(), 0u);
  EXPECT_EQ(r.accept(Order{"", 5, {}, false}), TaskRunner::OrderChange::kCancel);
  EXPECT_FALSE(r.busy());
  EXPECT_FALSE(r.hasGoal());
  EXPECT_FALSE(r.takeReport()) << "a cancel is the manager's own";
}

TEST(TaskRunner, AnEmptyPausedOrderHoldsTheIdleRobot) {
  TaskRunner r;
  EXPECT_EQ(r.accept(Order{"", 1, {}, true}), TaskRunner::OrderChange::kCancel);
  EXPECT_TRUE(r.paused()) << "a robot held by the operator while idle";
  EXPECT_FALSE(r.busy());
  EXPECT_EQ(r.tick(0), TaskTick::kNone) << "nothing to start";
  EXPECT_EQ(r.accept(Order{"", 2, {}, false}), TaskRunner::OrderChange::kCancel);
  EXPECT_FALSE(r.paused());
}

TEST(TaskRunner, NoticesNeedATaskAndFailuresKeepAtMost255BytesOfReason) {
  TaskRunner r;
  r.notice("sensor stream lost", 0);
  EXPECT_FALSE(r.takeReport());
  ASSERT_EQ(r.accept(transport()), TaskRunner::OrderChange::kNewTask);
  (void)r.tick(0);
  (void)r.takeReport();
  r.notice("sensor stream lost", kSec);
  auto rep = r.takeReport();
  ASSERT_TRUE(rep);
  EXPECT_EQ(rep->stage, TaskState::EnRoute) << "a notice says the stage the task is in";
  EXPECT_EQ(rep->reason, "sensor stream lost");
  r.finish(TaskState::Failed, std::string(400, 'x'), 2 * kSec);
  rep = r.takeReport();
  ASSERT_TRUE(rep);
  EXPECT_EQ(rep->reason.size(), 255u);
  EXPECT_EQ(rep->progress, 0.0f);
}

TEST(TaskRunner, AnOperatorHoldMovesTheDwellClock) {
  TaskRunner r;
  ASSERT_EQ(r.accept(transport()), TaskRunner::OrderChange::kNewTask);
  (void)r.tick(0);
  r.arrive(10 * kSec);  // dwell 2 s
  r.shiftClock(5 * kSec);
  EXPECT_FALSE(r.dwellOver(16 * kSec));
  EXPECT_EQ(r.tick(16 * kSec), TaskTick::kNone);
  EXPECT_TRUE(r.dwellOver(17 * kSec));
  EXPECT_EQ(r.tick(17 * kSec), TaskTick::kLegBegan);
}

TEST(TaskRunner, AnOrderWithoutGoalsIsRefusedAndReportedFailedAndTheCurrentTaskGoesOn) {
  TaskRunner r;
  ASSERT_EQ(r.accept(transport(1)), TaskRunner::OrderChange::kNewTask);
  (void)r.tick(0);
  (void)r.takeReport();
  Order empty{"t9", 2, {}, true, 5 * kSec, 9};
  EXPECT_EQ(r.accept(empty), TaskRunner::OrderChange::kRefused);
  EXPECT_TRUE(r.busy()) << "another task's order leaves the current one alone";
  EXPECT_EQ(r.task(), "t1");
  EXPECT_EQ(r.revision(), 1u);
  EXPECT_FALSE(r.paused()) << "nothing of the refused order is taken";
  EXPECT_EQ(r.priority(), 0);
  EXPECT_EQ(r.phase(), Phase::Driving);
  auto rep = r.takeReport();
  ASSERT_TRUE(rep);
  EXPECT_EQ(rep->task, "t9");
  EXPECT_EQ(rep->revision, 2u);
  EXPECT_EQ(rep->stage, TaskState::Failed);
  EXPECT_EQ(rep->reason, "refused: assignment has no goals");
  EXPECT_EQ(rep->stampNs, 5 * kSec);
  // The current task's own reports are not lost behind a refusal: both come, the refusal first.
  r.arrive(6 * kSec);
  r.refuse(Order{"t8", 1, {}, false, 6 * kSec}, "bad pose");
  EXPECT_EQ(r.takeReport()->task, "t8");
  rep = r.takeReport();
  ASSERT_TRUE(rep);
  EXPECT_EQ(rep->task, "t1");
  EXPECT_EQ(rep->stage, TaskState::Loading);
  // Its own task refused (at the process's edge, whatever the order holds): dropped and reported.
  r.refuse(transport(3), "bad pose");
  EXPECT_FALSE(r.busy());
  EXPECT_EQ(r.phase(), Phase::Idle);
  rep = r.takeReport();
  ASSERT_TRUE(rep);
  EXPECT_EQ(rep->task, "t1");
  EXPECT_EQ(rep->reason, "refused: bad pose");
  EXPECT_FALSE(r.takeReport());
  // Nothing for an empty task id.
  r.refuse(Order{"", 4, {}, false, 0}, "x");
  EXPECT_FALSE(r.takeReport());
}

TEST(TaskRunner, EveryLegOfAMultiStopOrderIsReportedWithItsStep) {
  TaskRunner r;
  Order o{"m1",
          1,
          {TaskGoal{{5.0, 1.0, 0.0}, "P-1", GoalAction::Load, 1.0, "L-1"},
           TaskGoal{{5.0, 6.0, 0.0}, "D-1", GoalAction::Unload, 1.0, "L-1"},
           TaskGoal{{5.0, 6.0, 0.0}, "D-1", GoalAction::None, 1.0},
           TaskGoal{{1.0, 6.0, 0.0}, "X", GoalAction::None, 0.0}}};
  ASSERT_EQ(r.accept(o), TaskRunner::OrderChange::kNewTask);
  EXPECT_EQ(r.goal().loadId, "L-1");
  std::vector<std::pair<TaskState, std::uint32_t>> seen;
  auto take = [&] {
    while (auto rep = r.takeReport()) {
      seen.emplace_back(rep->stage, rep->step);
    }
  };
  std::int64_t t = 0;
  while (r.busy() && t < 100 * kSec) {
    r.tick(t);
    take();
    if (r.phase() == Phase::Driving) {
      r.arrive(t);  // there at once
      take();
    }
    t += kSec / 2;
  }
  take();
  const std::vector<std::pair<TaskState, std::uint32_t>> expected = {
      {TaskState::EnRoute, 1},   {TaskState::Loading, 1},    {TaskState::Delivering, 2},
      {TaskState::Unloading, 2}, {TaskState::Delivering, 3}, {TaskState::Delivering, 4},
      {TaskState::Done, 4}};
  EXPECT_EQ(seen, expected);
}
